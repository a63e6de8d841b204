"""The colour-map tool's test scene, for copying: an emissive plane receding to
the horizon, its colour a two-stop ColorRamp driven by a Noise Texture in
Object coordinates, seen by a camera just above it. Far away, the noise is
much finer than a pixel, which is where a plain ramp sparkles.

Used by examples/demo_colormap.py, bench/colormap_render.py and the Blender
tests, so all three look at the same thing."""

import math

import bpy


def noise_ramp_plane(plane_size=400.0, plane_location=(0.0, 190.0, 0.0),
                     camera_location=(0.0, -2.0, 1.2), camera_rotation_degrees=(84.0, 0.0, 0.0),
                     detail=4.0, roughness=None):
    """Adds the plane, its material and a camera to the current scene (made
    the scene camera; the plane is left active). Returns
    (plane, material, ramp node, emission node, camera)."""
    bpy.ops.mesh.primitive_plane_add(size=plane_size, location=plane_location)
    plane = bpy.context.active_object
    material = bpy.data.materials.new("noise ramp")
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    coords = tree.nodes.new("ShaderNodeTexCoord")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 2.0
    noise.inputs["Detail"].default_value = detail
    if roughness is not None:
        noise.inputs["Roughness"].default_value = roughness
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    e = ramp.color_ramp.elements
    e[0].position, e[0].color = 0.47, (0.8, 0.05, 0.02, 1.0)
    e[1].position, e[1].color = 0.53, (0.02, 0.3, 0.9, 1.0)
    tree.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    tree.nodes.active = ramp
    plane.data.materials.append(material)
    bpy.ops.object.camera_add(location=camera_location,
                              rotation=tuple(math.radians(a) for a in camera_rotation_degrees))
    camera = bpy.context.active_object
    bpy.context.scene.camera = camera
    bpy.context.view_layer.objects.active = plane
    return plane, material, ramp, emission, camera
