#!/usr/bin/env python3
"""What EEVEE Next's ray tracing gives a light rig, beside issue #26's goals
(which judge factory render settings): the EEVEE benchmark's scenes and
references (bench/lights_eevee_benchmark.py, run first: its references and
stored results are read) rendered in bpy 4.5 and 5.2 with ray tracing off,
on, and on with a finer Fast GI (bench/blender_scripts/lights_eevee_raytracing.py).
Keeps each Blender's result in docs/lights/eevee-results/raytracing_<blender>.json
and writes the section "EEVEE Next with ray tracing" of docs/lights-benchmark.md:

    .venv/bin/python bench/lights_eevee_raytracing_benchmark.py [--blenders 5.2,4.5] [--section-only]

PENUMBRA_BENCH_QUICK=1: the EEVEE benchmark's quick scenes and results (a
smoke test, not a result; run that benchmark quick first)."""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.doc_section import write_json, write_section  # noqa: E402
from bench.helpers.paths import ROOT  # noqa: E402
from bench.lights_eevee_benchmark import (  # noqa: E402
    DOC, GOAL2_COUNT, OUT, QUICK, result_path, run_blender, variant_label)

SCRIPT = os.path.join(ROOT, "bench", "blender_scripts", "lights_eevee_raytracing.py")
TAGS = ("4.5", "5.2")  # EEVEE Next: 3.4's EEVEE Legacy has no ray tracing
MARKER = "\n## EEVEE Next with ray tracing"
TRACING = (("off", "off (factory)"), ("on", "on"), ("fine", "on, finer Fast GI"))
LIGHTING = (("baseline", "baseline"), ("rig", f"rig, {GOAL2_COUNT} suns"), ("budget8", "rig, shadow budget 8"))


def stored_path(tag):
    """Beside the EEVEE benchmark's result (committed; a quick run's in its OUT)."""
    return os.path.join(os.path.dirname(result_path(tag)), f"raytracing_{tag}.json")


def rows(result):
    """Error and mean rows of one Blender's result."""
    errors, means = [], []
    for name, entries in result["scenes"].items():
        head = f"| {result['blender']} | {name} |"
        errors.append(head + " " + variant_label(entries["baseline_key"]) + " | " + " | ".join(
            f"{100 * entries[f'{light}_{trace}']['error']:.1f}%" for light, _ in LIGHTING for trace, _ in TRACING)
            + f" | {best_ratio(entries):.2f} |")
        means.append(head + " " + " | ".join(f"{entries[f'{light}_{trace}']['mean']:.3f}"
                                             for light, _ in LIGHTING[1:] for trace, _ in TRACING) + " |")
    return errors, means


def best_ratio(entries, rig="budget8_fine"):
    """A rig's error over the best baseline render, ray traced or not."""
    return entries[rig]["error"] / min(entries[f"baseline_{t}"]["error"] for t, _ in TRACING)


def summary_rows(results):
    """Per rig and tracing, on how many scenes of each Blender issue #26's two goals would hold."""
    lines = []
    for light, light_label in LIGHTING[1:]:
        for trace, trace_label in TRACING:
            key, cells = f"{light}_{trace}", []
            for r in results:
                scenes = list(r["scenes"].values())
                cells.append(f"{sum(best_ratio(e, key) <= 0.5 for e in scenes)} of {len(scenes)}")
                cells.append(f"{sum(abs(e[key]['mean'] - 1) <= 0.02 for e in scenes)} of {len(scenes)}")
            lines.append(f"| {light_label} | {trace_label} | " + " | ".join(cells) + " |")
    return lines


def seconds(results):
    """Mean render seconds per rig and tracing over every scene and Blender."""
    cells = []
    for light, light_label in LIGHTING[1:]:
        for trace, trace_label in TRACING:
            values = [e[f"{light}_{trace}"]["seconds"] for r in results for e in r["scenes"].values()]
            cells.append(f"{light_label}, ray tracing {trace_label}: {sum(values) / len(values):.1f} s")
    return "; ".join(cells)


def stale(result):
    """Whether a Blender's run was measured against other references than
    the EEVEE benchmark's current ones (rendered again since: their noise differs)."""
    with open(result_path(result["tag"])) as f:
        current = json.load(f)["scenes"]
    return any(abs(e["reference"]["noise"] - current[name]["reference"]["noise"]) > 1e-9
               for name, e in result["scenes"].items())


def stale_note(results):
    old = [r["blender"] for r in results if stale(r)]
    if not old:
        return []
    return ["", f"**Not yet measured again: Blender {', '.join(old)}.** Its run above used the EEVEE benchmark's "
            "earlier references, rendered before both objects were given one explicit surface (in Blender before "
            "5.0 Cycles drew an object without a material as a grey diffuse, EEVEE as a Principled BSDF; section "
            "\"Shadowed comparison (EEVEE)\"). Its figures compare those two surfaces and stand until this "
            "benchmark runs again."]


def section(results):
    errors, means = zip(*(rows(r) for r in results)) if results else ((), ())
    columns = " | ".join(f"{light_label}: {trace_label}" for _, light_label in LIGHTING for _, trace_label in TRACING)
    return "\n".join([
        "", MARKER.strip() + (" (QUICK SMOKE TEST, NOT A RESULT)" if QUICK else ""), "",
        "Written by `bench/lights_eevee_raytracing_benchmark.py`. Outside issue #26's goals, which judge EEVEE at "
        "factory settings with only the rig's own lights set by the operator: what a user gains by turning on "
        "**Ray Tracing** (Render Properties; `scene.eevee.use_raytracing`) for the rig. With it, EEVEE Next "
        "gathers lamp light bounced between surfaces on screen (Fast GI, method Global Illumination, its "
        "factory setting), which the reference (Cycles, default bounces) has and factory EEVEE lacks: the rig "
        "is otherwise close to Cycles' direct light (docs/lights.md, goal 1). The benchmark's five scenes and "
        "references, 96x72, 16 samples; ray tracing off, on with factory Fast GI, and on with a finer Fast GI "
        "(`fast_gi_resolution` 1, 16 steps, quality 1). The baseline is the EEVEE benchmark's best World render "
        "for the scene, rendered here in each tracing mode.",
        "",
        "Runs: " + "; ".join(f"Blender {r['blender']}: {r['seconds']:.0f} s, ended {r['date']} UTC, load average "
                             f"{min(r['load']):.1f}–{max(r['load']):.1f}" for r in results) + ".",
    ] + stale_note(results) + [
        "",
        "Error against the reference (RMS of the luminance difference / its mean); the last column, the "
        "budget rig with the finer Fast GI over the best of the three baseline renders (issue #26 asks ≤ 0.5 "
        "at factory settings):",
        "",
        "| Blender | scene | baseline variant | " + columns + " | budget, finer / best baseline |",
        "|---|---|---|" + "---:|" * (len(LIGHTING) * len(TRACING) + 1),
    ] + [line for block in errors for line in block] + [
        "",
        "On how many scenes issue #26's goals (at 32 suns) would hold with ray tracing allowed: the error at "
        "most 0.5× the best baseline render (ray traced or not), the mean within 2% of the reference's:",
        "",
        "| rig | ray tracing | " + " | ".join(f"{r['blender']}: error ≤ 0.5× | {r['blender']}: mean within 2%"
                                             for r in results) + " |",
        "|---|---|" + "---:|" * (2 * len(results)),
    ] + summary_rows(results) + [
        "",
        "Mean luminance / the reference's:",
        "",
        "| Blender | scene | " + " | ".join(f"{light_label}: {trace_label}" for _, light_label in LIGHTING[1:]
                                          for _, trace_label in TRACING) + " |",
        "|---|---|" + "---:|" * ((len(LIGHTING) - 1) * len(TRACING)),
    ] + [line for block in means for line in block] + [
        "",
        "Render seconds, mean over the scenes and Blenders (shared 2-core machine, GALLIVM_PERF=nopt): "
        + seconds(results) + ".",
        "",
    ])


def main():
    argv = sys.argv
    tags = argv[argv.index("--blenders") + 1].split(",") if "--blenders" in argv else list(TAGS)
    for tag in ([] if "--section-only" in argv else tags):
        out = os.path.join(OUT, f"raytracing_{tag}")
        os.makedirs(out, exist_ok=True)
        write_json(stored_path(tag), run_blender(tag, out, None, SCRIPT))
    results = []
    for tag in TAGS:
        if os.path.exists(stored_path(tag)):
            with open(stored_path(tag)) as f:
                results.append(json.load(f))
    write_section(DOC, MARKER, section(results), "\n## Shadowed comparison (EEVEE)")
    print("wrote", DOC)


if __name__ == "__main__":
    main()
