"""Issue #14 goal 2's steadiness criteria of a light rig on video, with the
rig as bench/lights_video_benchmark.py builds it (the add-on's settings:
COUNT lights, the temporal filter at FPS, suns drawn as MODEL). Shared by
that benchmark (every sequence, beside its accuracy criterion (a)) and
tests/python/lights/test_lights_video_criteria.py (one short sequence):

  (b) the flux-weighted 95th percentile of every light's step between
      consecutive frames, the map's own motion removed, is below 1 degree;
  (c) no light carrying 1 % of the flux or more (in either frame) moves
      more than 5 degrees in one frame, the map's motion removed;
  (d) the mean relative RMS change of the rig's irradiance between
      consecutive frames is at most 1.1x the map's own."""

import math

import numpy as np

from bench.helpers.metrics import rel_rmse
from bench.helpers.paths import compiled_core

_penumbra = compiled_core()

COUNT = 64
FPS = 24.0
MODEL = "BLENDER4_CONE"


def rotation_z(degrees):
    a = math.radians(degrees)
    return np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])


def build_rig(maps, **options):
    b = _penumbra.lights.RigBuilder(count=COUNT, frames_per_second=FPS, sun_model=MODEL, max_width=0, **options)
    for m in maps:
        b.add_frame(m)
    return b.finish()


def rig_irradiances(rig, normals):
    """Each frame's irradiance at `normals` of the rig's suns, drawn as MODEL."""
    return [_penumbra.lights.irradiance(d, rgb, normals, spread=spread, sun_model=MODEL)
            for d, rgb, spread in zip(rig["directions"], rig["rgb"], rig["spread"])]


def steps(rig, motion):
    """Per (frame pair, light): the angle moved once `motion` is removed, and the light's flux share."""
    d, p = rig["directions"], rig["power"]
    out = []
    for t in range(1, len(d)):
        predicted = d[t - 1] @ motion.T
        angle = np.degrees(np.arccos(np.clip(np.sum(predicted * d[t], axis=1), -1.0, 1.0)))
        share = np.maximum(p[t - 1] / max(p[t - 1].sum(), 1e-300), p[t] / max(p[t].sum(), 1e-300))
        out.append((angle, share))
    return out


def weighted_percentile(values, weights, q):
    order = np.argsort(values)
    v, w = values[order], weights[order]
    c = np.cumsum(w)
    return float(v[np.searchsorted(c, q * c[-1])]) if c[-1] > 0 else 0.0


def flicker(irradiances):
    """Mean relative RMS change of irradiance between consecutive frames."""
    return float(np.mean([rel_rmse(b, a) for a, b in zip(irradiances, irradiances[1:])]))


def steadiness(rig, motion, irradiances, map_irradiances):
    """What (b), (c) and (d) measure of `rig` over a sequence whose content
    turns by `motion` each frame; `irradiances` are the rig's per frame
    (rig_irradiances), `map_irradiances` the maps' own, at the same normals."""
    st = steps(rig, motion)
    angles = np.concatenate([a for a, _ in st])
    shares = np.concatenate([s for _, s in st])
    big = shares >= 0.01
    return {"p95 step": weighted_percentile(angles, shares, 0.95),
            "largest big step": float(angles[big].max()) if big.any() else 0.0,
            "jumps": int(np.sum(big & (angles > 5.0))),
            "flicker": flicker(irradiances), "map flicker": flicker(map_irradiances)}


def steady(c):
    """(b), (c) and (d) met by the measures `c` of steadiness()."""
    return {"b": c["p95 step"] < 1.0, "c": c["jumps"] == 0, "d": c["flicker"] <= 1.1 * c["map flicker"]}
