"""The one-evaluation Noise Filter's closed form (noise_maths.
OCTAVE_CORRELATION_LENGTH, point_shrinkage) against the octave table that
scripts/colormap_measure_noise.py measured with Blender's own noise
(noise_statistics.json), and the quality presets' table. noise_maths and
filter_quality are free of bpy: loaded from their files."""

import importlib.util
import json
import math
import os

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
FOLDER = os.path.join(ROOT, "addon", "penumbra", "colormap")


def _load(name):
    spec = importlib.util.spec_from_file_location(f"colormap_{name}", os.path.join(FOLDER, f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


noise_maths = _load("noise_maths")
filter_quality = _load("filter_quality")


def _table():
    with open(os.path.join(FOLDER, "noise_statistics.json")) as f:
        return json.load(f)


@pytest.mark.parametrize("version", ["3.4", "4.5"])
def test_gaussian_correlation_matches_the_measured_octave_table(version):
    """1 − q = E over two kernel points of ρ = ((1 + 2s²/l²)(1 + 2s²e²/l²))^(−1/2)
    must reproduce the measured fraction q(s, e) of an octave's variance
    inside a footprint (25 sizes × 7 elongations); a length off by 30 %
    misses it by over 0.1."""
    d = _table()
    q = np.asarray(d["blender"][version]["octave"]["q"])
    s = 2.0 ** np.asarray(d["log2_footprint"])[None, :]
    e = 2.0 ** np.asarray(d["log2_elongation"])[:, None]

    def model(length):
        a = (s / length) ** 2
        return 1.0 - ((1.0 + 2.0 * a) * (1.0 + 2.0 * a * e * e)) ** -0.5

    fitted = model(noise_maths.OCTAVE_CORRELATION_LENGTH)
    assert np.sqrt(((fitted - q) ** 2).mean()) < 0.02
    assert np.abs(fitted - q).max() < 0.05
    assert np.abs(model(1.3 * noise_maths.OCTAVE_CORRELATION_LENGTH) - q).max() > 0.1


def test_point_shrinkage_keeps_coarse_octaves_and_drops_fine_ones():
    """g → 1 for an octave much coarser than the kernel, → 0 much finer, and
    an elongated kernel shrinks more than a round one of its minor axis."""
    g = noise_maths.point_shrinkage
    assert g(1e-4, 1e-4, 0, 2.0) == pytest.approx(1.0, abs=1e-6)
    assert g(10.0, 10.0, 0, 2.0) < 0.01
    assert g(0.1, 0.1, 3, 2.0) < g(0.1, 0.1, 0, 2.0)
    assert g(0.1, 1.0, 0, 2.0) < g(0.1, 0.1, 0, 2.0)
    # the Gaussian model's regression weight on the kernel's own centre
    a = (0.3 / noise_maths.OCTAVE_CORRELATION_LENGTH) ** 2
    assert g(0.3, 0.3, 0, 2.0) == pytest.approx(1.0 / (1.0 + a))
    assert math.isfinite(g(0.0, 0.0, 15, 2.0))


def test_presets_name_the_legacy_filter_and_a_different_default():
    q = filter_quality.QUALITIES
    legacy = q[filter_quality.LEGACY]
    assert (legacy.taps, legacy.analytic_octaves, legacy.mixture) == (16, 0, True)
    assert filter_quality.DEFAULT in q and filter_quality.DEFAULT != filter_quality.LEGACY
    assert all(p.taps == 1 or p.analytic_octaves == 0 for p in q.values())


def test_measured_table_covers_every_preset():
    """The benchmark writes filter_quality.json beside the add-on; the panel
    reads a cost and an equal-time ratio for each preset from it, and the
    default must be the preset with the lowest ratio among those that
    converge to the plain ramp (every octave evaluated: a preset that never
    evaluates one stays blurred where it is resolved) and keep the taps for
    one sample (the per-sample verdict there)."""
    table = filter_quality.measured()
    assert set(table) == set(filter_quality.QUALITIES)
    for row in table.values():
        assert row["cost"] > 0.0 and row["ratio"] > 0.0
    converging = [k for k in table if filter_quality.QUALITIES[k].analytic_octaves == 0
                  and filter_quality.QUALITIES[k].taps_at_one]
    assert min(converging, key=lambda k: table[k]["ratio"]) == filter_quality.DEFAULT
