#!/usr/bin/env python3
"""The renderers' limits (issue #14, item 4): the shadowed comparison of
docs/lights-benchmark.md (a sphere on a plane under Blender's sunrise.exr,
128x96) in EEVEE, beside Cycles in the same Blender:
  - EEVEE Legacy in Debian's Blender 3.4, headless under Xvfb (Mesa's
    llvmpipe: OpenGL on the CPU), rigs with and without the add-on's
    "Shadows for 8 Strongest" (limit_shadows);
  - EEVEE Next in the bpy 4.5 module, which makes its GPU context through
    EGL, here Mesa's software rasterizer too.
Writes the section "Shadowed comparison (EEVEE)" of docs/lights-benchmark.md
and its pictures (docs/lights/eevee_*.png):

    .venv/bin/python bench/lights_eevee_benchmark.py [--lock /work/bench.lock]

Each Blender runs bench/blender_scripts/lights_eevee_render.py (OUT ENGINE)
and prints one RESULT line of JSON. PENUMBRA_BENCH_QUICK=1: one rig, few
samples (a smoke test of the script, not a result).

EEVEE Legacy lights the scene with at most 128 lights and gives cascaded
shadow maps to at most 8 suns; EEVEE Next has neither cap (virtual shadow
maps). Both light the scene from the World through a light probe."""

import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.doc_section import lock_path, locked, write_section  # noqa: E402
from bench.helpers.paths import ROOT  # noqa: E402

DOC = os.path.join(ROOT, "docs", "lights-benchmark.md")
RENDER = os.path.join(ROOT, "bench", "blender_scripts", "lights_eevee_render.py")
PICTURES = os.path.join(ROOT, "docs", "lights")
QUICK = os.environ.get("PENUMBRA_BENCH_QUICK") == "1"
COUNTS = (16,) if QUICK else (16, 64, 256)
CYCLES_SPP = 4 if QUICK else 128
# EEVEE render samples (taa_render_samples; Blender's default is 64): 16 keeps
# an EEVEE Next render on llvmpipe near half a minute.
EEVEE_SAMPLES = 2 if QUICK else 16
MARKER = "\n## Shadowed comparison (EEVEE)"
LEGACY, NEXT = "BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"


# --- the driver ----------------------------------------------------------------

def rows(r):
    """Table rows of one Blender's EEVEE renders."""
    legacy = r["engine"] == LEGACY
    name = "EEVEE Legacy" if legacy else "EEVEE Next"
    w = r["eevee world"]
    out = [f"| {r['blender']} | {name}, World | – | – | {100 * w['error']:.2f}% | 0 | {w['mean']:.3f} | "
           f"{r['seconds']['eevee_world']:.1f} |"]
    for n in COUNTS:
        for key, label in (("all", "all"), ("limited", "8 strongest")):
            if f"{n} {key}" not in r:
                continue
            e = r[f"{n} {key}"]
            drawn = f"{min(e['suns'], 128)} of {e['suns']}" if legacy else f"{e['suns']}"
            shadowed = (f"{min(e['shadowed'], 8)} of {e['shadowed']} asking" if legacy else f"{e['shadowed']}")
            out.append(f"| {r['blender']} | {name}, {n} suns, shadows: {label} | {drawn} | {shadowed} | "
                       f"{100 * e['error']:.2f}% | {100 * e['vs eevee world']:.2f}% | {e['mean']:.3f} | "
                       f"{r['seconds'][f'eevee_{n}_{key}']:.1f} |")
    return out


def cycles_rows(r):
    out = [f"| {r['blender']} | Cycles, World, another seed (noise floor) | {100 * r['cycles noise']:.2f}% | – | "
           f"{r['seconds']['cycles_world_b']:.1f} |"]
    for n in COUNTS:
        e = r[f"{n} all"]
        out.append(f"| {r['blender']} | Cycles, {n} suns | {100 * e['cycles error']:.2f}% | {e['cycles mean']:.3f} | "
                   f"{r['seconds'][f'cycles_{n}']:.1f} |")
    return out


def section(results, elapsed):
    legacy, nxt = results
    middle = COUNTS[len(COUNTS) // 2]
    lines = [
        "",
        "## Shadowed comparison (EEVEE)" + (" (QUICK SMOKE TEST, NOT A RESULT)" if QUICK else ""),
        "",
        f"Written by `bench/lights_eevee_benchmark.py` ({time.strftime('%Y-%m-%d')}, {elapsed:.0f} s). The scene of "
        f"the Cycles comparison above (128x96, film transparent) in EEVEE Legacy (Debian's Blender "
        f"{legacy['blender']}, headless under Xvfb) and EEVEE Next (the bpy {nxt['blender']} module, whose GPU "
        "context comes through EGL), both on Mesa's llvmpipe (OpenGL on the CPU: no GPU here), "
        f"{EEVEE_SAMPLES} EEVEE samples, beside Cycles in the same Blender (CPU, {CYCLES_SPP} samples, no "
        "denoising). Each rig is built by `penumbra.build_light_rig` in that Blender for EEVEE (`target_renderer`; "
        "region powers, Havran; "
        "World strength 0 for the rig renders). Error = RMS of the luminance difference / mean luminance of "
        "that Blender's Cycles World render (the truth: the sun's shadow, the sky's occlusion); `vs EEVEE World` "
        "the same against EEVEE's own World render; `mean` = mean luminance / the Cycles World's; render time "
        "on the shared 2-core machine.",
        "",
        "EEVEE lights a scene from the World through its light probe (an irradiance and a reflection map), "
        f"without any shadow: its World render is {100 * legacy['eevee world']['error']:.1f}% (Legacy) and "
        f"{100 * nxt['eevee world']['error']:.1f}% (Next) from the truth, the sphere's shadow missing. A rig's "
        "suns bring the shadows back where EEVEE lets them: EEVEE Legacy draws at most 128 lights and gives "
        "cascaded shadow maps to at most 8 suns. `all`: every sun asks for a shadow and EEVEE grants 8 of its "
        "choosing; `8 strongest`: the add-on's *Shadows for 8 Strongest* (`limit_shadows`) gives them to the 8 "
        "suns of most power and turns the others' off. EEVEE Next draws and shadows every sun.",
        "",
        "| Blender | lit by | suns drawn | suns shadowed | error vs Cycles World | vs EEVEE World | mean | "
        "render (s) |",
        "|---|---|---|---|---|---|---|---|",
    ] + rows(legacy) + rows(nxt) + [
        "",
        "The same rigs in Cycles (every sun drawn and shadowed):",
        "",
        "| Blender | lit by | error vs Cycles World | mean | render (s) |",
        "|---|---|---|---|---|",
    ] + cycles_rows(legacy) + cycles_rows(nxt) + [
        "",
        "Pictures (Blender 3.4): [Cycles, World](lights/eevee_cycles_world.png), "
        f"[EEVEE Legacy, World](lights/eevee_world.png), [EEVEE Legacy, {middle} suns, 8 strongest shadowed]"
        f"(lights/eevee_rig_{middle}.png); (bpy 4.5) [EEVEE Next, World](lights/eevee_next_world.png), "
        f"[EEVEE Next, {middle} suns](lights/eevee_next_rig_{middle}.png).",
    ]
    return "\n".join(lines) + "\n"


def run_blender(command, out, engine):
    res = subprocess.run(command + [out, engine], capture_output=True, text=True, timeout=5400,
                         env=dict(os.environ, GALLIVM_PERF="nopt", LP_NUM_THREADS="2"))
    line = [x for x in res.stdout.splitlines() if x.startswith("RESULT ")]
    if res.returncode != 0 or not line:
        print(res.stdout[-4000:], res.stderr[-4000:])
        sys.exit(f"the {engine} renders failed")
    return json.loads(line[0][len("RESULT "):])


def main():
    import shutil
    import tempfile
    lock = lock_path(sys.argv)
    started = time.time()
    middle = COUNTS[len(COUNTS) // 2]
    results = []
    with locked(lock):
        for command, engine, pictures in (
                (["xvfb-run", "-a", "blender", "-b", "--factory-startup", "--python", RENDER, "--"], LEGACY,
                 (("cycles_world", "eevee_cycles_world.png"), ("eevee_world", "eevee_world.png"),
                  (f"eevee_{middle}_limited", f"eevee_rig_{middle}.png"))),
                ([os.path.join(ROOT, ".venv", "bin", "python"), RENDER], NEXT,
                 (("eevee_world", "eevee_next_world.png"), (f"eevee_{middle}_all", f"eevee_next_rig_{middle}.png")))):
            with tempfile.TemporaryDirectory(prefix="penumbra_eevee_") as out:
                results.append(run_blender(command, out, engine))
                print(json.dumps(results[-1], indent=1), flush=True)
                for name, picture in pictures:
                    shutil.copyfile(os.path.join(out, name + ".png"), os.path.join(PICTURES, picture))
    write_section(DOC, MARKER, section(results, time.time() - started), "\n## Shadowed comparison (Cycles)")
    print("wrote", DOC)


if __name__ == "__main__":
    main()
