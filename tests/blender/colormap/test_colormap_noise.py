"""Filtering a noise-driven ramp in real Blender: the octave weights against
Blender's own Noise Texture, the footprint node against the projected pixel,
and a filtered Cycles render against a high-sample reference."""

import os
import sys
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from penumbra import native

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))), "examples", "scenes"))
import colormap_scene  # noqa: E402  (the scene users can copy, examples/scenes/colormap_scene.py)
from penumbra.colormap import node_groups

from bench.helpers.noise_points import noise_evaluator  # noqa: E402


@pytest.mark.parametrize("detail, roughness", [(4.0, 0.5), (2.6, 0.8), (0.3, 0.5), (6.0, 1.0)])
def test_octave_weights_rebuild_blenders_noise(addon, detail, roughness):
    """The octave filter rebuilds the noise as Σ w_i · Noise(Detail 0,
    Scale·2^i): checked against Blender's own multi-octave Noise Texture."""
    from penumbra.colormap import noise_maths
    noise, evaluate = noise_evaluator()
    points = np.random.default_rng(3).uniform(-40, 40, (500, 3))
    noise.inputs["Scale"].default_value = 1.7
    noise.inputs["Detail"].default_value = detail
    noise.inputs["Roughness"].default_value = roughness
    full = evaluate(points)
    weights = noise_maths.octave_weights(detail, roughness, bpy.app.version)
    assert len(weights) == int(np.floor(detail)) + 1 + (1 if detail % 1 else 0)
    noise.inputs["Detail"].default_value = 0.0
    rebuilt = np.zeros_like(full)
    for i, w in enumerate(weights):
        noise.inputs["Scale"].default_value = 1.7 * 2.0 ** i
        rebuilt += w * evaluate(points)
    assert np.std(full) > 0.03
    np.testing.assert_allclose(rebuilt, full, atol=1e-5)


RENDER_W, RENDER_H = 48, 32


def _render_scene(scene, pitch_deg, filter_box=False):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x, scene.render.resolution_y = RENDER_W, RENDER_H
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    if filter_box:  # shade each pixel at its centre
        scene.cycles.pixel_filter_type = "BOX"
        scene.cycles.filter_width = 0.01
    plane, material, ramp, emission, camera = colormap_scene.noise_ramp_plane(
        plane_size=600.0, plane_location=(0, 250, 0), camera_location=(0.2, -2, 1.2),
        camera_rotation_degrees=(pitch_deg, 0, 5))
    return material, ramp, emission, camera


def _render(scene, path, spp, seed):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return native.require().image.read(path)[..., :3].astype(np.float64)


def _baked_plane_and_error(scene, tmp_path, pitch_deg, baked_samples=None, reference_spp=1024):
    """The receding plane baked with Penumbra and its plain ramp rendered at
    reference_spp: the material, the filtered group, the emission node, the
    reference, the ground (the plane; the sky is black) and rmse(image)
    against the reference over the ground. The plain ramp stays linked; link
    the group's Color to the emission to render the filter."""
    scene.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, _camera = _render_scene(scene, pitch_deg)
    if baked_samples is not None:
        scene.cycles.samples = baked_samples
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    group = material.node_tree.nodes[node_groups.FILTERED_RAMP]
    ramp.mute = False
    material.node_tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    reference = _render(scene, str(tmp_path / "reference.exr"), reference_spp, 7)
    ground = reference.sum(axis=2) > 0

    def rmse(image):
        return float(np.sqrt(((image - reference)[ground] ** 2).mean()))
    return SimpleNamespace(material=material, group=group, emission=emission, reference=reference,
                           ground=ground, rmse=rmse)


def test_footprint_node_matches_the_projected_pixel(addon, tmp_path):
    """The footprint group rendered at pixel centres against the footprint
    computed here from the camera: the pixel's edge midpoints projected onto
    the plane z = 0 (finite-difference Jacobian: √|det| and singular values)."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    material, ramp, emission, camera = _render_scene(addon, 72.0, filter_box=True)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    footprint = tree.nodes[node_groups.FOOTPRINT]
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    for i, name in enumerate(("Footprint", "Minor", "Major")):
        tree.links.new(footprint.outputs[name], combine.inputs[i])
    tree.links.new(combine.outputs[0], emission.inputs["Color"])
    image = _render(addon, str(tmp_path / "footprint.exr"), 1, 0)
    frame = [camera.matrix_world @ v for v in camera.data.view_frame(scene=addon)]
    top_right, _, bottom_left, top_left = frame
    origin = camera.matrix_world.translation

    def on_plane(x, y):
        point = top_left + (top_right - top_left) * (x / RENDER_W) + (bottom_left - top_left) * (y / RENDER_H)
        d = point - origin
        return np.array(origin - d * (origin.z / d.z))[:2]

    checked = 0
    for y in range(2, RENDER_H, 5):
        for x in (3, RENDER_W // 2, RENDER_W - 4):
            ju = on_plane(x + 1.0, y + 0.5) - on_plane(x, y + 0.5)
            jv = on_plane(x + 0.5, y + 1.0) - on_plane(x + 0.5, y)
            major, minor = np.linalg.svd(np.column_stack([ju, jv]), compute_uv=False)
            node = image[y, x]
            np.testing.assert_allclose(node, [np.sqrt(major * minor), minor, major], rtol=0.01,
                                       err_msg=f"pixel {x}, {y}")
            checked += 1
    assert checked >= 15

    # Position + Centre Offset: where the ray through the pixel's centre meets
    # the plane, the same for every sample of the pixel. A 1-px box filter at
    # 8 spp keeps the samples inside their pixel and spreads them over it.
    addon.cycles.filter_width = 1.0
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    add = tree.nodes.new("ShaderNodeVectorMath")
    add.operation = "ADD"
    tree.links.new(geometry.outputs["Position"], add.inputs[0])
    tree.links.new(footprint.outputs["Centre Offset"], add.inputs[1])
    tree.links.new(add.outputs[0], emission.inputs["Color"])
    snapped = _render(addon, str(tmp_path / "centre.exr"), 8, 3)
    tree.links.new(geometry.outputs["Position"], emission.inputs["Color"])
    raw = _render(addon, str(tmp_path / "position.exr"), 8, 3)
    moved = 0
    for y in range(2, RENDER_H, 5):
        for x in (3, RENDER_W // 2, RENDER_W - 4):
            centre = on_plane(x + 0.5, y + 0.5)
            pixel = np.linalg.norm(on_plane(x + 1.0, y + 0.5) - on_plane(x, y + 0.5))
            np.testing.assert_allclose(snapped[y, x, :2], centre, atol=1e-3 * pixel, err_msg=f"pixel {x}, {y}")
            moved += np.linalg.norm(raw[y, x, :2] - centre) > 0.01 * pixel
    assert moved > 10  # the raw position does differ from the centre


def test_filtered_render_is_closer_to_the_reference_than_the_plain_ramp(addon, tmp_path):
    """A small Cycles render: the plane receding to the horizon through a
    sharp ramp. At 1 spp the filtered material is much closer to a 256-spp
    render of the plain ramp than the plain ramp at 1 spp, and in the far
    field (where the ramp averages out) its mean colour matches the reference."""
    plane = _baked_plane_and_error(addon, tmp_path, 84.0, reference_spp=256)
    plain = _render(addon, str(tmp_path / "plain.exr"), 1, 1)
    plane.material.node_tree.links.new(plane.group.outputs["Color"], plane.emission.inputs["Color"])
    filtered = _render(addon, str(tmp_path / "filtered.exr"), 1, 1)
    ground, reference, rmse = plane.ground, plane.reference, plane.rmse
    assert ground.mean() > 0.5
    assert rmse(filtered) < 0.6 * rmse(plain), (rmse(filtered), rmse(plain))
    far = ground & (np.arange(RENDER_H)[:, None] < RENDER_H * 0.45)  # the rows near the horizon
    assert far.sum() > 50
    np.testing.assert_allclose(filtered[far].mean(axis=0), reference[far].mean(axis=0), atol=0.02)


# ---- The microsurface groups (paper Sec. 5.1 / 5.2) evaluated by Cycles -----
