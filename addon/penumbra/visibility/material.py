"""`penumbra.setup_material`: an Attribute node reading `penumbra_shading`,
wired into the object's material so Cycles and Eevee renders show it."""

import bpy

from ..compat import ensure_nodes
from .frame_shading import SHADING_ATTRIBUTE

NODE_NAME = "Penumbra Shading"


def setup_material(obj):
    """Adds (or reuses) a material whose surface emits the baked shading.
    The shading is already lit (it includes the World), so it is shown as
    emission of strength 1: a render then shows exactly penumbra_shading."""
    if obj.type != "MESH":
        raise ValueError(f"'{obj.name}' is not a mesh")
    material = obj.active_material
    if material is None:
        material = bpy.data.materials.new(f"{obj.name} Penumbra")
        obj.data.materials.append(material)
        obj.active_material_index = len(obj.data.materials) - 1
    tree = ensure_nodes(material)
    attribute = tree.nodes.get(NODE_NAME)
    if attribute is None:
        attribute = tree.nodes.new("ShaderNodeAttribute")
        attribute.name = NODE_NAME
        attribute.label = NODE_NAME
        attribute.location = (-500, 300)
    attribute.attribute_type = "GEOMETRY"
    attribute.attribute_name = SHADING_ATTRIBUTE
    emission = tree.nodes.get(NODE_NAME + " Emission")
    if emission is None:
        emission = tree.nodes.new("ShaderNodeEmission")
        emission.name = NODE_NAME + " Emission"
        emission.label = NODE_NAME
        emission.location = (-250, 300)
    emission.inputs["Strength"].default_value = 1.0
    output = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output), None)
    if output is None:
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        output.location = (0, 300)
    tree.links.new(attribute.outputs["Color"], emission.inputs["Color"])
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material
