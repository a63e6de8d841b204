"""The Noise Filter's quality presets (issue #25): what 1 Eval bakes
(the one-evaluation filter above one sample, the 16 taps at one; the
default 1 Noise: test_colormap_native.py), the groups
the render swaps by sample count, and the preset saved with the .blend."""

import bpy

from penumbra.colormap import filter_quality, interface, node_groups, sample_count

from test_colormap_noise import _render, _render_scene


def _node(material, prefix):
    return next(n for n in material.node_tree.nodes if n.name.startswith(prefix))


def test_one_eval_preset_bakes_one_evaluation_above_one_sample(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    assert addon.penumbra.colormap.filter_quality == filter_quality.DEFAULT == "NATIVE"
    addon.penumbra.colormap.filter_quality = "POINT"
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    addon.render.resolution_x, addon.render.resolution_y = 8, 6
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    ramp_node = _node(material, node_groups.FILTERED_RAMP)
    filter_node = _node(material, "Penumbra Noise Filter")
    assert filter_quality.baked_quality(filter_node) == "POINT"
    point = _node(material, node_groups.POINT_FOOTPRINT)
    for name in ("Minor", "Major"):
        assert filter_node.inputs["Point " + name].links[0].from_socket == point.outputs[name]
    assert ramp_node.inputs["Mixture"].links[0].from_socket == filter_node.outputs["Mixture"]
    one = sample_count.remembered_group(filter_node, sample_count.GROUP_AT_ONE_SAMPLE)
    many = sample_count.remembered_group(filter_node, sample_count.GROUP_ABOVE_ONE_SAMPLE)
    assert one["penumbra_taps"] == 16 and one["penumbra_point"]
    # Above one sample: the octaves once each, no taps, no octave table.
    assert sum(n.bl_idname == "ShaderNodeTexNoise" for n in many.nodes) == 5
    assert not any(n.bl_idname == "ShaderNodeTexImage" for n in many.nodes)
    links = sorted((l.from_socket.name, l.to_socket.name) for l in material.node_tree.links
                   if filter_node in (l.from_node, l.to_node))
    for samples, group in ((1, one), (4, many), (1, one)):
        _render(addon, str(tmp_path / f"s{samples}.exr"), samples, 0)     # render_init picks the group
        assert filter_node.node_tree == group
        at_one = sample_count.remembered_group(ramp_node, sample_count.GROUP_AT_ONE_SAMPLE)
        assert (ramp_node.node_tree == at_one) == (samples == 1)
    assert sorted((l.from_socket.name, l.to_socket.name) for l in material.node_tree.links
                  if filter_node in (l.from_node, l.to_node)) == links
    assert interface.socket_names(ramp_node.node_tree, "INPUT") == ["Mean", "Sigma", "Offsets", "Variances",
                                                                    "Mixture"]


def test_preset_is_saved_with_the_file_and_a_change_waits_for_a_bake(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.filter_quality = "POINT_COARSE"
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    addon.penumbra.colormap.filter_quality = "TAPS_4"     # changed after the bake: nothing re-bakes
    name = material.name
    path = str(tmp_path / "saved.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert scene.penumbra.colormap.filter_quality == "TAPS_4"
    material = bpy.data.materials[name]
    filter_node = _node(material, "Penumbra Noise Filter")
    assert filter_quality.baked_quality(filter_node) == "POINT_COARSE"
    # Both groups came back with the file, the one not in use too.
    for key in (sample_count.GROUP_AT_ONE_SAMPLE, sample_count.GROUP_ABOVE_ONE_SAMPLE):
        assert sample_count.remembered_group(filter_node, key) is not None
    assert sample_count.remembered_group(filter_node, sample_count.GROUP_ABOVE_ONE_SAMPLE)[
        "penumbra_analytic_octaves"] == 1
    # A filter baked before the presets has no property: the 16-tap mixture.
    del filter_node[filter_quality.NODE_PROPERTY]
    assert filter_quality.baked_quality(filter_node) == filter_quality.LEGACY
