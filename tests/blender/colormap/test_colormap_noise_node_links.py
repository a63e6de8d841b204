"""The noise-model reader (noise_model.read_noise) reads the inputs of the
Noise Texture that drives a ramp as Blender evaluates them (node_links.py):
through a reroute, past a muted link, through a muted node and across a
node group's boundary. Each scene says by construction which socket drives
Scale and which value Detail has; a reader that took an input's first live
link would see a reroute, a muted node or a Group Input instead."""

import bpy
import pytest

from penumbra import compat
from penumbra.colormap import interface, noise_maths, noise_model, ramp as ramp_io

OWN_DETAIL, ROUGHNESS = 3.0, 0.5


def _material():
    """A ramp whose Fac is driven by a 3D Noise Texture (Detail 3)."""
    tree = compat.ensure_nodes(bpy.data.materials.new("noisy"))
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.name = "Bumps"
    noise.inputs["Detail"].default_value = OWN_DETAIL
    noise.inputs["Roughness"].default_value = ROUGHNESS
    tree.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    return tree, ramp, noise


def _value(tree, value):
    node = tree.nodes.new("ShaderNodeValue")
    node.outputs[0].default_value = value
    return node


def _model(ramp):
    fed = ramp_io.driving(ramp)
    return noise_model.read_noise(fed.node, fed.output, fed.path)


def _weights(detail):
    return pytest.approx(noise_maths.octave_weights(detail, ROUGHNESS, bpy.app.version))


def test_a_scale_through_a_reroute_comes_from_the_node_behind_it(addon):
    tree, ramp, noise = _material()
    value, reroute = _value(tree, 2.1), tree.nodes.new("NodeReroute")
    tree.links.new(value.outputs[0], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], noise.inputs["Scale"])
    model = _model(ramp)
    assert model.scale is None and model.scale_from == value.outputs[0]


def test_inputs_behind_muted_links_keep_their_own_values(addon):
    """Detail ← reroute ⇠ (muted) Value: nothing drives the Detail, so the
    noise is derivable at its own Detail; Scale ⇠ (muted) Value: its own."""
    tree, ramp, noise = _material()
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(_value(tree, 6.0).outputs[0], reroute.inputs[0]).is_muted = True
    tree.links.new(reroute.outputs[0], noise.inputs["Detail"])
    noise.inputs["Scale"].default_value = 4.0
    tree.links.new(_value(tree, 2.1).outputs[0], noise.inputs["Scale"]).is_muted = True
    model = _model(ramp)
    assert model.coefficients == _weights(OWN_DETAIL)
    assert model.scale == pytest.approx(4.0) and model.scale_from is None


def test_a_muted_node_passes_its_first_input_or_leaves_the_inputs_own_value(addon):
    """Scale ← muted Math ← (Value 2.1, Value 9): Blender passes the first
    Value; Detail ← a muted Value node, which has no internal link: the
    Detail's own value."""
    tree, ramp, noise = _material()
    first, second, add = _value(tree, 2.1), _value(tree, 9.0), tree.nodes.new("ShaderNodeMath")
    tree.links.new(first.outputs[0], add.inputs[0])
    tree.links.new(second.outputs[0], add.inputs[1])
    tree.links.new(add.outputs[0], noise.inputs["Scale"])
    muted_value = _value(tree, 6.0)
    tree.links.new(muted_value.outputs[0], noise.inputs["Detail"])
    add.mute = muted_value.mute = True
    model = _model(ramp)
    assert model.scale_from == first.outputs[0]
    assert model.coefficients == _weights(OWN_DETAIL)


def _grouped_noise(tree, ramp):
    """The noise inside a group: Vector, Scale and Detail from the Group
    Input; outside, Object coordinates, a Value 2.1 and an unlinked Detail 1.5."""
    group = bpy.data.node_groups.new("Bumps Group", "ShaderNodeTree")
    for name, kind in (("Vector", "NodeSocketVector"), ("Scale", "NodeSocketFloat"), ("Detail", "NodeSocketFloat")):
        interface.add_socket(group, name, "INPUT", kind)
    interface.add_socket(group, "Fac", "OUTPUT", "NodeSocketFloat")
    noise = group.nodes.new("ShaderNodeTexNoise")
    noise.name = "Bumps"
    noise.inputs["Roughness"].default_value = ROUGHNESS
    group_in = group.nodes.new("NodeGroupInput")
    for name in ("Vector", "Scale", "Detail"):
        group.links.new(group_in.outputs[name], noise.inputs[name])
    group.links.new(noise.outputs["Fac"], group.nodes.new("NodeGroupOutput").inputs["Fac"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.inputs["Detail"].default_value = 1.5
    coords, scale = tree.nodes.new("ShaderNodeTexCoord"), _value(tree, 2.1)
    tree.links.new(coords.outputs["Object"], node.inputs["Vector"])
    tree.links.new(scale.outputs[0], node.inputs["Scale"])
    tree.links.new(node.outputs["Fac"], ramp.inputs["Fac"])
    return group, node, noise, coords, scale


def test_a_noise_inside_a_group_reads_its_inputs_from_the_group_node(addon):
    tree, ramp, decoy = _material()
    decoy.name = "decoy"
    group, node, noise, coords, scale = _grouped_noise(tree, ramp)
    model = _model(ramp)
    assert model.node_name == "Bumps" and ramp_io.driving(ramp).path == (node,)
    assert model.vector_from == coords.outputs["Object"] and model.scale_from == scale.outputs[0]
    assert model.coefficients == _weights(1.5)  # the group node's Detail, not the inner socket's
    # A Scale from a node inside the group cannot be linked beside the ramp: refused by name.
    group.links.new(_value(group, 2.1).outputs[0], noise.inputs["Scale"])
    with pytest.raises(noise_model.NoiseNotDerivable, match="'Bumps'.*Scale.*inside the node group"):
        _model(ramp)
