"""Issue #25's equal-time check (one Blender, conftest.ONLY_IN): the
benchmark plane at 96×54 in Cycles, the plain ramp and two Noise Filter
presets rendered interleaved in one process (bench/helpers/
colormap_equal_time.py), CPU seconds, median of 3, the plain ramp's RMSE
read log-log off its own 1–256 spp curve at each filtered render's time.

The 16-tap preset of the previous versions must fail the issue's goal
(≤ 0.7× the plain ramp's error at equal time) by more than the 20 % margin.
The default preset (1 Noise: one Noise Texture with its Detail cut at the
sample's resolution) does not meet 0.7× either (measured on this plane 1.31
at 4 spp and 0.86 at 16, on the seven benchmark scenes 0.75–1.03 at 16:
docs/colormap-benchmark.md, "Equal time"): what is asserted of it is what
it reaches, with a margin: at least 2× better than the 16-tap preset at
equal time at 4 and 16 spp (measured: about 3×)."""

import os

import pytest

from penumbra.colormap import filter_quality

from bench.helpers import colormap_equal_time as equal_time  # noqa: E402

SIZE = (96, 54)
GOAL = 0.7
MARGIN = 1.2
PLAIN_SPP = [1, 4, 16, 64, 256]
FILTERED_SPP = [4, 16]
LEGACY = "TAPS_16_MIXTURE"


@pytest.fixture(scope="module")
def ratios(tmp_path_factory):
    """{preset: {spp: equal-time RMSE ratio}}, the add-on registered only
    while rendering (the other tests' fixture registers it per test)."""
    import penumbra
    folder = str(tmp_path_factory.mktemp("equal_time"))
    penumbra.register()
    try:
        scene, plane, material = equal_time.new_plane_scene(SIZE)
        materials = {equal_time.PLAIN: material}
        for quality in (filter_quality.DEFAULT, LEGACY):
            materials[quality] = equal_time.bake_quality(scene, plane, material, quality,
                                                         os.path.join(folder, "lut"))
        renderer = equal_time.Renderer(scene, plane, materials, folder)
        reference = equal_time.reference_image(renderer, 1024)
        counts = {equal_time.PLAIN: PLAIN_SPP, filter_quality.DEFAULT: FILTERED_SPP, LEGACY: FILTERED_SPP}
        results = equal_time.sweep(renderer, reference, counts, repeats=3)
    finally:
        penumbra.unregister()
    return {q: equal_time.equal_time_ratios(results, q, "cpu") for q in (filter_quality.DEFAULT, LEGACY)}


@pytest.mark.parametrize("spp", FILTERED_SPP)
def test_sixteen_taps_fail_the_equal_time_goal(ratios, spp):
    assert ratios[LEGACY][spp] > GOAL * MARGIN, ratios


@pytest.mark.parametrize("spp", FILTERED_SPP)
def test_default_preset_beats_sixteen_taps_at_equal_time(ratios, spp):
    assert filter_quality.DEFAULT != LEGACY
    assert ratios[filter_quality.DEFAULT][spp] * 2.0 < ratios[LEGACY][spp], ratios


def test_plain_curve_is_read_on_its_best_error_within_a_time():
    """At EEVEE's small sizes a 1-sample render took longer than a 16-sample
    one (fixed costs): the plain ramp's error at a time is the best it
    reaches within that time, not a line through the slower, worse render."""
    import math
    plain = {1: {"cpu": 0.07, "rmse": 0.18}, 4: {"cpu": 0.05, "rmse": 0.09}, 16: {"cpu": 0.06, "rmse": 0.035},
             64: {"cpu": 0.12, "rmse": 0.013}}
    t = (math.log(0.08) - math.log(0.06)) / (math.log(0.12) - math.log(0.06))
    between = math.exp((1 - t) * math.log(0.035) + t * math.log(0.013))
    assert abs(equal_time.plain_error_at(plain, 0.08, "cpu") - between) < 1e-9
    assert abs(equal_time.plain_error_at(plain, 0.01, "cpu") - 0.09) < 1e-9      # clamped at the fastest
    assert abs(equal_time.plain_error_at(plain, 10.0, "cpu") - 0.013) < 1e-9     # and at the slowest
