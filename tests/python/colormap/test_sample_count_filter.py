"""The sample-count-aware filter's derivation (docs/colormap.md,
"Sample-count-aware filter"), tested on an image plane with the core's exact
L(mean, σ): a Gaussian pixel filter N(c, κ²I), a signal f with octaves both
coarser and much finer than the pixel, a sharp colour map C, and N samples
jittered on a √N × √N grid of the filter's quantiles (stratified, as
Cycles' and EEVEE's samplers are).

Each sample x_j gets L(μ_j, σ_j), the moments of f under its kernel
N(c + β(x_j − c), τ²). With β² + τ²/κ² = 1 the kernels' mixture is the pixel
filter at every N; τ² = κ²/N hands over to the plain ramp as N grows. The
tests check that this converges to the true pixel value, beats the plain
ramp at every sample count, and that the fixed pixel-centred filter (today's
1-spp filter, β = 0, τ = κ at every N) does not converge."""

from statistics import NormalDist

import numpy as np
import pytest

import _penumbra as pen

KAPPA = 1.0                                   # pixel filter σ, in pixels
POSITIONS = np.array([0.0, 0.47, 0.53, 1.0])  # a sharp two-stop ramp
COLORS = np.array([[0.8, 0.05, 0.02], [0.8, 0.05, 0.02], [0.02, 0.3, 0.9], [0.02, 0.3, 0.9]])
# f = 0.5 + Σ a_k sin(ω_k·x + φ_k): octaves from 8 pixels to a fifth of a
# pixel, each along its own direction.
FREQUENCY = 2 * np.pi * np.array([1 / 8, 1 / 4, 1 / 2, 1.0, 2.0, 5.0])
_ANGLES = np.array([0.3, 1.9, 0.9, 2.6, 1.4, 0.1])
OMEGA = FREQUENCY[:, None] * np.stack([np.cos(_ANGLES), np.sin(_ANGLES)], axis=1)   # (octaves, 2)
AMPLITUDE = 0.25 * 0.6 ** np.arange(len(FREQUENCY))


def signal(x, phase):
    """f at points x (..., 2)."""
    return 0.5 + (AMPLITUDE * np.sin(x @ OMEGA.T + phase)).sum(-1)


def colour(values):
    return np.stack([np.interp(values, POSITIONS, COLORS[:, c]) for c in range(3)], axis=-1)


def kernel_moments(centres, tau, phase):
    """Mean and σ of f under N(centre, τ²I), in closed form for the sines."""
    damp = np.exp(-0.5 * (FREQUENCY * tau) ** 2)
    angle = centres @ OMEGA.T + phase
    mean = 0.5 + (AMPLITUDE * damp * np.sin(angle)).sum(-1)
    # E[sin a sin b] under the Gaussian, for every pair of octaves.
    d = ((OMEGA[:, None] - OMEGA[None, :]) ** 2).sum(-1)
    s = ((OMEGA[:, None] + OMEGA[None, :]) ** 2).sum(-1)
    ad = angle[:, :, None] - angle[:, None, :]
    as_ = angle[:, :, None] + angle[:, None, :]
    products = 0.5 * (np.exp(-0.5 * d * tau ** 2) * np.cos(ad) - np.exp(-0.5 * s * tau ** 2) * np.cos(as_))
    second = (AMPLITUDE[:, None] * AMPLITUDE[None, :] * products).sum((-1, -2))
    variance = second - (mean - 0.5) ** 2
    return mean, np.sqrt(np.maximum(variance, 0.0))


def truth(centres, phase):
    """∫ C(f(x)) N(x; c, κ²I) dx by a dense midpoint rule over ±6κ."""
    z = np.linspace(-6, 6, 241)
    w = np.exp(-0.5 * z * z)
    w = np.outer(w, w).ravel()
    w /= w.sum()
    grid = KAPPA * np.stack(np.meshgrid(z, z, indexing="ij"), axis=-1).reshape(-1, 2)
    return np.stack([(w[:, None] * colour(signal(c + grid, phase))).sum(0) for c in centres])


def estimate(method, centres, samples, phase, rng):
    """The pixel value from `samples` samples of the pixel filter, jittered
    in the cells of a √N × √N grid of its quantiles."""
    side = int(round(np.sqrt(samples)))
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), axis=-1).reshape(-1, 2)
    strata = (cells[None, :, :] + rng.random((len(centres), samples, 2))) / side
    offsets = KAPPA * np.vectorize(NormalDist().inv_cdf)(strata)
    x = centres[:, None, :] + offsets
    if method == "plain":
        return colour(signal(x, phase)).mean(1)
    if method == "pixel-centred":
        beta, tau = 0.0, KAPPA
    else:  # the sample-count-aware kernel
        beta, tau = np.sqrt(1.0 - 1.0 / samples), KAPPA / np.sqrt(samples)
    mean, sigma = kernel_moments((centres[:, None, :] + beta * offsets).reshape(-1, 2), tau, phase)
    values = pen.colormap.filtered(POSITIONS, COLORS, "LINEAR", mean, sigma)
    return values.reshape(len(centres), samples, 3).mean(1)


def measure_errors():
    """RMSE of each method and sample count over 150 pixels and 2 signals."""
    rng = np.random.default_rng(12)
    centres = rng.uniform(0, 64, (150, 2))
    table = {}
    for trial in range(2):
        phase = rng.uniform(0, 2 * np.pi, len(OMEGA))
        reference = truth(centres, phase)
        for method in ("plain", "pixel-centred", "sample-count"):
            for samples in (1, 4, 16, 64, 256):
                error = estimate(method, centres, samples, phase, rng) - reference
                table.setdefault((method, samples), []).append(np.mean(error ** 2))
    return {key: float(np.sqrt(np.mean(v))) for key, v in table.items()}


@pytest.fixture(scope="module")
def errors():
    return measure_errors()


def test_kernels_average_to_the_pixel_filter_at_every_sample_count():
    """Kernel centres c + β(x − c) with x ~ N(c, κ²), plus the kernel's own
    τ: together they spread as the pixel filter does (β²κ² + τ² = κ²)."""
    rng = np.random.default_rng(1)
    for samples in (1, 2, 4, 16, 256):
        beta, tau = np.sqrt(1.0 - 1.0 / samples), KAPPA / np.sqrt(samples)
        points = beta * rng.normal(0, KAPPA, 400000) + rng.normal(0, tau, 400000)
        assert np.std(points) == pytest.approx(KAPPA, rel=0.01)


@pytest.mark.parametrize("samples", [1, 4, 16, 64, 256])
def test_sample_count_filter_beats_the_plain_ramp_at_every_sample_count(errors, samples):
    assert errors[("sample-count", samples)] < errors[("plain", samples)]


def test_sample_count_filter_converges_and_the_pixel_centred_one_does_not(errors):
    # One sample: both filters are the same pixel-centred estimate.
    assert errors[("sample-count", 1)] == pytest.approx(errors[("pixel-centred", 1)], rel=1e-9)
    # The pixel-centred filter keeps its bias (the Gaussian-of-f assumption).
    assert errors[("pixel-centred", 256)] > 0.5 * errors[("pixel-centred", 1)]
    # The sample-count filter goes to the truth (at 4 samples the kernels
    # leave the pixel's centre, and the samples' spread shows first).
    assert errors[("sample-count", 256)] < 0.4 * errors[("pixel-centred", 256)]
    for samples in (16, 64, 256):
        assert errors[("sample-count", samples)] < 0.6 * errors[("sample-count", samples // 4)]
