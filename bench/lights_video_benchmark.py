#!/usr/bin/env python3
"""Issue #14 goal 2: light rigs steady on video (not a test; `make bench`).

Sequences, made in memory from Blender's bundled HDRIs
(bench/helpers/test_videos.py) at WIDTH x WIDTH/2: rotations about +Z
of 0.5, 1 and 2 degrees per frame, a cross-fade between two HDRIs over 40
frames, and +-2 % exposure noise per frame (each frame's map times a factor
drawn uniformly in [0.98, 1.02]). Each is turned into a rig with
_penumbra.lights.RigBuilder as the add-on builds it (the add-on's defaults:
64 lights, the temporal filter at the scene's 24 fps, tracking, the
irradiance fit when it is on by default), every sun drawn as Blender 4.5 /
5.x draws it (the cone model, core/lights/sun_irradiance.hpp). Criteria:

  (a) accuracy: each frame's irradiance relative RMSE (luminance, 1000
      Fibonacci normals) against that frame's own map is at most the error
      of Debevec's median cut rebuilt for that frame (its rectangles' RMS
      radius drawn as the suns' angles, bench/helpers/median_cut.py);
  (b) steadiness: the flux-weighted 95th percentile of every light's step
      between consecutive frames, once the map's own motion (the known
      rotation) is removed, is below 1 degree;
  (c) no jumps: no light carrying 1 % of the flux or more (in either frame)
      moves more than 5 degrees in one frame, the map's motion removed;
  (d) flicker: the mean relative RMS change of the rig's irradiance between
      consecutive frames is at most 1.1x the map's own.

It also measures what the temporal filter's delay costs at a cut (one HDRI,
then another) and at the first and last frames, and the same criteria for
the rig built the old way (light k = Halton point k through each frame's
CDF) as the baseline. Only the cost at 2048x1024 is timed (under the lock
of --lock PATH or $PENUMBRA_BENCH_LOCK, when given, as `flock` takes it).
Run alone (`python bench/lights_video_benchmark.py [--no-timing] [--lock
PATH]`) or by
`make bench BENCH=lights`,
it replaces its section of docs/lights-benchmark.md and writes
docs/lights/video_delay.svg."""


import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers import svg_plot, test_videos as data  # noqa: E402
from bench.helpers.doc_section import lock_path, locked, write_section  # noqa: E402
from bench.helpers.lights_video_criteria import (COUNT, FPS, MODEL, build_rig, rig_irradiances,  # noqa: E402
                                                 rotation_z, steadiness, steady)
from bench.helpers.median_cut import median_cut_suns  # noqa: E402
from bench.helpers.metrics import rel_rmse  # noqa: E402
from bench.helpers.paths import ROOT, compiled_core  # noqa: E402

_penumbra = compiled_core()

L = _penumbra.lights
WIDTH = 512
SECTION = "## Video (issue #14 goal 2)"


def sequences(frames=40):
    """name -> (maps, per-frame rotation of the content from the previous frame)."""
    courtyard = np.maximum(data.load_world("courtyard", WIDTH), 0)
    sunrise = np.maximum(data.load_world("sunrise", WIDTH), 0)
    forest = np.maximum(data.load_world("forest", WIDTH), 0)
    sunset = np.maximum(data.load_world("sunset", WIDTH), 0)
    rng = np.random.default_rng(14)
    out = {}
    for name, image in (("courtyard", courtyard), ("sunrise", sunrise)):
        for rate in (0.5, 1.0, 2.0):
            out[f"{name}, rotation {rate:g}°/frame"] = (data.rotation_frames(image, frames, rate), rotation_z(rate))
    out["cross-fade forest → sunset, 40 frames"] = (data.crossfade_frames(forest, sunset, frames), np.eye(3))
    factors = rng.uniform(0.98, 1.02, frames)
    out["courtyard, ±2% exposure noise"] = ([(courtyard * f).astype(np.float32) for f in factors], np.eye(3))
    return out


def criteria(maps, motion, rig, normals, refs, median):
    """The four criteria of one rig over one sequence."""
    es = rig_irradiances(rig, normals)
    errors = np.array([rel_rmse(e, r) for e, r in zip(es, refs)])
    ratio = errors / median
    return {"worst ratio": float(ratio.max()), "mean error": float(errors.mean()),
            "median cut error": float(median.mean()), **steadiness(rig, motion, es, refs)}


def passes(c):
    return {"a": c["worst ratio"] <= 1.0, **steady(c)}


VARIANTS = {
    "default (followed, fitted)": {},
    "followed, no fit": {"fit_irradiance": False},
    "resampled, fitted": {"tracking": "RESAMPLE"},
    "before (resampled, no fit)": {"tracking": "RESAMPLE", "fit_irradiance": False},
}


def measure(seqs, normals):
    rows = {}
    for name, (maps, motion) in seqs.items():
        started = time.time()
        refs = [L.exact_irradiance(m, normals) for m in maps]
        median = []
        for m, r in zip(maps, refs):
            d, rgb, spread = median_cut_suns(m, COUNT)
            median.append(rel_rmse(L.irradiance(d, rgb, normals, spread=spread, sun_model=MODEL), r))
        median = np.array(median)
        for variant, options in VARIANTS.items():
            rig = build_rig(maps, **options)
            c = criteria(maps, motion, rig, normals, refs, median)
            rows[(name, variant)] = c
            print(f"  {name} / {variant}: " + ", ".join(f"{k} {v:.4g}" for k, v in c.items())
                  + "  " + str(passes(c)), flush=True)
        print(f"  ({time.time() - started:.0f} s)", flush=True)
    return rows


def references(maps, normals):
    """Each frame's exact irradiance and median cut's error on it."""
    refs, median = [], []
    for m in maps:
        ref = L.exact_irradiance(m, normals)
        d, rgb, spread = median_cut_suns(m, COUNT)
        refs.append(ref)
        median.append(rel_rmse(L.irradiance(d, rgb, normals, spread=spread, sun_model=MODEL), ref))
    return refs, median


def per_frame_ratio(maps, normals, refs, median, **options):
    """Each frame's irradiance error / median cut's on that frame."""
    rig = build_rig(maps, **options)
    return [rel_rmse(L.irradiance(rig["directions"][t], rig["rgb"][t], normals, spread=rig["spread"][t],
                                  sun_model=MODEL), refs[t]) / median[t] for t in range(len(maps))]


CUT_VARIANTS = {
    "default (filtered shot by shot)": {},
    "default, unfiltered": {"temporal_filter": False},
    "resampled, filtered across the cut (before)": {"tracking": "RESAMPLE", "fit_irradiance": False},
}


def delay_cost(normals, frames=24):
    """What the temporal filter costs at a cut (12 frames of forest, then 12 of
    sunset) and at the first and last frames of a sunrise turning 1°/frame."""
    forest = np.maximum(data.load_world("forest", WIDTH), 0)
    sunset = np.maximum(data.load_world("sunset", WIDTH), 0)
    cut = [forest] * (frames // 2) + [sunset] * (frames - frames // 2)
    turning = data.rotation_frames(np.maximum(data.load_world("sunrise", WIDTH), 0), frames, 1.0)
    cut_refs, turning_refs = references(cut, normals), references(turning, normals)
    return {"cut": {k: per_frame_ratio(cut, normals, *cut_refs, **o) for k, o in CUT_VARIANTS.items()},
            "ends": {k: per_frame_ratio(turning, normals, *turning_refs, **o)
                     for k, o in list(CUT_VARIANTS.items())[:2]}}


def cost_at_2048(frames=6):
    """Seconds per frame of the default rig and of the rig before issue #14 on
    2048x1024 maps (the add-on's working width; courtyard doubled), turning
    1° per frame, alternated A/B/A/B in the same run, under the lock given
    (--lock PATH or $PENUMBRA_BENCH_LOCK)."""
    big = np.repeat(np.repeat(np.maximum(data.load_world("courtyard"), 0), 2, axis=0), 2, axis=1)
    maps = data.rotation_frames(big, frames, 1.0)
    times = {k: [] for k in ("default (followed, fitted)", "before (resampled, no fit)")}
    with locked(lock_path(sys.argv)):
        load = os.getloadavg()[0]
        for _ in range(2):
            for label in times:
                t0 = time.time()
                build_rig(maps, **VARIANTS[label])
                times[label].append((time.time() - t0) / frames)
    return {k: min(v) for k, v in times.items()}, load


def plot(delays, path):
    panels = []
    for kind, title in (("cut", "a cut between frames 11 and 12"), ("ends", "sunrise turning 1°/frame: the ends")):
        series = [{"name": label, "xs": list(range(len(v))), "ys": v, "colour": colour}
                  for (label, v), colour in zip(delays[kind].items(), ("#27c", "#2a2", "#c33"))]
        series.append({"name": "median cut", "xs": [0, len(series[0]["ys"]) - 1], "ys": [1.0, 1.0],
                       "colour": "#000"})
        panels.append({"title": title, "xs": series[0]["xs"], "logy": True, "xlabel": "frame",
                       "series": series})
    svg_plot.figure(panels, path, columns=2, caption="Irradiance error / median cut's on each frame, 64 lights")


def section(rows, delays, seconds):
    names = list(dict.fromkeys(name for name, _ in rows))
    lines = [SECTION, "",
             f"Written by `bench/lights_video_benchmark.py` ({time.strftime('%Y-%m-%d')}, {seconds:.0f} s, load "
             f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores). Sequences of {WIDTH}x{WIDTH // 2} maps made from "
             "the bundled HDRIs, 40 frames each; rigs of "
             f"{COUNT} lights built by `RigBuilder` with the add-on's settings at {FPS:g} fps, suns drawn as "
             "Blender 4.5 / 5.x draws them. (a) worst per-frame irradiance error / median cut's on that frame "
             "(≤ 1); (b) flux-weighted 95th percentile of the lights' steps between frames, the map's rotation "
             "removed (< 1°); (c) steps over 5° by lights with ≥ 1% of the flux (none); (d) the rig's mean "
             "frame-to-frame irradiance change / the map's (≤ 1.1). `resampled`: light k = Halton point k through "
             "each frame's CDF (the tracking before issue #14); `before`: that without the fit, the rig before "
             "issue #14 except that each frame keeps its own brightness, as every rig here does (the rig before "
             "issue #14 low-passed it, `filter_brightness`).", "",
             "| sequence | rig | (a) worst error / median cut | (b) p95 step | (c) jumps > 5° (largest step of a "
             "≥ 1% light) | (d) flicker / map's |",
             "|---|---|---|---|---|---|"]
    for name in names:
        for variant in VARIANTS:
            c = rows[(name, variant)]
            ok = passes(c)
            mark = {k: "PASS" if v else "FAIL" for k, v in ok.items()}
            lines.append(f"| {name} | {variant} | {c['worst ratio']:.2f}× {mark['a']} | {c['p95 step']:.2f}° "
                         f"{mark['b']} | {c['jumps']} ({c['largest big step']:.1f}°) {mark['c']} | "
                         f"{c['flicker'] / c['map flicker']:.2f}× {mark['d']} |")
    cuts, ends = delays["cut"], delays["ends"]
    if delays.get("cost"):
        cost, load = delays["cost"]
        base = cost["before (resampled, no fit)"]
        lines += ["", "**Cost at the add-on's working width.** 2048x1024 maps (courtyard doubled) turning 1° per "
                  "frame, 6 frames, the better of two alternated runs: " + ", ".join(
                      f"{k} {v:.2f} s per frame ({v / base:.2f}×)" for k, v in cost.items()) +
                  f" (load {load:.1f} when the timing started)."]
    else:
        lines += ["", "**Cost at the add-on's working width:** not measured in this run (`--no-timing`)."]
    lines += ["", "**The filter's delay at a cut and at the ends.** Per-frame irradiance error / median cut's on that "
              "frame. A cut: 12 frames of forest, then 12 of sunset (the cut between frames 11 and 12); the rig "
              "detects it (no rotation explains the change) and starts afresh, and the filter works shot by shot; "
              "the paper's way blends light k of one shot with light k of the other for the filter's half-width "
              "(6 frames at 24 fps: 13 taps) on each side. Plot: [video_delay.svg](lights/video_delay.svg).", "",
              "| rig | " + " | ".join(str(t) for t in range(len(next(iter(cuts.values()))))) + " |",
              "|---|" + "---|" * len(next(iter(cuts.values())))]
    for label, values in cuts.items():
        lines.append(f"| {label} | " + " | ".join(f"{v:.2f}" for v in values) + " |")
    lines += ["", "The ends: sunrise turning 1° per frame, 24 frames; the window shrinks symmetrically near the "
              "first and last frames, so a steadily moving light stays where it is:", "",
              "| rig | " + " | ".join(str(t) for t in range(len(next(iter(ends.values()))))) + " |",
              "|---|" + "---|" * len(next(iter(ends.values())))]
    for label, values in ends.items():
        lines.append(f"| {label} | " + " | ".join(f"{v:.2f}" for v in values) + " |")
    return lines + [""]


def run(timing=True):
    started = time.time()
    normals = _penumbra.sh.fibonacci_directions(1000)
    rows = measure(sequences(), normals)
    delays = delay_cost(normals)
    for kind, rows_ in delays.items():
        print(f"  {kind}:", {k: [round(v, 2) for v in vs] for k, vs in rows_.items()}, flush=True)
    plot(delays, os.path.join(ROOT, "docs", "lights", "video_delay.svg"))
    if timing:
        delays["cost"] = cost_at_2048()
        print("  cost:", delays["cost"], flush=True)
    return section(rows, delays, time.time() - started)


if __name__ == "__main__":
    path = os.path.join(ROOT, "docs", "lights-benchmark.md")
    write_section(path, SECTION, "\n" + "\n".join(run(timing="--no-timing" not in sys.argv[1:])))
    print(f"wrote {path}")
