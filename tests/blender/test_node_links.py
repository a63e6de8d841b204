"""penumbra.node_links, the one node-graph walker, inside real Blender: what
drives an input through live and muted links, reroutes, muted nodes (the
internal links Blender makes), node groups in and out, invalid and
unavailable links, each against what Blender itself reports for the tree
(its internal links, its link flags) and what Cycles' add_nodes keeps."""

import bpy
import pytest

from penumbra import compat, node_links
from penumbra.colormap import interface


def _tree():
    material = bpy.data.materials.new("walked")
    return compat.ensure_nodes(material)


def _value(tree, value, name):
    node = tree.nodes.new("ShaderNodeValue")
    node.outputs[0].default_value = value
    node.name = name
    return node


def _by_identifier(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def _ramp(tree):
    return tree.nodes.new("ShaderNodeValToRGB")


def test_a_live_link_is_followed_and_a_muted_one_is_not(factory_scene):
    tree = _tree()
    ramp, source = _ramp(tree), _value(tree, 0.3, "Source")
    link = tree.links.new(source.outputs[0], ramp.inputs["Fac"])
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node == source and fed.output == source.outputs[0] and fed.path == ()
    link.is_muted = True
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node is None and fed.socket == ramp.inputs["Fac"]
    assert node_links.driver(ramp.inputs["Fac"]) is None


def test_reroutes_are_passed_and_an_empty_one_leaves_the_input_its_own_value(factory_scene):
    tree = _tree()
    ramp, source = _ramp(tree), _value(tree, 0.3, "Source")
    first, second = tree.nodes.new("NodeReroute"), tree.nodes.new("NodeReroute")
    tree.links.new(second.outputs[0], ramp.inputs["Fac"])
    tree.links.new(first.outputs[0], second.inputs[0])
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node is None and fed.socket == ramp.inputs["Fac"]  # Blender drops the links through it
    behind = tree.links.new(source.outputs[0], first.inputs[0])
    assert node_links.driver(ramp.inputs["Fac"]) == source.outputs[0]
    behind.is_muted = True  # a muted link before a reroute cuts the whole chain
    assert node_links.driver(ramp.inputs["Fac"]) is None


def test_a_muted_node_passes_the_input_of_its_internal_link(factory_scene):
    """A muted RGBA Mix passes A (Color), not its first input Factor: the
    internal link Blender makes (first input of the output's type)."""
    tree = _tree()
    bsdf = tree.nodes["Principled BSDF"]
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    colours = {name: tree.nodes.new("ShaderNodeRGB") for name in ("A", "B")}
    factor = _value(tree, 0.5, "Factor")
    tree.links.new(factor.outputs[0], _by_identifier(mix.inputs, "Factor_Float"))
    tree.links.new(colours["A"].outputs[0], _by_identifier(mix.inputs, "A_Color"))
    tree.links.new(colours["B"].outputs[0], _by_identifier(mix.inputs, "B_Color"))
    tree.links.new(_by_identifier(mix.outputs, "Result_Color"), bsdf.inputs["Base Color"])
    assert node_links.feed(bsdf.inputs["Base Color"]).node == mix
    mix.mute = True
    internal = {(l.from_socket.identifier, l.to_socket.identifier) for l in mix.internal_links}
    assert internal == {("A_Color", "Result_Color")}  # Blender's own choice, which the walker follows
    fed = node_links.feed(bsdf.inputs["Base Color"])
    assert fed.node == colours["A"] and fed.socket == _by_identifier(mix.inputs, "A_Color")


def test_a_muted_node_without_an_internal_link_drives_nothing(factory_scene):
    tree = _tree()
    ramp, source = _ramp(tree), _value(tree, 0.3, "Source")
    tree.links.new(source.outputs[0], ramp.inputs["Fac"])
    source.mute = True
    assert not list(source.internal_links)
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node is None and fed.socket == ramp.inputs["Fac"]


def test_invalid_and_unavailable_links_are_ignored_as_cycles_does(factory_scene):
    tree = _tree()
    ramp = _ramp(tree)
    bsdf = tree.nodes["Principled BSDF"]
    link = tree.links.new(bsdf.outputs[0], ramp.inputs["Fac"])  # a shader into a float: invalid
    assert not link.is_valid
    assert node_links.driver(ramp.inputs["Fac"]) is None
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.noise_dimensions = "3D"
    w = _by_identifier(noise.inputs, "W")
    link = tree.links.new(_value(tree, 2.0, "W source").outputs[0], w)
    assert not w.enabled  # W is unavailable to 3D noise (3.4 still calls the link valid)
    assert node_links.driver(w) is None


def _group(name, outputs=1):
    """A shader node group with a float input "In" and output "Out", and
    `outputs` Group Output nodes."""
    group = bpy.data.node_groups.new(name, "ShaderNodeTree")
    interface.add_socket(group, "In", "INPUT", "NodeSocketFloat")
    interface.add_socket(group, "Out", "OUTPUT", "NodeSocketFloat")
    group_in = group.nodes.new("NodeGroupInput")
    group_outs = [group.nodes.new("NodeGroupOutput") for _ in range(outputs)]
    return group, group_in, group_outs


def test_a_group_is_entered_at_its_active_output_and_left_at_its_group_input(factory_scene):
    tree = _tree()
    ramp = _ramp(tree)
    group, group_in, (first_out, second_out) = _group("walked group", outputs=2)
    inner = _value(group, 0.7, "Inner")
    group.links.new(inner.outputs[0], first_out.inputs["Out"])
    group.links.new(group_in.outputs["In"], second_out.inputs["Out"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    tree.links.new(node.outputs["Out"], ramp.inputs["Fac"])
    outer = _value(tree, 0.2, "Outer")
    tree.links.new(outer.outputs[0], node.inputs["In"])
    first_out.is_active_output = True
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node == inner and fed.path == (node,) and fed.output.id_data == group
    second_out.is_active_output = True
    assert not first_out.is_active_output
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node == outer and fed.path == () and fed.socket == node.inputs["In"]
    # The group node's own input value counts when nothing drives it.
    tree.links.remove(node.inputs["In"].links[0])
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node is None and fed.socket == node.inputs["In"]
    # Without a group node to leave to, a Group Input drives nothing.
    assert node_links.feed(second_out.inputs["Out"]).node is None


def test_nested_groups_record_their_path_outermost_first(factory_scene):
    tree = _tree()
    ramp = _ramp(tree)
    inner_group, _, (inner_out,) = _group("inner")
    deepest = _value(inner_group, 0.9, "Deepest")
    inner_group.links.new(deepest.outputs[0], inner_out.inputs["Out"])
    outer_group, _, (outer_out,) = _group("outer")
    nested = outer_group.nodes.new("ShaderNodeGroup")
    nested.node_tree = inner_group
    outer_group.links.new(nested.outputs["Out"], outer_out.inputs["Out"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = outer_group
    tree.links.new(node.outputs["Out"], ramp.inputs["Fac"])
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node == deepest and fed.path == (node, nested)
    # Muted, a group passes its input through as any muted node; with nothing
    # behind that input Blender drops the link, so the Group Output keeps its value.
    nested.mute = True
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node is None and fed.socket == outer_out.inputs["Out"] and fed.path == (node,)
    beside = _value(outer_group, 0.4, "Beside")
    outer_group.links.new(beside.outputs[0], nested.inputs["In"])
    fed = node_links.feed(ramp.inputs["Fac"])
    assert fed.node == beside and fed.path == (node,)


def test_a_walk_that_does_not_end_is_refused(factory_scene, monkeypatch):
    """A group nested in itself cannot be built in Blender; a reroute chain
    longer than the step limit stands in for one."""
    tree = _tree()
    ramp = _ramp(tree)
    monkeypatch.setattr(node_links, "MAX_STEPS", 3)
    socket = ramp.inputs["Fac"]
    for _ in range(4):
        reroute = tree.nodes.new("NodeReroute")
        tree.links.new(reroute.outputs[0], socket)
        socket = reroute.inputs[0]
    tree.links.new(_value(tree, 1.0, "Far").outputs[0], socket)
    with pytest.raises(node_links.NodeTreeCycle, match="loop"):
        node_links.feed(ramp.inputs["Fac"])


def test_the_source_in_the_inputs_own_tree_stands_for_the_driver(factory_scene):
    """What a link in the input's place takes: the driver itself when it is
    in the same tree (past reroutes), the group node's output when it is
    inside a group, nothing behind a muted link."""
    tree = _tree()
    ramp, source = _ramp(tree), _value(tree, 0.3, "Source")
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(source.outputs[0], reroute.inputs[0])
    link = tree.links.new(reroute.outputs[0], ramp.inputs["Fac"])
    assert node_links.source_in_tree(ramp.inputs["Fac"]) == source.outputs[0]
    link.is_muted = True
    assert node_links.source_in_tree(ramp.inputs["Fac"]) is None
    group, _, (group_out,) = _group("source group")
    group.links.new(_value(group, 0.7, "Inner").outputs[0], group_out.inputs["Out"])
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    tree.links.new(node.outputs["Out"], ramp.inputs["Fac"])
    assert node_links.source_in_tree(ramp.inputs["Fac"]) == node.outputs["Out"]
