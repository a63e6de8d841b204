"""Issue #14 goal 1: the fitted rig's irradiance error against Debevec's
median cut on the same map, every light drawn as a sun the way Blender 3.4
(disc) or 4.5 / 5.x (cone) draws it. Goal: fit / median cut <= 0.5 at
N = 16, 64, 256 and <= 1 at N = 4. Shared by bench/lights_fit_benchmark.py
(every bundled HDRI at 1024x512) and tests/python/lights/test_lights_fit_criteria.py
(one HDRI, N <= 64).

The error is the relative RMSE on luminance over `normals` against the
map's exact irradiance `ref`."""

import time

from bench.helpers.median_cut import median_cut_suns
from bench.helpers.metrics import rel_rmse
from bench.helpers.paths import compiled_core

_penumbra = compiled_core()

COUNTS = (4, 16, 64, 256)
MODELS = {"3.4": "BLENDER3_DISC", "4.5 / 5.x": "BLENDER4_CONE"}
GOAL = {4: 1.0, 16: 0.5, 64: 0.5, 256: 0.5}


def measure(maps, normals, counts=COUNTS):
    """rows[(blender, hdri, n)] = {method: error, or its seconds}: median
    cut, the region lights without the fit ("region power") and with it
    ("region power + fit"), for each (name, image, ref) of `maps`."""
    L = _penumbra.lights
    rows = {}
    for name, image, ref in maps:
        for n in counts:
            d, rgb, spread = median_cut_suns(image, n)
            started = time.time()
            region = L.frame_lights(image, count=n, max_width=0, fit_irradiance=False)
            region_seconds = time.time() - started
            for blender, model in MODELS.items():
                row = rows.setdefault((blender, name, n), {})
                row["median cut"] = rel_rmse(L.irradiance(d, rgb, normals, spread=spread, sun_model=model), ref)
                row["region power"] = rel_rmse(L.irradiance(region["directions"], region["rgb"], normals,
                                                            spread=region["spread"], sun_model=model), ref)
                started = time.time()
                fit = L.frame_lights(image, count=n, max_width=0, fit_irradiance=True, sun_model=model)
                row["seconds"] = time.time() - started
                row["region seconds"] = region_seconds
                row["region power + fit"] = rel_rmse(L.irradiance(fit["directions"], fit["rgb"], normals,
                                                                  spread=fit["spread"], sun_model=model), ref)
                print(f"  {blender} {name} N={n}: " + ", ".join(f"{k} {v:.4g}" for k, v in row.items()), flush=True)
    return rows


def meets_goal(row, n, method="region power + fit"):
    """Whether `method` of a measure() row at N = n meets the goal."""
    return row[method] / row["median cut"] <= GOAL[n]
