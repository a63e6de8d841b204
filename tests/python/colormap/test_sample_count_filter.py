"""The sample-count-aware filter's derivation (docs/colormap.md,
"Sample-count-aware filter"), tested on an image plane as Cycles and EEVEE
sample it, with the core's exact L(mean, σ): pixels on an integer grid, the
separable Blackman-Harris pixel filter over ±1.5 px (the default width),
sample 0 of every pixel at its centre and the others spread over the
filter's whole support (stratified, through the filter's inverse CDF), a
signal with octaves both coarser and much finer than a pixel, a sharp ramp.

The shader sees the sample's position x, never the pixel c it is for: with
this filter a sample anywhere is about as likely to belong to the next pixel
(posterior weights 0.5 / 0.5 on a pixel edge, 0.9 / 0.05 / 0.05 at a
centre), and the posterior mean offset m(x) = E[x − c | x] stays within
0.054 px. For any kernel whose centre is a function of x alone, the filter a
pixel ends up with has the variance Var(u − a) + E[τ²] (u = x − c, a = x −
centre) = κ² − E[m²] + E[(m − a)²] + E[τ²] ≥ κ² + E[τ²] − E[m²]: every kernel
but one of variance below E[m²] = 0.0085 κ² widens the pixel filter. The
variance-keeping rule, centre x − (1 − β) m(x) with τ² = (1 − β²) E[m²], is
therefore almost the plain ramp; pulling the kernel towards the centre of the
pixel the sample lies in (the earlier rule) only adds (1 − β)² Var(x − snap)
to the blur. The filter keeps the kernel at the sample with τ = κ/√N: at
one sample (at the centre) the pixel's estimate, a blur that shrinks as 1/N,
traded against the samples' noise."""

from statistics import NormalDist

import numpy as np
import pytest

import _penumbra as pen

WIDTH = 1.5                                   # Cycles' filter_width, EEVEE's filter_size (defaults)
POSITIONS = np.array([0.0, 0.47, 0.53, 1.0])  # a sharp two-stop ramp
COLORS = np.array([[0.8, 0.05, 0.02], [0.8, 0.05, 0.02], [0.02, 0.3, 0.9], [0.02, 0.3, 0.9]])
# f = 0.5 + Σ a_k sin(ω_k·x + φ_k): octaves from 8 pixels to a fifth of a
# pixel, each along its own direction.
FREQUENCY = 2 * np.pi * np.array([1 / 8, 1 / 4, 1 / 2, 1.0, 2.0, 5.0])
_ANGLES = np.array([0.3, 1.9, 0.9, 2.6, 1.4, 0.1])
OMEGA = FREQUENCY[:, None] * np.stack([np.cos(_ANGLES), np.sin(_ANGLES)], axis=1)   # (octaves, 2)
AMPLITUDE = 0.25 * 0.6 ** np.arange(len(FREQUENCY))
SHARE_EXPONENT = 0.5                          # noise_filter.KERNEL_SHARE_EXPONENT


def blackman_harris(u):
    """Cycles' and EEVEE's pixel filter at offset u (pixels), 0 beyond ±WIDTH."""
    x = 2 * np.pi * (np.asarray(u, float) / (2 * WIDTH) + 0.5)
    w = 0.35875 - 0.48829 * np.cos(x) + 0.14128 * np.cos(2 * x) - 0.01168 * np.cos(3 * x)
    return np.where(np.abs(u) <= WIDTH, w, 0.0)


_U = np.linspace(-WIDTH, WIDTH, 20001)
_CDF = np.cumsum(blackman_harris(_U))
_CDF = (_CDF - _CDF[0]) / (_CDF[-1] - _CDF[0])
KAPPA = float(np.sqrt(np.sum(blackman_harris(_U) * _U ** 2) / np.sum(blackman_harris(_U))))


def posterior_mean_offset(x):
    """m(x) = E[x − c | x] over the pixels c whose filter reaches x (weights
    w(x − c), one axis)."""
    offsets = np.stack([x - np.floor(x) - 0.5 + k for k in (-2, -1, 0, 1, 2)])
    weights = blackman_harris(offsets)
    return (offsets * weights).sum(0) / weights.sum(0)


def signal(x, phase):
    return 0.5 + (AMPLITUDE * np.sin(x @ OMEGA.T + phase)).sum(-1)


def colour(values):
    return np.stack([np.interp(values, POSITIONS, COLORS[:, c]) for c in range(3)], axis=-1)


def kernel_moments(centres, tau, phase):
    """Mean and σ of f under N(centre, τ²I), in closed form for the sines
    (τ per centre)."""
    tau = np.broadcast_to(np.asarray(tau, float), centres.shape[:-1])[:, None, None]
    angle = centres @ OMEGA.T + phase
    mean = 0.5 + (AMPLITUDE * np.exp(-0.5 * (FREQUENCY * tau[:, :, 0]) ** 2) * np.sin(angle)).sum(-1)
    d = ((OMEGA[:, None] - OMEGA[None, :]) ** 2).sum(-1)
    s = ((OMEGA[:, None] + OMEGA[None, :]) ** 2).sum(-1)
    ad = angle[:, :, None] - angle[:, None, :]
    as_ = angle[:, :, None] + angle[:, None, :]
    products = 0.5 * (np.exp(-0.5 * d * tau ** 2) * np.cos(ad) - np.exp(-0.5 * s * tau ** 2) * np.cos(as_))
    second = (AMPLITUDE[:, None] * AMPLITUDE[None, :] * products).sum((-1, -2))
    return mean, np.sqrt(np.maximum(second - (mean - 0.5) ** 2, 0.0))


def truth(centres, phase):
    """∫ C(f(x)) w(x − c) dx, the pixel the renderer converges to (midpoint rule)."""
    z = np.linspace(-WIDTH, WIDTH, 121)
    w = blackman_harris(z)
    w = np.outer(w, w).ravel()
    w /= w.sum()
    grid = np.stack(np.meshgrid(z, z, indexing="ij"), axis=-1).reshape(-1, 2)
    return np.stack([(w[:, None] * colour(signal(c + grid, phase))).sum(0) for c in centres])


def sample_offsets(pixels, samples, rng):
    """x − c for each pixel's samples: sample 0 at the centre (Cycles' and
    EEVEE's first sample), the others in N − 1 of the N cells of a √N × √N
    jittered grid (one left out at random: the point the centre replaces),
    mapped through the filter's inverse CDF per axis."""
    side = int(round(np.sqrt(samples)))
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), axis=-1).reshape(-1, 2)
    offsets = np.zeros((pixels, samples, 2))
    for p in range(pixels):
        kept = cells[rng.permutation(samples)[:samples - 1]]
        offsets[p, 1:] = np.interp((kept + rng.random((samples - 1, 2))) / side, _CDF, _U)
    return offsets


def second_moment_of_m():
    """E[m(x)²] under the renderer's samples (c uniform over pixels, x − c ~ w)."""
    x = (np.arange(20000) + 0.5) / 20000
    density = sum(blackman_harris(x - 0.5 + k) for k in (-2, -1, 0, 1, 2))
    return float(np.sum(density * posterior_mean_offset(x) ** 2) / np.sum(density))


def kernels(rule, x, samples):
    """(centres, τ) of each sample's kernel under `rule`, from x alone."""
    beta = np.sqrt(1.0 - 1.0 / samples)
    if rule == "at the sample":
        return x, np.full(x.shape[:-1], KAPPA * samples ** -SHARE_EXPONENT)
    if rule == "pulled to the pixel's centre":     # the rule before: snap to the pixel x lies in
        return x - (1 - beta) * (x - np.floor(x) - 0.5), np.full(x.shape[:-1], KAPPA / np.sqrt(samples))
    if rule == "posterior centre":                 # keeps the filter's variance exactly
        tau = np.sqrt((1 - beta ** 2) * second_moment_of_m())
        return x - (1 - beta) * posterior_mean_offset(x), np.full(x.shape[:-1], tau)
    raise ValueError(rule)


def estimate(rule, centres, samples, phase, rng):
    x = centres[:, None, :] + sample_offsets(len(centres), samples, rng)
    if rule == "plain":
        return colour(signal(x, phase)).mean(1)
    y, tau = kernels(rule, x, samples)
    mean, sigma = kernel_moments(y.reshape(-1, 2), tau.reshape(-1), phase)
    values = pen.colormap.filtered(POSITIONS, COLORS, "LINEAR", mean, sigma)
    return values.reshape(len(centres), samples, 3).mean(1)


RULES = ("plain", "at the sample", "pulled to the pixel's centre", "posterior centre")


def measure_errors():
    """RMSE of each rule and sample count over 120 pixels and 2 signals."""
    rng = np.random.default_rng(12)
    centres = np.floor(rng.uniform(0, 64, (120, 2))) + 0.5
    table = {}
    for trial in range(2):
        phase = rng.uniform(0, 2 * np.pi, len(OMEGA))
        reference = truth(centres, phase)
        for rule in RULES:
            for samples in (1, 4, 16, 64, 256):
                error = estimate(rule, centres, samples, phase, rng) - reference
                table.setdefault((rule, samples), []).append(np.mean(error ** 2))
    return {key: float(np.sqrt(np.mean(v))) for key, v in table.items()}


@pytest.fixture(scope="module")
def errors():
    return measure_errors()


def test_a_sample_hardly_tells_which_pixel_it_belongs_to():
    """The posterior mean offset is tiny against the filter's spread."""
    assert KAPPA == pytest.approx(0.2770 * WIDTH, rel=1e-3)
    assert np.abs(posterior_mean_offset(np.linspace(0, 3, 3001))).max() < 0.06
    assert second_moment_of_m() < 0.01 * KAPPA ** 2


def test_a_kernel_placed_from_the_position_alone_widens_the_pixel_filter():
    """Var(u − a(x)) = κ² − E[m²] + E[(m − a)²] for any offset rule a(x):
    the cross term vanishes because m = E[u | x]. Checked by simulation for
    the earlier rule (pull to the centre of the pixel x lies in), which
    therefore widens the filter by almost its kernel's τ² instead of keeping
    it at κ², and for the variance-keeping posterior rule."""
    rng = np.random.default_rng(3)
    u = np.interp(rng.random(400000), _CDF, _U)
    x = rng.uniform(0, 64, u.size).round() + 0.5 + u   # pixel centres c, x = c + u
    for samples in (4, 16):
        pull = (1 - np.sqrt(1 - 1 / samples)) * (x - np.floor(x) - 0.5)
        m = posterior_mean_offset(x)
        assert np.var(u - pull) == pytest.approx(KAPPA ** 2 - np.mean(m * m) + np.mean((m - pull) ** 2), rel=0.01)
        # The pull gives back less than E[m²] of the kernel's τ² = κ²/N: the
        # pixel's filter is wider than the renderer's by almost all of τ².
        assert np.var(u - pull) + KAPPA ** 2 / samples > KAPPA ** 2 * (1 + 0.9 / samples)
        m_rule = (1 - np.sqrt(1 - 1 / samples)) * m
        assert np.var(u - m_rule) + (1 - (1 - 1 / samples)) * second_moment_of_m() == pytest.approx(KAPPA ** 2,
                                                                                                  rel=0.01)


@pytest.mark.parametrize("samples", [1, 4, 16, 64, 256])
def test_the_filter_beats_the_plain_ramp_at_every_sample_count(errors, samples):
    assert errors[("at the sample", samples)] < errors[("plain", samples)]


def test_the_variance_keeping_posterior_rule_is_almost_the_plain_ramp(errors):
    """The brief's proposal: with E[m²] this small its kernels vanish."""
    for samples in (4, 16):
        assert errors[("posterior centre", samples)] > 0.85 * errors[("plain", samples)]
        assert errors[("at the sample", samples)] < 0.75 * errors[("plain", samples)]
    # At one sample (at the centre, m = 0) its kernel is 0.09 κ wide: aliasing.
    assert errors[("posterior centre", 1)] > 4 * errors[("at the sample", 1)]


def test_the_kernel_at_the_sample_beats_the_pull_to_the_pixel_centre(errors):
    for samples in (4, 16, 64):
        assert errors[("at the sample", samples)] < errors[("pulled to the pixel's centre", samples)]
    assert errors[("at the sample", 1)] == pytest.approx(errors[("pulled to the pixel's centre", 1)], rel=1e-9)


def test_the_filter_converges(errors):
    for samples in (16, 64, 256):
        assert errors[("at the sample", samples)] < 0.6 * errors[("at the sample", samples // 4)]
    assert errors[("at the sample", 256)] < 0.25 * errors[("at the sample", 1)]
