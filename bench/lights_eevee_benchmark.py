#!/usr/bin/env python3
"""Light rigs in EEVEE (issue #26, goals 1 and 2, and the shadow budget's
render time): five scenes, each a sphere on a plane, lit by Blender's
bundled sunrise, courtyard, sunset and night maps and by a map this
benchmark makes with two bright sources on opposite sides ("opposite"),
rendered by EEVEE in each Blender in ONE process (its shaders compile once):
  - Debian's Blender 3.4, headless under Xvfb: EEVEE Legacy;
  - the bpy 4.5 module (GPU context through EGL) and the bpy 5.2 module
    (after gpu.init()): EEVEE Next;
all on Mesa's llvmpipe (OpenGL on the CPU). EEVEE keeps its factory settings
except EEVEE_SAMPLES samples and a transparent film.

Reference: Cycles' World render (default bounces) at REFERENCE_SPP or more,
the mean of two seeds, rendered once per Blender (their Cycles differ, and
3.4's bundled maps are other files than 4.5's and 5.2's) and cached under
OUT/references/<Blender>/, reused by later runs. Baseline: EEVEE's World
render; from 4.2 the best of it alone and with the World's sun extraction
(sun_threshold in THRESHOLDS x sun_angle in ANGLES, its shadow on). The rig:
`penumbra.build_light_rig` with its defaults and target_renderer EEVEE,
World strength 0 for its renders.

Writes the section "Shadowed comparison (EEVEE)" of docs/lights-benchmark.md
and its pictures (docs/lights/eevee_<blender>_<scene>_*.png):

    .venv/bin/python bench/lights_eevee_benchmark.py [--blenders 3.4,5.2,4.5] [--time-limit S] [--resume]
        [--section-only] [--lock /work/bench.lock]

Each Blender's result is kept in docs/lights/eevee-results/result_<blender>.json
(committed); the section is written from every result there, so Blenders run
apart, in any session, publish together.
--time-limit S stops a Blender after S seconds and publishes the renders it
finished (goal 2 on every scene first); --resume then renders only the rest
(delete a render's .json in OUT/<blender> to render it again).
PENUMBRA_BENCH_QUICK=1: two scenes, few samples (a smoke test, not a result)."""

import json
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.doc_section import lock_path, locked, write_json, write_section  # noqa: E402
from bench.helpers.paths import BUILD, ROOT, compiled_core  # noqa: E402
from bench.helpers.result_line import last_result  # noqa: E402

DOC = os.path.join(ROOT, "docs", "lights-benchmark.md")
RENDER = os.path.join(ROOT, "bench", "blender_scripts", "lights_eevee_render.py")
PICTURES = os.path.join(ROOT, "docs", "lights")
RESULTS = os.path.join(PICTURES, "eevee-results")
QUICK = os.environ.get("PENUMBRA_BENCH_QUICK") == "1"
OUT = os.path.join(BUILD, "bench", "lights_eevee_quick" if QUICK else "lights_eevee")
# In the order rendered (a run stopped at its time limit has the first ones).
SCENES = ("sunrise", "opposite") if QUICK else ("sunrise", "opposite", "courtyard", "night", "sunset")
WIDTH, HEIGHT = 96, 72
EEVEE_SAMPLES = 2 if QUICK else 16
REFERENCE_SPP = 16 if QUICK else 4096
MAX_REFERENCE_SPP = 16 if QUICK else 16384
NOISE_LIMIT = 0.01  # the reference's two seeds differ by less (issue #26)
COUNTS = (32,) if QUICK else (16, 32, 64)  # goal 1
GOAL2_COUNT = 32
GOAL2_RATIO = 0.5  # the rig's error at most this times the baseline's
GOAL1_TOLERANCE = 0.02  # the rig's mean luminance within this of the reference's
THRESHOLDS = (1, 5, 20)  # world.sun_threshold of the 4.2+ baseline
ANGLES = (1, 10)  # world.sun_angle, degrees
SHADOW_BUDGET = 8
PICTURE_SCENES = ("sunrise", "opposite")
MARKER = "\n## Shadowed comparison (EEVEE)"
# How each Blender runs a script: the command before the script, and after it.
BLENDERS = {
    "3.4": (["xvfb-run", "-a", "blender", "-b", "--factory-startup", "--python"], ["--"]),
    "4.5": ([os.path.join(ROOT, ".venv", "bin", "python")], []),
    "5.2": ([os.path.join(ROOT, ".venv313", "bin", "python")], []),
}


def opposite_map(path, width=1024):
    """An equirectangular map (Blender's convention) of a dim sky (0.3 above
    the horizon, 0.1 below) and two bright discs (radius 3°, radiance 300) at
    35° elevation on opposite sides, across the camera's view: the case where
    one extracted sun, at the sources' mean direction, lands between them."""
    from bench.helpers.test_videos import directions
    d = directions(width // 2, width)
    image = np.where(d[..., 2:] > 0, 0.3, 0.1) * np.ones(3)
    e, a = math.radians(35), math.radians(45)
    for side in (1, -1):
        source = np.array([side * math.cos(e) * math.cos(a), side * math.cos(e) * math.sin(a), math.sin(e)])
        image[d @ source > math.cos(math.radians(3))] = 300.0
    compiled_core().image.write_exr(path, image.astype(np.float32), False)


def run_blender(tag, out, time_limit, script=RENDER):
    """One Blender's renders (`script`, by default bench/blender_scripts/lights_eevee_render.py,
    given OUT, the reference cache and the opposite map); stopped after
    `time_limit` seconds, its finished renders are the result (`stopped`),
    and a later run with --resume renders only the rest."""
    cache = os.path.join(OUT, "references", tag)
    os.makedirs(cache, exist_ok=True)
    before, after = BLENDERS[tag]
    command = ["nice", "-n", "5"] + before + [script] + after + [out, cache, os.path.join(OUT, "opposite.exr")]
    stem = os.path.splitext(os.path.basename(script))[0]
    log = os.path.join(OUT, f"log_{stem}_{tag}.txt")  # each render's line as it comes: a long run can be followed
    env = dict(os.environ, GALLIVM_PERF="nopt", LP_NUM_THREADS="2")
    earlier, earlier_load = 0.0, []  # the stopped run's, its renders reused
    if "--resume" in sys.argv:
        env["PENUMBRA_EEVEE_RESUME"] = "1"
        if os.path.exists(os.path.join(out, "partial.json")):
            with open(os.path.join(out, "partial.json")) as f:
                stopped = json.load(f)
            earlier, earlier_load = stopped.get("seconds", 0.0), stopped.get("load", [])
    with open(log, "w") as f:
        try:
            code = subprocess.run(command, stdout=f, stderr=subprocess.STDOUT, timeout=time_limit, env=env).returncode
        except subprocess.TimeoutExpired:
            code = None
    with open(log) as f:
        text = f.read()
    result = last_result(text) or {"ok": False}
    if code is None and os.path.exists(os.path.join(out, "partial.json")):
        with open(os.path.join(out, "partial.json")) as f:
            result = dict(json.load(f), ok=True, stopped=True)
    if not result["ok"]:
        print(text[-4000:], result.get("error", ""))
        sys.exit(f"the renders in Blender {tag} failed (log: {log})")
    return dict(result, tag=tag, date=time.strftime("%Y-%m-%d %H:%M"), quick=QUICK, earlier_seconds=earlier,
                earlier_load=earlier_load)


def baseline(entries):
    """(key, entry) of the baseline: the World render of least error."""
    return min(((k, e) for k, e in entries.items() if k == "world" or k.startswith("sun_")),
               key=lambda item: item[1]["error"])


def copy_pictures(result, out):
    for name in PICTURE_SCENES:
        entries = result["scenes"][name]
        if f"rig_{GOAL2_COUNT}" not in entries:
            continue
        for key, label in (("reference", "reference"), (baseline(entries)[0], "baseline"),
                           (f"rig_{GOAL2_COUNT}", f"rig_{GOAL2_COUNT}")):
            shutil.copyfile(os.path.join(out, f"{name}_{key}.png"),
                            os.path.join(PICTURES, f"eevee_{result['tag'].replace('.', '')}_{name}_{label}.png"))


def variant_label(key):
    if key == "world":
        return "World alone"
    threshold, angle = key[len("sun_t"):].split("_a")
    return f"sun extraction, threshold {threshold}, {angle}°"


def pct(value):
    return f"{100 * value:.2f}%"


def goal2_rows(result):
    """Rows of goal 2, and whether it holds on every scene (None: not every scene measured)."""
    rows, met = [], True
    for name, entries in result["scenes"].items():
        if f"rig_{GOAL2_COUNT}" not in entries:
            met = None if met is not False else met
            continue
        ref = entries["reference"]
        key, base = baseline(entries)
        rig = entries[f"rig_{GOAL2_COUNT}"]
        ratio = rig["error"] / base["error"]
        if ratio > GOAL2_RATIO:
            met = False
        rows.append(f"| {result['blender']} | {name} | {ref['spp']} | {pct(ref['noise'])} | "
                    f"{pct(entries['world']['error'])} | {variant_label(key)}: {pct(base['error'])} | "
                    f"{pct(rig['error'])} | {ratio:.3f} | {'yes' if ratio <= GOAL2_RATIO else '**no**'} |")
    return rows, met


def goal1_rows(result):
    """Rows of goal 1, and whether it holds (None: not every scene and count measured)."""
    rows, met = [], True
    for name, entries in result["scenes"].items():
        if "world" not in entries:
            met = None if met is not False else met
            continue
        means = [entries[f"rig_{n}"]["mean"] if f"rig_{n}" in entries else None for n in COUNTS]
        off = [m for m in means if m is not None and abs(m - 1) > GOAL1_TOLERANCE]
        verdict = "**no**" if off else ("yes" if None not in means else "–")
        if off:
            met = False
        elif None in means and met:
            met = None
        rows.append(f"| {result['blender']} | {name} | " +
                    " | ".join("–" if m is None else f"{m:.3f}" for m in means) +
                    f" | {entries['world']['mean']:.3f} | {verdict} |")
    return rows, met


def extraction_rows(result):
    rows = []
    for name, entries in result["scenes"].items():
        keys = [f"sun_t{t:g}_a{a:g}" for t in THRESHOLDS for a in ANGLES]
        if any(k in entries for k in keys):
            rows.append(f"| {result['blender']} | {name} | {pct(entries['world']['error'])} | " +
                        " | ".join(pct(entries[k]["error"]) if k in entries else "–" for k in keys) + " |")
    return rows


def budget_rows(result):
    rows = []
    for name, entries in result["scenes"].items():
        every, budget = entries.get(f"rig_{GOAL2_COUNT}"), entries.get(f"rig_{GOAL2_COUNT}_budget{SHADOW_BUDGET}")
        if not every or not budget:
            continue
        points = 100 * (budget["error"] - every["error"])
        rows.append(f"| {result['blender']} | {name} | {every['shadowed']} | {pct(every['error'])} | "
                    f"{every['seconds']:.1f} | {budget['shadowed']} | {pct(budget['error'])} | "
                    f"{budget['seconds']:.1f} | {points:+.2f} | {1 - budget['seconds'] / every['seconds']:+.0%} |")
    return rows


def budget_summary(result):
    """One line: the budget's error change and time saved, their range over the scenes."""
    pairs = [(e[f"rig_{GOAL2_COUNT}"], e[f"rig_{GOAL2_COUNT}_budget{SHADOW_BUDGET}"]) for e in result["scenes"].values()
             if f"rig_{GOAL2_COUNT}" in e and f"rig_{GOAL2_COUNT}_budget{SHADOW_BUDGET}" in e]
    if not pairs:
        return []
    points = [100 * (b["error"] - a["error"]) for a, b in pairs]
    saved = [1 - b["seconds"] / a["seconds"] for a, b in pairs]
    if all(a["shadowed"] == b["shadowed"] and a["error"] == b["error"] for a, b in pairs):
        return [f"- Blender {result['blender']}: the default rig is the budget's ({pairs[0][0]['shadowed']} "
                f"shadowed suns, the same error); render times differ by {min(saved):+.0%} to {max(saved):+.0%} "
                "between the two renders of one rig."]
    within = "no scene worse by more than 1 point" if max(points) <= 1 else "worse by more than 1 point on a scene"
    return [f"- Blender {result['blender']}: the budget's error is {min(points):+.2f} to {max(points):+.2f} points "
            f"from the all-shadowed rig's ({within}); render time saved {min(saved):+.0%} to "
            f"{max(saved):+.0%}, median {sorted(saved)[len(saved) // 2]:+.0%}."]


def verdict(met):
    return {True: "met", False: "not met", None: "not measured on every scene (see the tables)"}[met]


def run_facts(results):
    return "; ".join(f"Blender {r['blender']} ({r['engine']}): {r['seconds']:.0f} s"
                     + (f" (resumed: plus {r['earlier_seconds']:.0f} s of earlier runs whose finished renders it "
                        "reused)" if r.get("earlier_seconds") else "")
                     + f", ended {r['date']} UTC, load average {min(r['load'] + r.get('earlier_load', [])):.1f}–"
                     f"{max(r['load'] + r.get('earlier_load', [])):.1f} (1 min, sampled between scenes)"
                     for r in results)


def section(results):
    goal2, goal1, extraction, budget, verdicts = [], [], [], [], []
    for r in results:
        rows, met2 = goal2_rows(r)
        goal2 += rows
        rows, met1 = goal1_rows(r)
        goal1 += rows
        extraction += extraction_rows(r)
        budget += budget_rows(r)
        verdicts.append(f"- Blender {r['blender']} ({r['engine']}): goal 2 ({GOAL2_COUNT} suns, error ≤ "
                        f"{GOAL2_RATIO}× the baseline's on every scene) **{verdict(met2)}**; goal 1 (mean within "
                        f"{GOAL1_TOLERANCE:.0%} at {'/'.join(map(str, COUNTS))} suns on every scene) "
                        f"**{verdict(met1)}**."
                        + (" This run was stopped at its time limit: the tables show the renders it finished."
                           if r.get("stopped") else ""))
    missing = [tag for tag in BLENDERS if tag not in {r["tag"] for r in results}]
    pictures = ", ".join(
        f"Blender {r['blender']} {name}: " + ", ".join(
            f"[{label}](lights/eevee_{r['tag'].replace('.', '')}_{name}_{label}.png)"
            for label in ("reference", "baseline", f"rig_{GOAL2_COUNT}"))
        for r in results for name in PICTURE_SCENES if f"rig_{GOAL2_COUNT}" in r["scenes"][name])
    lines = [
        "",
        "## Shadowed comparison (EEVEE)" + (" (QUICK SMOKE TEST, NOT A RESULT)" if QUICK else ""),
        "",
        f"Written by `bench/lights_eevee_benchmark.py` (issue #26, goals 1 and 2). Five scenes, each a sphere on a "
        f"plane at {WIDTH}x{HEIGHT} with a transparent film, both of one Principled BSDF at each Blender's "
        "defaults (`examples/scenes/light_rig_scene.py: default_surface`: without a material, Cycles before 5.0 "
        "draws a grey diffuse, EEVEE this), lit by "
        "Blender's bundled sunrise, courtyard, sunset "
        "and night maps (each Blender's own files: 3.4's differ from 4.5's and 5.2's) and by `opposite`, a map the "
        "benchmark makes: a dim sky with two bright discs on opposite sides at 35° elevation. EEVEE: factory "
        f"settings except {EEVEE_SAMPLES} samples, every render of one Blender in one process, on Mesa's llvmpipe "
        "(OpenGL on the CPU; no GPU here). **Reference**: that Blender's Cycles World render with default "
        f"bounces, the mean of two seeds at `spp` samples ({REFERENCE_SPP} or more, doubled until the seeds "
        f"differ by less than {NOISE_LIMIT:.0%}); `noise` = RMS difference of the two seeds / their mean (the "
        "mean of both is about half as noisy). References are rendered once per Blender (their Cycles differ) "
        "and cached. **Error** = RMS of the luminance difference to the reference / its mean luminance; "
        "**mean** = mean luminance / the reference's. **Baseline**: EEVEE's World render; in 4.5 and 5.2 the "
        "best of it alone (`sun_threshold` 0) and with the World's sun extraction (`sun_threshold` ∈ "
        f"{{{', '.join(map(str, THRESHOLDS))}}} × `sun_angle` ∈ {{{', '.join(f'{a}°' for a in ANGLES)}}}, "
        "`use_sun_shadow` on). **Rig**: `penumbra.build_light_rig` with its defaults (the fitted rig) and "
        "`target_renderer='EEVEE'`, rendered with World strength 0 and whatever the operator set on its lights.",
        "",
        f"Runs: {run_facts(results)}. Renders took turns with other jobs on a shared 2-core machine (`nice -n 5`)."
        + (f" Not run: Blender {', '.join(missing)} (it did not fit this session's time); "
           f"`--blenders {','.join(missing)}` adds it to this section." if missing else ""),
        "",
    ] + verdicts + [
        "",
        "EEVEE lights from the World through a probe that casts no shadow: a small bright sun in the map also "
        "lights the plane inside the sphere's shadow. The World's sun extraction (4.2+) clamps what lies above "
        "its threshold into one sun at the mean direction of what it clamps, so with two opposite sources it "
        "puts one sun between them (`opposite`). The rig's suns cast the shadows themselves.",
        "",
        f"**Goal 2**: error against the reference, {GOAL2_COUNT} suns.",
        "",
        "| Blender | scene | reference spp | reference noise | EEVEE World alone | baseline (best) | "
        f"rig, {GOAL2_COUNT} suns | rig / baseline | ≤ {GOAL2_RATIO} |",
        "|---|---|---:|---:|---:|---|---:|---:|---|",
    ] + goal2 + [
        "",
        f"**Goal 1**: mean luminance / the reference's (goal: within {GOAL1_TOLERANCE:.0%}); EEVEE's World render "
        "beside it. EEVEE draws no bounce light from lamps (no baked probes, no ray tracing at factory "
        "settings); the reference has bounces. With Ray Tracing on: \"EEVEE Next with ray tracing\" below.",
        "",
        "| Blender | scene | " + " | ".join(f"rig, {n} suns" for n in COUNTS) + " | EEVEE World alone | within |",
        "|---|---|" + "---:|" * (len(COUNTS) + 1) + "---|",
    ] + goal1 + ([
        "",
        "The 4.2+ baseline's variants (error; threshold, angle):",
        "",
        "| Blender | scene | World alone | " + " | ".join(f"{t}, {a}°" for t in THRESHOLDS for a in ANGLES) + " |",
        "|---|---|---:|" + "---:|" * (len(THRESHOLDS) * len(ANGLES)),
    ] + extraction if extraction else []) + [
        "",
        f"**Shadow budget** (issue #26 item 3): the default {GOAL2_COUNT}-sun rig, every sun shadowed, against "
        f"`shadow_budget={SHADOW_BUDGET}`: the {SHADOW_BUDGET} strongest of the suns sharp enough to cast a "
        "visible shadow (at most 2·atan(1/2) ≈ 53° wide, docs/lights.md) keep theirs. EEVEE Legacy draws "
        "the shadows of at most 8 suns, so its default rig already gives them as a budget of 8 does "
        "(docs/lights.md, \"Shadow budget\"): there the two renders are the same rig. Each pair is rendered "
        "back to back; render times are single renders on the shared machine: differences of a few percent "
        "are noise.",
        "",
        "| Blender | scene | shadowed | error | render (s) | shadowed, budget | error, budget | render (s) | "
        "Δ error (points) | time saved |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ] + budget + [""] + [line for r in results for line in budget_summary(r)] + [
        "",
        f"Pictures: {pictures}.",
    ]
    return "\n".join(lines) + "\n"


def result_path(tag):
    """Where a Blender's result is kept: beside the page (committed), so that
    Blenders run in different sessions publish together; a quick run's in OUT."""
    return os.path.join(OUT if QUICK else RESULTS, f"result_{tag}.json")


def stored_results():
    found = []
    for tag in BLENDERS:
        path = result_path(tag)
        if os.path.exists(path):
            with open(path) as f:
                found.append(json.load(f))
    return found


def main():
    argv = sys.argv
    tags = argv[argv.index("--blenders") + 1].split(",") if "--blenders" in argv else list(BLENDERS)
    time_limit = float(argv[argv.index("--time-limit") + 1]) if "--time-limit" in argv else None
    if "--section-only" in argv:  # the stored results, published again (a changed table, no render)
        tags = []
    os.makedirs(OUT, exist_ok=True)
    if not os.path.exists(os.path.join(OUT, "opposite.exr")):
        opposite_map(os.path.join(OUT, "opposite.exr"))
    with locked(lock_path(argv)):
        for tag in tags:
            out = os.path.join(OUT, tag)
            os.makedirs(out, exist_ok=True)
            result = run_blender(tag, out, time_limit)
            os.makedirs(os.path.dirname(result_path(tag)), exist_ok=True)
            write_json(result_path(tag), result)
            print(f"Blender {tag}: {result['seconds']:.0f} s", flush=True)
            if not QUICK:
                copy_pictures(result, out)
    write_section(DOC, MARKER, section(stored_results()), "\n## Shadowed comparison (Cycles)")
    print("wrote", DOC)


if __name__ == "__main__":
    main()
