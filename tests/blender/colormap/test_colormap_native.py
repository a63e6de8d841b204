"""The band-limited Noise Filter (preset NATIVE, native_filter.py): one
Blender Noise Texture with its Detail linked to the sample's resolution.
Resolved (Pixel Size 0) its Mean is the user's noise itself, sample for
sample; averaged away (a huge Pixel Size) it is the noise's mean; a noise
it cannot rebuild falls back to the one-evaluation filter; preset NATIVE
keeps the 16 taps for one sample, NATIVE_ONLY does not."""

import bpy
import numpy as np

from penumbra.colormap import filter_quality, node_groups, sample_count

from test_colormap_noise import _render, _render_scene


def _node(material, prefix):
    return next(n for n in material.node_tree.nodes if n.name.startswith(prefix))


def _bake(scene, tmp_path, detail=4.0, quality="NATIVE_ONLY"):
    scene.penumbra.colormap.output_folder = str(tmp_path)
    scene.penumbra.colormap.filter_quality = quality
    material, ramp, emission, _camera = _render_scene(scene, 70.0, filter_box=True)
    noise = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    noise.inputs["Detail"].default_value = detail
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    return material, noise, emission, _node(material, "Penumbra Noise Filter")


def test_resolved_mean_is_the_noise_and_unresolved_is_its_mean(addon, tmp_path):
    material, noise, emission, filter_node = _bake(addon, tmp_path)
    group = filter_node.node_tree
    assert filter_quality.baked_quality(filter_node) == "NATIVE_ONLY" and group["penumbra_native"]
    natives = [n for n in group.nodes if n.bl_idname == "ShaderNodeTexNoise"]
    assert len(natives) == 1 and natives[0].inputs["Detail"].is_linked
    assert group["penumbra_taps"] == 16 and not any(n.bl_idname == "ShaderNodeTexImage" for n in group.nodes)
    # One group at every sample count: no taps to swap in at one sample.
    assert sample_count.remembered_group(filter_node, sample_count.GROUP_AT_ONE_SAMPLE) is None
    links = material.node_tree.links
    links.new(noise.outputs["Fac"], emission.inputs["Color"])
    plain = _render(addon, str(tmp_path / "plain.exr"), 1, 0)
    ground = plain.sum(axis=2) > 0
    links.new(filter_node.outputs["Mean"], emission.inputs["Color"])
    footprint = _node(material, node_groups.POINT_FOOTPRINT)
    footprint.inputs["Pixel Size"].default_value = 0.0
    resolved = _render(addon, str(tmp_path / "resolved.exr"), 1, 0)
    assert np.abs(resolved - plain)[ground].max() < 2e-3
    footprint.inputs["Pixel Size"].default_value = 1e4
    blurred = _render(addon, str(tmp_path / "blurred.exr"), 1, 0)
    assert plain[ground].std() > 0.05
    assert np.abs(blurred[ground] - 0.5).max() < 0.01


def test_noise_it_cannot_rebuild_falls_back_to_one_evaluation(addon, tmp_path):
    _material, _noise, _emission, filter_node = _bake(addon, tmp_path, detail=0.5)
    above = sample_count.remembered_group(filter_node, sample_count.GROUP_ABOVE_ONE_SAMPLE)
    assert not above["penumbra_native"] and above["penumbra_point"]
    assert sum(n.bl_idname == "ShaderNodeTexNoise" for n in above.nodes) == 2


def test_one_noise_keeps_the_taps_for_one_sample(addon, tmp_path):
    _material, _noise, _emission, filter_node = _bake(addon, tmp_path, quality="NATIVE")
    one = sample_count.remembered_group(filter_node, sample_count.GROUP_AT_ONE_SAMPLE)
    above = sample_count.remembered_group(filter_node, sample_count.GROUP_ABOVE_ONE_SAMPLE)
    assert one["penumbra_native"] and sum(n.bl_idname == "ShaderNodeTexNoise" for n in one.nodes) > 16
    assert above["penumbra_native"] and sum(n.bl_idname == "ShaderNodeTexNoise" for n in above.nodes) == 1
