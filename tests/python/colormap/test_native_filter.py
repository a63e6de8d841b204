"""The band-limited Noise Filter's closed forms (noise_maths.
fbm_detail_roughness, band_limited_terms; native_filter.py bakes them into
Float Curves): the Detail and Roughness read back from a noise's octave
weights, and the rescaled lower-Detail noise against the full one, octave
by octave. noise_maths is free of bpy: loaded from its file."""

import importlib.util
import math
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
spec = importlib.util.spec_from_file_location(
    "colormap_noise_maths", os.path.join(ROOT, "addon", "penumbra", "colormap", "noise_maths.py"))
noise_maths = importlib.util.module_from_spec(spec)
spec.loader.exec_module(noise_maths)

NOISES = [(4.0, 0.5, 2.0), (4.3, 0.5, 2.0), (8.0, 0.6, 2.5), (2.7, 1.0, 2.0), (5.0, 1.3, 1.7), (15.0, 0.5, 2.0)]


@pytest.mark.parametrize("detail, roughness, _lacunarity", NOISES)
def test_detail_and_roughness_read_back(detail, roughness, _lacunarity):
    weights = noise_maths.octave_weights(detail, roughness, (4, 5, 0))
    got = noise_maths.fbm_detail_roughness(weights)
    assert got is not None
    assert got[0] == pytest.approx(detail, abs=1e-9) and got[1] == pytest.approx(roughness, abs=1e-12)


@pytest.mark.parametrize("detail", [0.0, 0.6, 1.0])
def test_too_few_octaves_are_not_read_back(detail):
    assert noise_maths.fbm_detail_roughness(noise_maths.octave_weights(detail, 0.5, (4, 5, 0))) is None


@pytest.mark.parametrize("detail, roughness, lacunarity", NOISES)
def test_rescaled_lower_detail_leaves_out_what_sigma_carries(detail, roughness, lacunarity):
    """Far inside the resolved range (g₀ = 1): k·(fBm(D') − 0.5) has weight
    c_i on every octave up to ⌊D'⌋, and the weights it misses, Σ(c_i − k
    w_i(D'))², are σ²/V₀; at D' = D it is the noise itself."""
    coefficients = noise_maths.octave_weights(detail, roughness, (4, 5, 0))
    bias = -40.0        # x = cut − bias: L^(−2x) vanishes, g₀ = 1
    total = sum(c * c for c in coefficients)
    for cut in [step / 8.0 for step in range(int(detail * 8) + 1)] + [detail]:
        got_cut, scale, sigma = noise_maths.band_limited_terms(cut - bias, coefficients, detail, roughness,
                                                               lacunarity, 1.0, bias)
        assert got_cut == pytest.approx(cut)
        lower = noise_maths.octave_weights(cut, roughness, (4, 5, 0))
        kept = [scale * w for w in lower] + [0.0] * (len(coefficients) - len(lower))
        assert kept[:int(math.floor(cut)) + 1] == pytest.approx(coefficients[:int(math.floor(cut)) + 1], rel=1e-9)
        missed = sum((c - w) ** 2 for c, w in zip(coefficients, kept))
        assert sigma ** 2 == pytest.approx(missed, rel=1e-9, abs=1e-12 * total)
    assert sigma == pytest.approx(0.0, abs=1e-9)


def test_unresolved_octave_zero_is_averaged_away():
    """Where the kernel spans many octave-0 cells (x ≪ 0) the estimate tends
    to the mean and σ² to the noise's whole variance."""
    coefficients = noise_maths.octave_weights(4.0, 0.5, (4, 5, 0))
    cut, scale, sigma = noise_maths.band_limited_terms(-12.0, coefficients, 4.0, 0.5, 2.0, 1.0, 0.5)
    assert cut == 0.0 and scale < 1e-3
    assert sigma ** 2 == pytest.approx(sum(c * c for c in coefficients), rel=1e-5)
