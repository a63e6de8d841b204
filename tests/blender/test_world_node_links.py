"""The World reader follows links as Blender evaluates them (node_links.py):
in each World a decoy Environment Texture sits where a reader that took a
node's first link would find it, and the live one is reached through a
reroute, past a muted link, through a muted node's internal link, or at a
node group's active output."""

import bpy
import pytest

from penumbra import compat, world
from penumbra.colormap import interface


def _new_world(scene):
    w = bpy.data.worlds.new("Linked World")
    scene.world = w
    return compat.ensure_nodes(w)


def _environment(tree, name):
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.get(name) or bpy.data.images.new(name, 4, 2, float_buffer=True)
    env.name = name
    return env


def _socket(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def _through_reroute(tree, colour):
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(_environment(tree, "live").outputs["Color"], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], colour)
    return "live"


def _past_a_muted_link(tree, colour):
    """Only a muted link reaches the Background: its own colour lights the
    World, and the decoy is named as not connected."""
    tree.links.new(_environment(tree, "decoy").outputs["Color"], colour).is_muted = True
    return None


def _through_a_muted_node(tree, colour):
    """A muted RGBA Mix passes A (its internal link), not Factor or B."""
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    decoy = _environment(tree, "decoy")
    tree.links.new(decoy.outputs["Color"], _socket(mix.inputs, "Factor_Float"))
    tree.links.new(decoy.outputs["Color"], _socket(mix.inputs, "B_Color"))
    tree.links.new(_environment(tree, "live").outputs["Color"], _socket(mix.inputs, "A_Color"))
    tree.links.new(_socket(mix.outputs, "Result_Color"), colour)
    mix.mute = True
    return "live"


def _at_the_active_group_output(tree, colour):
    """Two Group Outputs: the decoy's is the first, the live one's is active."""
    group = bpy.data.node_groups.new("Sky Group", "ShaderNodeTree")
    interface.add_socket(group, "Color", "OUTPUT", "NodeSocketColor")
    decoy_out, live_out = group.nodes.new("NodeGroupOutput"), group.nodes.new("NodeGroupOutput")
    group.links.new(_environment(group, "decoy").outputs["Color"], decoy_out.inputs["Color"])
    group.links.new(_environment(group, "live").outputs["Color"], live_out.inputs["Color"])
    live_out.is_active_output = True
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    tree.links.new(node.outputs["Color"], colour)
    return "live"


CASES = {"reroute": _through_reroute, "muted link": _past_a_muted_link, "muted node": _through_a_muted_node,
         "node group": _at_the_active_group_output}


@pytest.mark.parametrize("case", CASES)
def test_the_world_reader_finds_the_environment_blender_renders(addon, case):
    tree = _new_world(addon)
    background = tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.2, 0.3, 0.4, 1.0)
    expected = CASES[case](tree, background.inputs["Color"])
    reading = world.read_scene(addon)
    if expected is None:
        assert reading.kind == "uniform" and tuple(reading.colour) == pytest.approx((0.2, 0.3, 0.4))
        assert "'decoy' (image 'decoy') is not connected" in reading.note
    else:
        assert reading.kind == "environment" and reading.image.name == expected, reading.note
        assert reading.supported, reading.note
