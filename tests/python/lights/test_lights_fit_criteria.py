"""Guards issue #14 goal 1, which bench/lights_fit_benchmark.py checks on
every bundled HDRI at 1024x512 and N = 4 ... 256: the fitted rig's
irradiance error at most 0.5x median cut's (at most 1x at N = 4), both
drawn as Blender 3.4 and 4.5 / 5.x draw suns. Here on one HDRI, forest.exr
at 512x256 (found as the benchmark finds it), N = 4, 16 and 64 (the fit at
256 lights takes 20 s), the benchmark's 1000 normals, measured and judged by
the benchmark's own code (bench/helpers/lights_fit_criteria.py). No
rendering: the error is the irradiance at the normals against the map's
exact irradiance.

Shown able to fail: the same goal rejects the region lights without the
fit (the rig before issue #14), measured in the same call: 0.75x median
cut's error at N = 16, in both Blenders."""

import numpy as np
import pytest

import _penumbra
from bench.helpers import test_videos as videos
from bench.helpers.lights_fit_criteria import MODELS, measure, meets_goal

HDRI = "forest"
COUNTS = (4, 16, 64)


@pytest.fixture(scope="module")
def rows():
    image = np.maximum(videos.load_world(HDRI, 512), 0)
    normals = _penumbra.sh.fibonacci_directions(1000)
    return measure([(HDRI, image, _penumbra.lights.exact_irradiance(image, normals))], normals, COUNTS)


@pytest.mark.parametrize("method, must_fail", [
    ("region power + fit", set()),
    ("region power", {(blender, 16) for blender in MODELS}),
], ids=["fitted", "without the fit"])
def test_fitted_rig_has_at_most_half_median_cuts_error_on_one_hdri(rows, method, must_fail):
    failing = {(blender, n) for (blender, _, n), row in rows.items() if not meets_goal(row, n, method)}
    ratios = {key: row[method] / row["median cut"] for key, row in rows.items()}
    assert len(rows) == len(MODELS) * len(COUNTS)
    assert failing >= must_fail if must_fail else not failing, ratios
