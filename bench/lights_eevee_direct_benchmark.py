#!/usr/bin/env python3
"""Issue #26's goals against Cycles' direct light: the EEVEE benchmark's
renders (bench/lights_eevee_benchmark.py, run first: its renders in
build/bench/lights_eevee/<blender> and its stored results are read) measured
against Cycles' World render without bounces, the light EEVEE draws from
lamps at factory settings, beside the issue's reference with bounces
(bench/blender_scripts/lights_eevee_direct.py). Keeps each Blender's result
in docs/lights/eevee-results/direct_<blender>.json and writes the section
"Against Cycles' direct light" of docs/lights-benchmark.md:

    .venv/bin/python bench/lights_eevee_direct_benchmark.py [--blenders 3.4,4.5,5.2] [--shadow-pool] [--section-only]

--shadow-pool: instead, EEVEE Next's shadow pool (4.5, 5.2): the 32- and
64-sun rigs with the factory pool, the 64-sun rig with a larger pool and
with shadows on its 32 strongest suns (bench/blender_scripts/lights_eevee_shadow_pool.py),
kept in docs/lights/eevee-results/shadow_pool_<blender>.json.

Stops with an error when a render read no longer gives the benchmark's
published error against the issue's reference (the renders were made again
since, or by a quick run)."""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.doc_section import write_json, write_section  # noqa: E402
from bench.helpers.paths import ROOT  # noqa: E402
from bench.lights_eevee_benchmark import (  # noqa: E402
    BLENDERS, COUNTS, DOC, GOAL1_TOLERANCE, GOAL2_COUNT, GOAL2_RATIO, OUT, SHADOW_BUDGET, baseline, result_path,
    run_blender, variant_label)

SCRIPT = os.path.join(ROOT, "bench", "blender_scripts", "lights_eevee_direct.py")
POOL_SCRIPT = os.path.join(ROOT, "bench", "blender_scripts", "lights_eevee_shadow_pool.py")
POOL_TAGS = ("4.5", "5.2")  # EEVEE Next: EEVEE Legacy has no shadow pool
POOL_RENDERS = (("rig_32", "32 suns"), ("rig_64", "64 suns"), ("rig_64_pool_1024", "64 suns, pool 1024 MB"),
                ("rig_64_strongest_32", "64 suns, 32 strongest shadowed"))
MARKER = "\n## Against Cycles' direct light"
RIG, BUDGET = f"rig_{GOAL2_COUNT}", f"rig_{GOAL2_COUNT}_budget{SHADOW_BUDGET}"


def stored_path(tag, kind="direct"):
    return os.path.join(os.path.dirname(result_path(tag)), f"{kind}_{tag}.json")


def check_renders(result, published):
    """The renders measured are the published ones: their errors against the issue's reference agree."""
    for name, entries in result["scenes"].items():
        for key, entry in entries.items():
            if key != "direct" and abs(entry["error_against_issue_reference"]
                                       - published["scenes"][name][key]["error"]) > 1e-5:
                sys.exit(f"Blender {result['tag']}, {name} {key}: the render in {OUT} is not the published one; "
                         "run bench/lights_eevee_benchmark.py first")


def rows(result):
    """Goal rows of one Blender, and on how many scenes goals 2 and 1 hold against direct light."""
    lines, goal2, goal1 = [], 0, 0
    for name, e in result["scenes"].items():
        key, base = baseline({k: v for k, v in e.items() if k != "direct"})
        ratio = e[RIG]["error"] / base["error"]
        means = [e[f"rig_{n}"]["mean"] for n in COUNTS]
        within = all(abs(m - 1) <= GOAL1_TOLERANCE for m in means)
        goal2, goal1 = goal2 + (ratio <= GOAL2_RATIO), goal1 + within
        lines.append(
            f"| {result['blender']} | {name} | {1 - e['direct']['mean']:.1%} | {100 * e['direct']['noise']:.2f}% | "
            f"{variant_label(key)}: {100 * base['error']:.1f}% | {100 * e[RIG]['error']:.1f}% | "
            f"{100 * e[BUDGET]['error']:.1f}% | {ratio:.2f} | " + " / ".join(f"{m:.3f}" for m in means)
            + f" | {'yes' if within else 'no'} |")
    return lines, goal2, goal1


def pool_rows(result):
    """Rows of one Blender's shadow-pool renders."""
    lines = []
    for name, e in result["scenes"].items():
        cells = []
        for key, _ in POOL_RENDERS:
            r = e[key]
            pages = f"{r['pages_needed']} / {r['pages_held']}" if r["pages_needed"] else "fits"
            cells.append(f"{pages}; {r['mean']:.3f}, {100 * r['error']:.1f}% ({r['issue_mean']:.3f})")
        lines.append(f"| {result['blender']} | {name} | " + " | ".join(cells) + " |")
    return lines


def pool_section(results):
    if not results:
        return []
    full = "; ".join(f"{r['blender']}: " + ", ".join(
        f"{k.split('_')[1]} suns " + (f"{v} pages" if v else "fit") for k, v in r["full_size"]["pages_needed"].items())
        for r in results)
    size = "x".join(map(str, results[0]["full_size"]["size"]))
    return [
        "", "**EEVEE Next's shadow pool** (`--shadow-pool`, `bench/blender_scripts/lights_eevee_shadow_pool.py`): "
        "EEVEE Next keeps every light's shadow-map pages in one pool (`scene.eevee.shadow_pool_size`, factory "
        "512 MB: 2048 pages of 256 KiB). A render that needs more prints \"Shadow buffer full, may result in "
        "missing shadows\" with the pages it needed and drops some. Each cell: pages needed / held when it "
        "overflowed (read from EEVEE's message; \"fits\" when it printed none); the mean and error against "
        "Cycles' direct light; in brackets the mean against the issue's reference.", "",
        "| Blender | scene | " + " | ".join(label for _, label in POOL_RENDERS) + " |",
        "|---|---|" + "---|" * len(POOL_RENDERS),
    ] + [line for r in results for line in pool_rows(r)] + [
        "", f"The pages follow the view's depth, not its pixels: the opposite scene at {size}, 1 sample: {full}.",
    ]


def section(results, pool_results=()):
    table, summary = [], []
    for r in results:
        lines, goal2, goal1 = rows(r)
        table += lines
        n = len(r["scenes"])
        cached = all(e["direct"]["seconds"] == 0 for e in r["scenes"].values())
        summary.append(f"- Blender {r['blender']}: goal 2 (≤ {GOAL2_RATIO}×) on {goal2} of {n} scenes, goal 1 "
                       f"(within {GOAL1_TOLERANCE:.0%} at {', '.join(map(str, COUNTS))} suns) on {goal1} of {n}; "
                       f"{r['seconds']:.0f} s" + (" (its Cycles references cached by an earlier run)" if cached else "")
                       + f", load average {min(r['load']):.1f}–{max(r['load']):.1f}.")
    return "\n".join([
        "", MARKER.strip(), "",
        "Written by `bench/lights_eevee_direct_benchmark.py`. Not issue #26's verdict (its reference is Cycles "
        "with default bounces; the section above) but what stands between the rig and it: the renders of "
        "\"Shadowed comparison (EEVEE)\" above, the same files, measured against Cycles' World render with "
        "**no bounce** (`max_bounces` 0, two seeds at the reference's samples, cached beside it): the light "
        "that EEVEE at factory settings draws from lamps, which give no bounce light there without baked "
        "probes or Ray Tracing. Each render's error against the issue's reference is checked to equal the "
        "published one. The baseline is chosen again: the best World render against this reference. "
        "**Bounce**: the share of the issue's reference that Cycles' direct light lacks (1 − its mean / the "
        "reference's): light bounced between sphere and plane, which depends on their albedos, not on the map.",
        "",
    ] + summary + [
        "",
        f"| Blender | scene | bounce | noise (two seeds) | baseline (best) | rig, {GOAL2_COUNT} suns | "
        f"shadow budget {SHADOW_BUDGET} | rig / baseline | rig mean, {' / '.join(map(str, COUNTS))} suns | "
        f"within {GOAL1_TOLERANCE:.0%} |",
        "|---|---|---:|---:|---|---:|---:|---:|---|---|",
    ] + table + pool_section(list(pool_results)) + [""])


def run_shadow_pool(tags):
    for tag in tags:
        out = os.path.join(OUT, f"shadow_pool_{tag}")
        os.makedirs(out, exist_ok=True)
        write_json(stored_path(tag, "shadow_pool"), run_blender(tag, out, None, POOL_SCRIPT))


def stored(kind, tags):
    results = []
    for tag in tags:
        if os.path.exists(stored_path(tag, kind)):
            with open(stored_path(tag, kind)) as f:
                results.append(json.load(f))
    return results


def main():
    argv = sys.argv
    pool = "--shadow-pool" in argv
    tags = argv[argv.index("--blenders") + 1].split(",") if "--blenders" in argv else list(
        POOL_TAGS if pool else BLENDERS)
    if pool and "--section-only" not in argv:
        run_shadow_pool(tags)
    for tag in ([] if "--section-only" in argv or pool else tags):
        with open(result_path(tag)) as f:
            published = json.load(f)
        result = run_blender(tag, os.path.join(OUT, tag), None, SCRIPT)
        check_renders(result, published)
        write_json(stored_path(tag), result)
    write_section(DOC, MARKER, section(stored("direct", BLENDERS), stored("shadow_pool", POOL_TAGS)),
                  "\n## Shadowed comparison (EEVEE)")
    print("wrote", DOC)


if __name__ == "__main__":
    main()
