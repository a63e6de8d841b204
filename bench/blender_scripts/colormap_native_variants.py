"""Variants of the default Noise Filter (1 Noise, native_filter.py) against
it at equal time, in one process (issue #25, docs/colormap-benchmark.md,
"Equal time", "Tried on the default"):

    .venv/bin/python bench/blender_scripts/colormap_native_variants.py -- OUT.json

Each variant is baked with native_filter.native_estimate wrapped so that
the kernel it reads is τ = c·κ·N^(−e) instead of κ/√N ("kernel c,e"), the
groups of the bakes before it renamed so the bake builds its own. Then the
plain ramp (1–256 spp) and every variant (PENUMBRA_BENCH_NV_SPP: 16,64) are
rendered interleaved, PENUMBRA_BENCH_NV_REPEATS (3) seeds, at 96×54, on
PENUMBRA_BENCH_NV_SCENES (plane,constant); equal-time ratios in CPU and
wall seconds (bench/helpers/colormap_equal_time.py)."""

import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import bpy  # noqa: E402
from bench.helpers import colormap_equal_time as equal_time  # noqa: E402
from penumbra.colormap import native_filter  # noqa: E402

ORIGINAL = native_filter.native_estimate


def _with_kernel(c, e):
    """The default with τ = c·κ·N^(−e)."""
    def estimate(b, gin, model, total_var, filter_stddev_px, share):
        if (c, e) != (1.0, 0.5):
            share = b.math("MULTIPLY", b.math("POWER", b.math("MAXIMUM", gin.outputs["Samples"], 1.0), -e), c)
        return ORIGINAL(b, gin, model, total_var, filter_stddev_px, share)
    return estimate


def _fixed_x(b, gin, model, total_var, filter_stddev_px, share):
    """A timing probe, not a filter: the curves read a constant (x = 1), so
    the point footprint and x's arithmetic drop out of the compiled shader."""
    original_math = b.math

    def math(op, a, b_=0.0, c=None, clamp=False):
        if op == "LOGARITHM":
            return 0.25      # x = −½ · 0.25·… folded: any constant
        return original_math(op, a, b_, c, clamp)
    b.math = math
    try:
        return ORIGINAL(b, gin, model, total_var, filter_stddev_px, share)
    finally:
        b.math = original_math


# name: the native_estimate the bake uses.
VARIANTS = {"default": _with_kernel(1.0, 0.5), "kernel 1.5,0.5": _with_kernel(1.5, 0.5),
            "kernel 2,0.5": _with_kernel(2.0, 0.5), "kernel 1,0.375": _with_kernel(1.0, 0.375),
            "kernel 0.7,0.5": _with_kernel(0.7, 0.5), "kernel 0.5,0.5": _with_kernel(0.5, 0.5),
            "kernel 1,0.625": _with_kernel(1.0, 0.625), "fixed x (timing probe)": _fixed_x}


def bake_variant(scene, obj, material, name, folder):
    native_filter.native_estimate = VARIANTS[name]
    try:
        baked = equal_time.bake_quality(scene, obj, material, "NATIVE_ONLY", folder)
    finally:
        native_filter.native_estimate = ORIGINAL
    for group in bpy.data.node_groups:      # the next bake must not reuse this one's groups
        if group.name.startswith("Penumbra Noise Filter") and "[" not in group.name:
            group.name = f"{group.name} [{name}]"
    return baked


def main(out_path):
    spp = [int(v) for v in os.environ.get("PENUMBRA_BENCH_NV_SPP", "16,64").split(",")]
    repeats = int(os.environ.get("PENUMBRA_BENCH_NV_REPEATS", "3"))
    names = [n for n in os.environ.get("PENUMBRA_BENCH_NV_VARIANTS", ";".join(VARIANTS)).split(";") if n]
    data = {"blender": bpy.app.version_string, "repeats": repeats, "variants": names,
            "scenes": {}}
    folder = os.path.splitext(out_path)[0] + "_renders"
    for scene_name in os.environ.get("PENUMBRA_BENCH_NV_SCENES", "plane,constant").split(","):
        scene, obj, material = equal_time.new_bench_scene(scene_name, 0.5)
        materials = {equal_time.PLAIN: material}
        for name in names:
            materials[name] = bake_variant(scene, obj, material, name, os.path.join(folder, scene_name, "lut"))
        renderer = equal_time.Renderer(scene, obj, materials, folder)
        reference = equal_time.reference_image(renderer, 2048)
        counts = {equal_time.PLAIN: [1, 4, 16, 64, 256], **{n: spp for n in names}}
        load, started = os.getloadavg(), time.perf_counter()
        results = equal_time.sweep(renderer, reference, counts, repeats)
        data["scenes"][scene_name] = {
            "results": {m: {str(s): e for s, e in rows.items()} for m, rows in results.items()},
            "ratios": {n: {clock: {str(s): r for s, r in equal_time.equal_time_ratios(results, n, clock).items()}
                           for clock in ("wall", "cpu")} for n in names},
            "load_average": [load, os.getloadavg()], "seconds": time.perf_counter() - started}
        with open(out_path, "w") as f:
            json.dump(data, f, indent=1)
        print(f"native variants: {scene_name} done", flush=True)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1])
