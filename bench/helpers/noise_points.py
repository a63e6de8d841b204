"""Blender's own Noise Texture evaluated at given points through geometry
nodes (the noise code Cycles runs): what the colour map's noise statistics
are measured on (scripts/colormap_measure_noise.py) and tested against
(tests/blender/colormap/test_colormap_noise.py). Inside Blender, with the
add-on importable."""

import bpy
import numpy as np

from penumbra.colormap import interface


def noise_evaluator():
    """Adds an object whose geometry-nodes modifier stores the Noise Texture's
    Fac at each vertex position. Returns (the Noise Texture node: set its
    inputs to choose the noise, evaluate(points (N, 3)) -> Fac (N,) float64)."""
    mesh = bpy.data.meshes.new("noise_points")
    obj = bpy.data.objects.new("noise_points", mesh)
    bpy.context.scene.collection.objects.link(obj)
    group = bpy.data.node_groups.new("noise at points", "GeometryNodeTree")
    interface.add_socket(group, "Geometry", "INPUT", "NodeSocketGeometry")
    interface.add_socket(group, "Geometry", "OUTPUT", "NodeSocketGeometry")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    noise = group.nodes.new("ShaderNodeTexNoise")
    store = group.nodes.new("GeometryNodeStoreNamedAttribute")
    store.data_type, store.domain = "FLOAT", "POINT"
    store.inputs["Name"].default_value = "noise"
    group.links.new(group.nodes.new("GeometryNodeInputPosition").outputs[0], noise.inputs["Vector"])
    group.links.new(gin.outputs[0], store.inputs["Geometry"])
    value = [s for s in store.inputs if s.name == "Value" and s.type == "VALUE"]  # 3.4 has one per data type
    group.links.new(noise.outputs["Fac"], value[0] if value else store.inputs["Value"])
    group.links.new(store.outputs[0], gout.inputs[0])
    obj.modifiers.new("noise", "NODES").node_group = group

    def evaluate(points):
        mesh.clear_geometry()
        mesh.vertices.add(len(points))
        mesh.vertices.foreach_set("co", np.asarray(points, np.float32).ravel())
        mesh.update()
        data = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.attributes["noise"].data
        out = np.empty(len(data), np.float32)
        data.foreach_get("value", out)
        return out.astype(np.float64)
    return noise, evaluate
