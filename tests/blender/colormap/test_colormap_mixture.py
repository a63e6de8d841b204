"""The filtered ramp over a mixture of four Gaussians (docs/colormap.md, "A
mixture of Gaussians"): the group's arithmetic against the lookup table read
here, and a 1-spp Cycles render where the mixture beats the one Gaussian."""

import bpy
import numpy as np

from penumbra import native
from penumbra.colormap import filtered_ramp, node_groups

from test_colormap_noise import _baked_plane_and_error, _render, _render_scene


def _table_lookup(table, spec, mean, sigma):
    """What the group fetches: bilinear between texel centres of the lookup
    (rows bottom-up, σ = 0 in the bottom row), clamped at the edges."""
    height, width = table.shape[:2]
    x = (mean - spec["mean_min"]) / (spec["mean_max"] - spec["mean_min"]) * (width - 1)
    y = min(max(sigma, 0.0) / spec["sigma_max"], 1.0) * (height - 1)
    x0, y0 = int(np.clip(np.floor(x), 0, width - 2)), int(np.clip(np.floor(y), 0, height - 2))
    fx, fy = np.clip(x - x0, 0, 1), np.clip(y - y0, 0, 1)
    rows = table[y0:y0 + 2, x0:x0 + 2]
    return ((1 - fy) * ((1 - fx) * rows[0, 0] + fx * rows[0, 1]) + fy * ((1 - fx) * rows[1, 0] + fx * rows[1, 1]))


def test_mixture_group_averages_the_four_components(addon, tmp_path):
    """Constant inputs, one pixel each. Four components (m_k, v_k + w_k), as
    the Noise Filter forms them (a shared variance v, group means m_k, group
    spreads w_k), handed over as Mean = mean(m), Sigma² = v + mean(w) +
    var(m), δ_k = m_k − Mean, ε_k = w_k − mean(w) − var(m) for k = 1..3:
    the group must rebuild the fourth and give the average of the lookup at
    (m_k, √(v + w_k)), computed here from the components themselves."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0, filter_box=True)
    addon.render.resolution_x = addon.render.resolution_y = 1
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    baked = tree.nodes[node_groups.FILTERED_RAMP].node_tree
    spec = dict(baked["penumbra_lookup"])
    image = bpy.data.images[spec["image"]]
    table = native.require().image.read(bpy.path.abspath(image.filepath))[::-1, :, :3].astype(np.float64)
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = filtered_ramp.filtered_ramp_group(image, spec, "mixture under test", mixture=True)
    tree.links.new(node.outputs["Color"], emission.inputs["Color"])
    cases = [(0.0004, (0.5, 0.5, 0.5, 0.5), (0.0, 0.0, 0.0, 0.0)),          # one Gaussian
             (0.0001, (0.56, 0.45, 0.53, 0.48), (0.0004, 0.0001, 0.0009, 0.0)),
             (0.0, (0.40, 0.62, 0.50, 0.47), (0.0, 0.0016, 0.0001, 0.0004)),
             (0.0009, (0.42, 0.58, 0.47, 0.55), (0.0025, 0.0, 0.0001, 0.0009))]
    for k, (shared, means, spreads) in enumerate(cases):
        means, spreads = np.array(means), np.array(spreads)
        mean, spread = means.mean(), spreads.mean() + means.var()
        node.inputs["Mean"].default_value = mean
        node.inputs["Sigma"].default_value = np.sqrt(shared + spread)
        node.inputs["Offsets"].default_value = means[:3] - mean
        node.inputs["Variances"].default_value = spreads[:3] - spread
        pixel = _render(addon, str(tmp_path / f"case{k}.exr"), 1, 0)[0, 0]
        expected = np.mean([_table_lookup(table, spec, m, np.sqrt(shared + w)) for m, w in zip(means, spreads)], 0)
        np.testing.assert_allclose(pixel, expected, atol=2e-4, err_msg=f"case {k}")
        if k:  # not the one Gaussian: the mixture is not the Gaussian of its mean and variance
            assert np.abs(expected - _table_lookup(table, spec, mean, np.sqrt(shared + spread))).max() > 0.008


def test_mixture_beats_one_gaussian_at_one_sample(addon, tmp_path):
    """48×32 Cycles render of the receding plane at 1 spp against the plain
    ramp at 1024 spp: the baked material (the four-Gaussian mixture the
    Noise Filter hands the ramp) against the same material fed its Mean and
    Sigma only (one Gaussian, the filter before)."""
    plane = _baked_plane_and_error(addon, tmp_path, 80.0)
    tree, group, rmse = plane.material.node_tree, plane.group, plane.rmse
    tree.links.new(group.outputs["Color"], plane.emission.inputs["Color"])
    mixture = rmse(_render(addon, str(tmp_path / "mixture.exr"), 1, 0))
    for name in ("Offsets", "Variances"):
        tree.links.remove(group.inputs[name].links[0])
    single = rmse(_render(addon, str(tmp_path / "single.exr"), 1, 0))
    assert mixture < 0.9 * single, (mixture, single)
