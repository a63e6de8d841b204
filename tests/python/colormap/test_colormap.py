"""_penumbra's colour-map functions against references written here in numpy:
a brute-force Gaussian-weighted sum over a fine grid (midpoint rule) for the
lookup, the contract's layout, and bad input."""

import math

import numpy as np
import pytest

import _penumbra as pen


def brute_force(colors, mean, sigma, n=200001):
    """∫ C(v) N(v; mean, σ²) dv with C the samples joined linearly, clamped."""
    z = np.linspace(-12, 12, n)
    v = mean + sigma * z
    w = np.exp(-0.5 * z * z)
    k = colors.shape[0]
    xs = np.linspace(0, 1, k)
    values = np.stack([np.interp(v, xs, colors[:, c]) for c in range(colors.shape[1])], axis=1)
    return (w[:, None] * values).sum(0) / w.sum()


def test_colormap_lut_follows_the_contract_layout_and_matches_brute_force():
    rng = np.random.default_rng(3)
    colors = rng.random((9, 3)).astype(np.float32)
    lut = pen.colormap.lut(colors, 33, 17, 0.3, -0.25, 1.25)
    assert lut.shape == (17, 33, 3) and lut.dtype == np.float32
    for y in (0, 5, 16):
        for x in (0, 7, 20, 32):
            mean = -0.25 + 1.5 * x / 32
            sigma = 0.3 * y / 16
            expect = np.array([np.interp(mean, np.linspace(0, 1, 9), colors[:, c]) for c in range(3)]) \
                if sigma == 0 else brute_force(colors, mean, sigma)
            np.testing.assert_allclose(lut[y, x], expect, atol=2e-6)


def test_large_sigma_tends_to_the_clamped_maps_mean():
    colors = np.array([[0.0, 1.0], [1.0, 0.0], [0.2, 0.6]], np.float32)
    lut = pen.colormap.lut(colors, 5, 3, 1e9, 0.0, 1.0)
    np.testing.assert_allclose(lut[2, 2], [(0.0 + 0.2) / 2, (1.0 + 0.6) / 2], atol=1e-6)


@pytest.mark.parametrize("kwargs, message", [
    (dict(sigma_max=0.0), "sigma_max"),
    (dict(sigma_max=float("nan")), "sigma_max"),
    (dict(width=1), r"width must be in \[2, 8192\]"),
    (dict(mean_min=1.0, mean_max=1.0), "mean"),
])
def test_bad_arguments_raise_value_error(kwargs, message):
    args = dict(colors=np.zeros((2, 3), np.float32), width=8, height=8, sigma_max=0.2, mean_min=0.0, mean_max=1.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        pen.colormap.lut(**args)


def test_nan_colours_are_rejected():
    colors = np.array([[0.0, 0.0, 0.0], [np.nan, 1.0, 1.0]], np.float32)
    with pytest.raises(ValueError, match="finite"):
        pen.colormap.lut(colors, 8, 8, 0.2, 0.0, 1.0)


def test_single_colour_gives_a_constant_table():
    lut = pen.colormap.lut(np.array([[0.1, 0.2, 0.3, 1.0]], np.float32), 4, 4, 0.5, -1.0, 2.0)
    np.testing.assert_allclose(lut.reshape(-1, 4), np.tile([0.1, 0.2, 0.3, 1.0], (16, 1)), atol=1e-7)


def test_progress_is_reported_and_false_cancels():
    seen = []
    pen.colormap.lut(np.zeros((2, 3), np.float32), 16, 64, 0.2, 0.0, 1.0, progress=lambda f: seen.append(f))
    assert seen and seen[-1] == 1.0
    with pytest.raises(pen.Cancelled):
        pen.colormap.lut(np.zeros((2, 3), np.float32), 16, 64, 0.2, 0.0, 1.0, progress=lambda f: False)


def test_bilinear_accuracy_report_matches_an_independent_bilinear_lookup():
    rng = np.random.default_rng(5)
    colors = rng.random((6, 1)).astype(np.float32)
    lut = pen.colormap.lut(colors, 16, 16, 0.2, 0.0, 1.0)
    report = pen.colormap.lut_accuracy(np.linspace(0, 1, 6), colors, "linear", lut, 0.2, 0.0, 1.0, probes=50)
    # Recompute the worst probe's error here with numpy's own bilinear interpolation.
    m, s = report["worst_mean"], report["worst_sigma"]
    fx, fy = m * 15, s / 0.2 * 15
    x0, y0 = min(int(fx), 14), min(int(fy), 14)
    tx, ty = fx - x0, fy - y0
    t = lut[..., 0]
    bilinear = ((1 - tx) * (1 - ty) * t[y0, x0] + tx * (1 - ty) * t[y0, x0 + 1] +
                (1 - tx) * ty * t[y0 + 1, x0] + tx * ty * t[y0 + 1, x0 + 1])
    exact = brute_force(colors, m, s)[0] if s > 0 else np.interp(m, np.linspace(0, 1, 6), colors[:, 0])
    assert abs(abs(bilinear - exact) - report["max_abs_error"]) < 1e-5


def test_microsurface_functions_against_closed_forms():
    # Λ from the paper's Eq. 3 written here.
    a = 0.8
    assert pen.colormap.smith_lambda_of_a(a) == pytest.approx(
        math.exp(-a * a / 2) / (math.sqrt(2 * math.pi) * a) - 0.5 * math.erfc(a / math.sqrt(2)), rel=1e-12)
    assert pen.colormap.smith_lambda(math.pi / 2, 0.3) == math.inf
    assert pen.colormap.average_visibility(1.0, 3.0) == pytest.approx(0.4)
    # Λ_sum = 1: the larger of two standard normals.
    mean, sd = pen.colormap.effective_height(1.0)
    assert mean == pytest.approx(1 / math.sqrt(math.pi), abs=1e-8)
    assert sd == pytest.approx(math.sqrt(1 - 1 / math.pi), abs=1e-8)
    g_mean, g_cov = pen.colormap.slope_filtering(1.2, 0.3, [0.0, 0.0], [0.1, 0.02, 0.05])
    n_mean, n_cov = pen.colormap.slope_filtering(1.2, 0.3, [0.0, 0.0], [0.1, 0.02, 0.05], method="numerical")
    np.testing.assert_allclose(g_mean, n_mean, atol=3e-5)
    np.testing.assert_allclose(g_cov, n_cov, atol=3e-5)
