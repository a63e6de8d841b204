"""The colour map's ramp reader follows links as Blender evaluates them
(node_links.py): the Noise Texture that drives a ramp is found through a
reroute, past a muted link, through a muted node's internal link and inside
a node group, and the bake filters that noise (a decoy noise sits where a
reader that took the Fac's first link would find something else)."""

import bpy
import pytest

from penumbra.colormap import interface, node_groups, ramp as ramp_io

from colormap_scenes import make_ramp_material, plane_with

LIVE_SCALE, DECOY_SCALE = 20.0, 5.0


def _noise(tree, name, scale):
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.name = name
    noise.inputs["Scale"].default_value = scale
    return noise


def _socket(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def _through_reroute(tree, fac):
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(_noise(tree, "live", LIVE_SCALE).outputs["Fac"], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], fac)
    return "live"


def _past_a_muted_link(tree, fac):
    """Only a muted link reaches the Fac: the ramp is driven by nothing."""
    tree.links.new(_noise(tree, "decoy", DECOY_SCALE).outputs["Fac"], fac).is_muted = True
    return None


def _through_a_muted_node(tree, fac):
    """A muted RGBA Mix passes A (its internal link), not Factor or B."""
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    decoy = _noise(tree, "decoy", DECOY_SCALE)
    tree.links.new(decoy.outputs["Fac"], _socket(mix.inputs, "Factor_Float"))
    tree.links.new(decoy.outputs["Color"], _socket(mix.inputs, "B_Color"))
    tree.links.new(_noise(tree, "live", LIVE_SCALE).outputs["Fac"], _socket(mix.inputs, "A_Color"))
    tree.links.new(_socket(mix.outputs, "Result_Color"), fac)
    mix.mute = True
    return "live"


def _inside_a_group(tree, fac):
    """The noise inside a group, its Vector from the material's Object
    coordinates through the Group Input."""
    group = bpy.data.node_groups.new("Bumps", "ShaderNodeTree")
    interface.add_socket(group, "Vector", "INPUT", "NodeSocketVector")
    interface.add_socket(group, "Fac", "OUTPUT", "NodeSocketFloat")
    noise = _noise(group, "live", LIVE_SCALE)
    group.links.new(group.nodes.new("NodeGroupInput").outputs["Vector"], noise.inputs["Vector"])
    group.links.new(noise.outputs["Fac"], group.nodes.new("NodeGroupOutput").inputs["Fac"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.name = "Bumps"
    coords = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coords.outputs["Object"], node.inputs["Vector"])
    tree.links.new(node.outputs["Fac"], fac)
    return "live"


CASES = {"reroute": _through_reroute, "muted link": _past_a_muted_link, "muted node": _through_a_muted_node,
         "node group": _inside_a_group}


def _scene(addon, tmp_path, case):
    settings = addon.penumbra.colormap
    settings.output_folder = str(tmp_path)
    settings.lut_width = settings.lut_height = 16
    material, ramp = make_ramp_material(name=f"linked {case}", noise=False)
    expected = CASES[case](material.node_tree, ramp.inputs["Fac"])
    material.node_tree.nodes.active = ramp
    obj = plane_with(material)
    bpy.ops.object.camera_add(location=(0, -6, 3), rotation=(1.1, 0, 0))
    addon.camera = bpy.context.active_object
    bpy.context.view_layer.objects.active = obj
    return material, ramp, expected


@pytest.mark.parametrize("case", CASES)
def test_the_ramp_reader_finds_the_noise_blender_renders(addon, tmp_path, case):
    material, ramp, expected = _scene(addon, tmp_path, case)
    noise = ramp_io.driving_noise(ramp)
    assert (noise.name if noise else None) == expected
    assert (ramp_io.driving_socket(ramp) == noise.outputs["Fac"]) if noise else ramp_io.driving_socket(ramp) is None
    if case == "node group":
        assert ramp_io.driving(ramp).path == (material.node_tree.nodes["Bumps"],)


# A noise bake takes seconds: the two cases that change what the bake links
# (nothing at all; a noise whose coordinates come from outside its group).
@pytest.mark.parametrize("case", ["muted link", "node group"])
def test_the_bake_filters_the_noise_blender_renders(addon, tmp_path, case):
    material, ramp, expected = _scene(addon, tmp_path, case)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    group_node = tree.nodes[node_groups.FILTERED_RAMP]
    noise_filter = next((n for n in tree.nodes if n.name.startswith("Penumbra Noise Filter")), None)
    if expected is None:  # a plain ramp: its own Fac value is the mean
        assert noise_filter is None and not group_node.inputs["Mean"].is_linked
        assert group_node.inputs["Mean"].default_value == pytest.approx(ramp.inputs["Fac"].default_value)
        return
    assert noise_filter is not None and noise_filter.inputs["Scale"].default_value == pytest.approx(LIVE_SCALE)
    vector = noise_filter.inputs["Vector"].links[0].from_socket
    assert vector.node.bl_idname == "ShaderNodeTexCoord" and vector.identifier == "Object"  # from outside


def test_a_plain_ramp_driven_from_inside_a_group_is_linked_from_the_group_node(addon, tmp_path):
    """What drives the Fac is inside a group; the filter, beside the ramp,
    takes the group node's output, which carries the same value."""
    material, ramp = make_ramp_material(name="grouped value", noise=False)
    tree = material.node_tree
    group = bpy.data.node_groups.new("Level", "ShaderNodeTree")
    interface.add_socket(group, "Fac", "OUTPUT", "NodeSocketFloat")
    inner = group.nodes.new("ShaderNodeValue")
    group.links.new(inner.outputs[0], group.nodes.new("NodeGroupOutput").inputs["Fac"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    tree.links.new(node.outputs["Fac"], ramp.inputs["Fac"])
    assert ramp_io.driving_socket(ramp) == inner.outputs[0]
    assert ramp_io.fac_source_in_tree(ramp) == node.outputs["Fac"]
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    tree.nodes.active = ramp
    bpy.context.view_layer.objects.active = plane_with(material)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    mean = tree.nodes[node_groups.FILTERED_RAMP].inputs["Mean"]
    assert mean.links[0].from_socket == node.outputs["Fac"]
