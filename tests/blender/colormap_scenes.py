"""Scenes shared by the colour-map tests: a ramp material on a plane."""

import bpy

from penumbra import compat


def make_ramp_material(name="ramped", noise=True):
    material = bpy.data.materials.new(name)
    tree = compat.ensure_nodes(material)
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    elements = ramp.color_ramp.elements
    elements[0].color = (0.9, 0.1, 0.05, 1.0)
    elements[1].color = (0.05, 0.2, 0.9, 1.0)
    elements[0].position = 0.45
    elements[1].position = 0.55
    bsdf = tree.nodes["Principled BSDF"]
    tree.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    if noise:
        tex = tree.nodes.new("ShaderNodeTexNoise")
        tex.inputs["Scale"].default_value = 20.0
        tree.links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    tree.nodes.active = ramp
    return material, ramp


def plane_with(material):
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    obj = bpy.context.active_object
    obj.data.materials.append(material)
    return obj
