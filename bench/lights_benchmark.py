#!/usr/bin/env python3
"""Light-rig accuracy and temporal flicker (not a test; `make bench`).

Accuracy: irradiance relative RMSE over 1000 Fibonacci normals against the
exact irradiance of the full map (Σ L Ω max(0, n·ω) over every pixel), for
Blender's eight bundled HDRIs at 1024x512, N = 4 ... 1024, geometric mean
over the maps. Baseline in the same run: Debevec's median-cut light-probe
sampling (2005) in numpy (bench/helpers/median_cut.py). RMSE definition:
sqrt(Σ_n ΔY²) / sqrt(Σ_n Y_ref²) on luminance.

Flicker: slowly rotating map (0.5°/frame) and a map with 100 Hz mains flicker
at 21 fps plus sensor noise; per frame the relative RMS change of irradiance
on 200 normals between consecutive frames, minus nothing (the reference's own
change is printed beside it). Variants (FLICKER_VARIANTS): the default rig
(followed, fitted, filtered, each frame its own brightness), the same with
the brightness low-passed too (the paper's), the rig before issue #14
(resampled, no fit, filtered), and lights resampled per frame without
tracking (a fresh Cranley–Patterson shift of the points each frame, so no
light keeps its place).

Writes docs/lights-benchmark.md, keeping its "Irradiance fit" and "Video"
sections, which bench/lights_fit_benchmark.py and lights_video_benchmark.py
write, and its "Cycles at equal time" section, which `--equal-time` alone
writes (issue #26 item 5, bench/blender_scripts/lights_equal_time_render.py:
the World and a 64-sun rig rendered by Cycles for the same time)."""

import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench import lights_fit_benchmark, lights_video_benchmark  # noqa: E402  (their sections' headings)
from bench.helpers import test_videos as data  # noqa: E402
from bench.helpers.doc_section import write_section  # noqa: E402
from bench.helpers.median_cut import median_cut  # noqa: E402
from bench.helpers.metrics import rel_rmse  # noqa: E402
from bench.helpers.paths import ROOT, compiled_core  # noqa: E402
from bench.helpers.result_line import only_result  # noqa: E402

_penumbra = compiled_core()

COUNTS = (4, 16, 64, 256, 1024)


def accuracy(maps, normals):
    # The region and equal rows without the irradiance fit (LightOptions'
    # default since issue #14); the fit's own row fits and is measured as
    # point lights, as the rest of this table (bench/lights_fit_benchmark.py
    # measures it drawn as suns). Above 256 lights the fit is not run.
    plain = dict(fit_irradiance=False)
    variants = {
        "median cut (Debevec 2005)": None,
        "paper: equal power, Havran": dict(power="EQUAL", sampler="HAVRAN", **plain),
        "equal power, standard": dict(power="EQUAL", sampler="STANDARD", **plain),
        "equal power, Havran, blue noise": dict(power="EQUAL", sampler="HAVRAN", blue_noise=True, **plain),
        "region power, Havran": dict(power="REGION", sampler="HAVRAN", **plain),
        "region power, standard": dict(power="REGION", sampler="STANDARD", **plain),
        "region power, Havran, blue noise": dict(power="REGION", sampler="HAVRAN", blue_noise=True, **plain),
        "region power + irradiance fit (default; N ≤ 256)": dict(power="REGION", sampler="HAVRAN",
                                                                 fit_irradiance=True, sun_model="POINT"),
        "region, 4N lights clustered to <= N": "cluster",
    }
    table = {name: {} for name in variants}
    for name, kind in variants.items():
        for n in COUNTS:
            logs = []
            for image, ref in maps:
                if kind is None:
                    d, rgb = median_cut(image, n)
                elif kind == "cluster":
                    lights = _penumbra.lights.frame_lights(image, count=min(4 * n, 4096), max_width=0,
                                                           fit_irradiance=False)
                    c = _penumbra.lights.cluster(lights["directions"], lights["rgb"], max_clusters=n)
                    d, rgb = c["directions"], c["rgb"]
                else:
                    lights = _penumbra.lights.frame_lights(image, count=n, max_width=0, **kind)
                    d, rgb = lights["directions"], lights["rgb"]
                logs.append(math.log(rel_rmse(_penumbra.lights.irradiance(d, rgb, normals), ref)))
            table[name][n] = math.exp(np.mean(logs))
        print(f"  {name}: " + ", ".join(f"N={n} {100 * table[name][n]:.2f}%" for n in COUNTS), flush=True)
    return table


FLICKER_VARIANTS = {
    "default (followed, fitted, filtered)": {},
    "filter brightness too (the paper's)": {"filter_brightness": True},
    "resampled, filtered (before issue #14)": {"tracking": "RESAMPLE", "fit_irradiance": False,
                                               "filter_brightness": True},
}


def flicker_of(sequence, normals, rig_kind, fps):
    """Mean relative RMS frame-to-frame irradiance change of the rig's suns (4.x cone)."""
    n = 64
    if rig_kind == "untracked":
        rng = np.random.default_rng(7)
        es = []
        for f in sequence:
            l = _penumbra.lights.frame_lights(f, count=n, shift=tuple(rng.random(2)), fit_irradiance=False)
            es.append(_penumbra.lights.irradiance(l["directions"], l["rgb"], normals, spread=l["spread"]))
    elif rig_kind == "reference":
        es = [_penumbra.lights.exact_irradiance(f, normals) for f in sequence]
    else:
        b = _penumbra.lights.RigBuilder(count=n, frames_per_second=fps, **FLICKER_VARIANTS[rig_kind])
        for f in sequence:
            b.add_frame(f)
        rig = b.finish()
        es = [_penumbra.lights.irradiance(rig["directions"][t], rig["rgb"][t], normals, spread=rig["spread"][t])
              for t in range(len(sequence))]
    changes = [rel_rmse(b, a) for a, b in zip(es, es[1:])]
    return float(np.mean(changes[4:-4]))


SHADOW_COUNTS = (16, 64, 256)
SHADOW_SPP = 128


def _bpy_result(script_name, args, what, timeout):
    """The "RESULT {json}" line of bench/blender_scripts/<script_name> run in
    the bpy 4.5 module (a fresh process) with a temporary folder and `args`."""
    import subprocess
    import tempfile
    python = os.path.join(ROOT, ".venv", "bin", "python")
    script = os.path.join(ROOT, "bench", "blender_scripts", script_name)
    with tempfile.TemporaryDirectory(prefix="penumbra_lights_") as tmp:
        res = subprocess.run([python, script, tmp, *args], capture_output=True, text=True, timeout=timeout)
        try:
            return only_result(res, exit_zero=True, tail=3000)
        except RuntimeError as failure:
            raise RuntimeError(f"the {what} failed: {failure}") from None


def shadowed_comparison():
    """Relative RMSE of Cycles renders lit by rigs against the World-lit render."""
    return _bpy_result("lights_shadowed_render.py", [",".join(str(n) for n in SHADOW_COUNTS), str(SHADOW_SPP)],
                       "shadowed comparison", 1200)


EQUAL_TIME_SECTION = "## Cycles at equal time (issue #26 item 5)"
EQUAL_TIME_SUNS = 64
EQUAL_TIME_REFERENCE_SPP = 1024  # the reference has 2048; 1024 keeps the run near 3 minutes here
EQUAL_TIME_BUDGETS_SPP = (32, 128)  # the World's samples that set each time budget


def equal_time_comparison():
    """The World and a rig of EQUAL_TIME_SUNS suns at equal Cycles render
    time (bench/blender_scripts/lights_equal_time_render.py)."""
    return _bpy_result("lights_equal_time_render.py",
                       [str(EQUAL_TIME_SUNS), str(EQUAL_TIME_REFERENCE_SPP),
                        ",".join(str(n) for n in EQUAL_TIME_BUDGETS_SPP)], "equal-time comparison", 1800)


def _time_for_world_noise(row, world):
    """The render time a lighting needs for the World's noise, in units of
    the World's time (Monte Carlo noise ∝ 1/√time)."""
    return (row["noise"] / world["noise"]) ** 2 * row["seconds"] / world["seconds"]


def equal_time_section(result, seconds):
    """The section's lines: per budget, each lighting's samples, time and
    error against the reference, and the time the rig needs for the World's
    noise (noise ∝ 1/√time)."""
    world_reference_noise = result["budgets"][-1]["rows"]["World"]["noise"] * math.sqrt(
        result["budgets"][-1]["budget_spp"] / result["reference_spp"])
    lines = [EQUAL_TIME_SECTION, "",
             f"Written by `bench/lights_benchmark.py --equal-time` ({time.strftime('%Y-%m-%d')}, {seconds:.0f} s, "
             f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores). The scene of the shadowed comparison "
             f"(sunrise.exr, a sphere on a plane, 128x96, Cycles on the CPU, no denoising, bpy 4.5) on "
             f"{result['threads']} threads, lit by the World and by the default rig of {result['count']} suns "
             "(built for Cycles, World strength 0), the rig with Blender's light tree on (the factory setting) "
             "and off. Each lighting's render time was fitted as a + b·spp from renders of 8 and 64 samples "
             "after a warm-up; each budget is the World's time at the samples named, and each lighting renders "
             "with the samples that fill it, with two seeds. Time is the render's CPU seconds (all threads of "
             "the process): on this shared machine wall seconds measure the other jobs' load (they are given "
             "too). "
             f"Error = RMS of the luminance difference to a World render of {result['reference_spp']} samples "
             f"(not the issue's 2048, for time; its own noise is about {100 * world_reference_noise:.1f} %, "
             "included in every error) / its mean, the mean of the two seeds; noise = one render's own (the "
             "two seeds' RMS difference / √2); mean = mean luminance / the reference's. `time for the World's "
             "noise` = (noise / the World's noise)² × CPU s / the World's CPU s: the time this lighting needs "
             "to be as clean as the World is in the budget, in the World's times.", "",
             "| budget (World spp) | lit by | spp | CPU s | wall s | error | noise | mean | time for the World's "
             "noise |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for budget in result["budgets"]:
        world = budget["rows"]["World"]
        for kind, row in budget["rows"].items():
            needed = _time_for_world_noise(row, world)
            lines.append(f"| {budget['budget_spp']} ({budget['budget_seconds']:.1f} CPU s) | {kind} | {row['spp']} "
                         f"| {row['seconds']:.1f} | {row['wall_seconds']:.1f} | {100 * row['error']:.2f}% "
                         f"| {100 * row['noise']:.2f}% | {row['mean']:.3f} | {needed:.1f}× |")
    last = result["budgets"][-1]["rows"]
    tree_on, tree_off = (last[k]["noise"] / last["World"]["noise"] for k in ("rig, light tree on",
                                                                             "rig, light tree off"))
    time_on, time_off = (_time_for_world_noise(last[k], last["World"]) for k in ("rig, light tree on",
                                                                                 "rig, light tree off"))
    verdict = "pays in noise" if min(time_on, time_off) > 1.0 else "gains in noise"
    lines += ["", f"What a user {verdict}, in Cycles: at equal time the {result['count']}-sun rig is "
              f"{tree_on:.1f}× as noisy as the World with the light tree and {tree_off:.1f}× without it "
              f"(largest budget), so it needs {time_on:.1f}× (light tree) or {time_off:.1f}× the "
              "World's render time for the World's noise. Cycles importance-samples the World map itself, "
              "where each sun of the rig is one more light to choose and to trace a shadow ray to. The rig "
              "is for what cannot sample the map (EEVEE's shadows, game engines through the JSON) and for "
              "lights edited one by one, not a faster Cycles render.", ""]
    return lines


def accuracy_section(table, seconds):
    """The page's title and the accuracy table."""
    title = ["# Light-rig benchmark results", "",
             f"Written by `bench/lights_benchmark.py` ({time.strftime('%Y-%m-%d')}, {seconds:.0f} s). "
             "Irradiance relative RMSE over 1000 normals against the exact irradiance of the full 1024x512 map, "
             "geometric mean over Blender's 8 bundled HDRIs (city, courtyard, forest, interior, night, studio, "
             "sunrise, sunset). Ratio = error / median cut's error at the same N (< 1: better than median cut).", "",
             "| method | " + " | ".join(f"N={n}" for n in COUNTS) + " |",
             "|---|" + "---|" * len(COUNTS)]
    base = table["median cut (Debevec 2005)"]
    for name, row in table.items():
        cells = [f"{100 * row[n]:.2f}% ({row[n] / base[n]:.2f}×)" for n in COUNTS]
        title.append(f"| {name} | " + " | ".join(cells) + " |")
    return title


def flicker_section(flicker):
    """The section "Temporal flicker"."""
    flicker_lines = [
        "", "## Temporal flicker", "",
        "Mean relative RMS change of irradiance on 200 normals between consecutive frames, 64 lights drawn as "
        "Blender 4.x suns, forest.exr at 256x128, 40 frames (the first and last 4 frame pairs left out). "
        "`reference` is the map's own change (what a perfect rig would show). Since issue #14 a rig keeps "
        "each frame's own brightness unless asked to filter it (`filter_brightness`, the add-on's "
        "Temporal > Brightness): the default follows a lamp's flicker as the map does; the paper's way "
        "removes it, and with it the source's real exposure changes. The video benchmark below has the "
        "criteria of issue #14 goal 2.", "",
        "| sequence | reference | " + " | ".join(FLICKER_VARIANTS) + " | resampled per frame, untracked |",
        "|---|---|" + "---|" * len(FLICKER_VARIANTS) + "---|"]
    for name, row in flicker.items():
        cells = [f"{100 * row[k]:.3f}%" for k in ("reference", *FLICKER_VARIANTS, "untracked")]
        flicker_lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return flicker_lines


def shadowed_section(shadows):
    """The section "Shadowed comparison (Cycles)"."""
    shadow_lines = [
        "", "## Shadowed comparison (Cycles)", "",
        "A sphere on a plane, both of one Principled BSDF at Blender's defaults "
        "(`examples/scenes/light_rig_scene.py`), under Blender's `sunrise.exr` (its sun casts a visible shadow), "
        "Cycles on the "
        f"CPU, 128x96 pixels, {SHADOW_SPP} samples, denoising off, bpy 4.5; rendered lit by the World "
        "(reference), by the World again with another seed (the noise floor: what two equally correct "
        "renders differ by), and by rigs of N suns built from the World by `penumbra.build_light_rig` "
        "(region powers, Havran; World strength 0). Error = RMS of the luminance difference over all "
        "pixels / mean reference luminance. Pictures: [World](lights/render_world.png), "
        "[64 suns](lights/render_rig_64.png).", "",
        "The rig's own noise is the same error between two seeds of the rig render; "
        "`bias` = sqrt(max(0, RMSE² − (noise_World² + noise_rig²)/2)) estimates the part that is not Monte "
        "Carlo noise. `mean` = mean luminance of the render / the World render's (a scale error shows "
        "here).", "",
        "Two Cycles facts the suns are written for (docs/lights.md, \"Suns in Cycles\"): a sun whose angle "
        "is positive but below ~1e-10 rad renders black (before the fix, a one-pixel region's rounding-noise "
        "radius of 1.6e-16 rad put out one of the four suns standing for the map's sun (11% of the flux): 17.6% error, mean 0.90), and "
        "Blender 4.x's wide suns carry strength·2/(1 + cos h) of ∫L dω (before the fix, 16 suns with angles "
        "up to 142° rendered 13% too bright: 16.6%, mean 1.13).", "",
        "| lit by | relative RMSE vs World | ratio to the World's noise floor | rig's own noise | bias | mean |",
        "|---|---|---|---|---|---|",
        f"| World, other seed (noise floor) | {100 * shadows['noise']:.2f}% | 1.00× | – | – "
        f"| {shadows['noise mean']:.3f} |"]
    for n in SHADOW_COUNTS:
        e, noise = shadows[str(n)], shadows[f"{n} noise"]
        bias = math.sqrt(max(0.0, e * e - 0.5 * (shadows['noise'] ** 2 + noise ** 2)))
        shadow_lines.append(f"| {n} suns | {100 * e:.2f}% | {e / shadows['noise']:.2f}× | {100 * noise:.2f}% "
                            f"| {100 * bias:.2f}% | {shadows[f'{n} mean']:.3f} |")
    return shadow_lines


def main():
    if "--equal-time" in sys.argv[1:]:
        started = time.time()
        result = equal_time_comparison()
        print("equal time:", result, flush=True)
        path = os.path.join(ROOT, "docs", "lights-benchmark.md")
        write_section(path, EQUAL_TIME_SECTION, "\n" + "\n".join(equal_time_section(result, time.time() - started)),
                      "## Shadowed comparison (EEVEE)")
        print(f"wrote {path}")
        return
    started = time.time()
    shadows = shadowed_comparison()
    print("shadowed comparison:", shadows, flush=True)
    normals = _penumbra.sh.fibonacci_directions(1000)
    maps = []
    for name in data.WORLDS:
        image = np.maximum(data.load_world(name), 0)  # 1024x512; negatives clamped as the tool does
        maps.append((image, _penumbra.lights.exact_irradiance(image, normals)))
    print("accuracy (geometric mean over 8 bundled HDRIs):", flush=True)
    table = accuracy(maps, normals)

    forest = np.maximum(data.load_world("forest", 256), 0)
    # 50 Hz mains lights lamps at 100 Hz; captured at 22 fps it aliases to
    # 10 Hz (stop band). Rotation and the cross-fade are slow (pass band).
    sunset = np.maximum(data.load_world("sunset", 256), 0)
    sequences = {
        "rotation 0.5°/frame (21 fps)": (data.rotation_frames(forest, 40, 0.5), 21.0),
        "cross-fade forest → sunset over 40 frames (21 fps)": (data.crossfade_frames(forest, sunset, 40), 21.0),
        "100 Hz lamp flicker at 22 fps (aliased to 10 Hz) + 2% noise":
            (data.noisy(data.flicker_frames(forest, 40, 22.0, 0.2), 0.02), 22.0),
    }
    fnormals = _penumbra.sh.fibonacci_directions(200)
    flicker = {}
    for name, (seq, fps) in sequences.items():
        flicker[name] = {k: flicker_of(seq, fnormals, k, fps)
                         for k in ("reference", *FLICKER_VARIANTS, "untracked")}
        print(f"  flicker {name}: {flicker[name]}", flush=True)

    title = accuracy_section(table, time.time() - started)
    flicker_lines = flicker_section(flicker)
    shadow_lines = shadowed_section(shadows)
    path = os.path.join(ROOT, "docs", "lights-benchmark.md")
    # Only this script's three sections are replaced: the page's others
    # (equal time, the fit, the video, the EEVEE drivers') are their own
    # scripts' and stay as they are.
    write_section(path, title[0], "\n".join(title) + "\n")
    write_section(path, flicker_lines[1], "\n".join(flicker_lines) + "\n", title[0])
    write_section(path, shadow_lines[1], "\n".join(shadow_lines) + "\n", flicker_lines[1])
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
