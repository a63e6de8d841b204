"""Cycles at equal render time (issue #26 item 5), run by
`bench/lights_benchmark.py --equal-time` in the bpy module (a fresh
process): the scene of the shadowed comparison (sunrise.exr, a sphere on a
plane, 128x96, bench/helpers/lights_render_scene.py), on 2 threads, lit by
the World and by the default rig of N suns (World strength 0), with
Blender's light tree on (the factory setting) and off.

Each lighting is first timed at two sample counts (seconds of
bpy.ops.render.render after a warm-up render, the best of two): its time is
a + b·spp. For each budget (the World's time at BUDGET_SPP samples), every
lighting then renders with the samples that fill that budget, twice (two
seeds); the error is the RMS of the luminance difference to a World render
of REFERENCE_SPP samples, over its mean. Prints one line "RESULT {json}".

Time is the process's CPU seconds (all its threads), which on a machine
shared with other jobs measures the render's work where wall seconds
measure the load (a 128-spp World render took 7 to 17 wall seconds in one
run); both are recorded for the renders that are compared.

    .venv/bin/python bench/blender_scripts/lights_equal_time_render.py OUT N REFERENCE_SPP BUDGET_SPP[,...]"""

import json
import os
import sys
import time
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.helpers.metrics import LUMINANCE  # noqa: E402

THREADS = 2
TIMING_SPP = (8, 64)  # the two sample counts a lighting's a + b·spp is fitted from


def main(out, count, reference_spp, budgets):
    penumbra.register()
    core = native.require()
    scene, strength = sunrise_sphere_scene(16)
    scene.render.threads_mode, scene.render.threads = "FIXED", THREADS
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    r = bpy.ops.penumbra.build_light_rig(filepath="", count=count, target_renderer="CYCLES",
                                         json_path=os.path.join(out, "rig.json"))
    assert r == {"FINISHED"}, r
    rig = scene.penumbra.light_rig.collection

    def light(kind):
        """World, or the rig with the light tree on or off."""
        world = kind == "World"
        strength.default_value = 1.0 if world else 0.0
        rig.hide_render = world
        scene.cycles.use_light_tree = kind != "rig, light tree off"

    wall = [0.0]  # the last render's wall seconds

    def render(spp, seed, name="render"):
        """(CPU seconds, luminance) of one render."""
        scene.cycles.samples, scene.cycles.seed = spp, seed
        scene.render.filepath = os.path.join(out, name)
        started, cpu = time.perf_counter(), time.process_time()
        bpy.ops.render.render(write_still=True)
        wall[0] = time.perf_counter() - started
        return time.process_time() - cpu, core.image.read(scene.render.filepath + ".exr") @ LUMINANCE

    kinds = ("World", "rig, light tree on", "rig, light tree off")
    cost = {}
    for kind in kinds:
        light(kind)
        render(4, 0)  # warm-up: scene sync, kernels, the World's importance map
        seconds = [min(render(spp, 0)[0] for _ in range(2)) for spp in TIMING_SPP]
        b = (seconds[1] - seconds[0]) / (TIMING_SPP[1] - TIMING_SPP[0])
        cost[kind] = {"a": seconds[0] - b * TIMING_SPP[0], "b": b}

    light("World")
    started = time.perf_counter()
    _, reference = render(reference_spp, 100, "reference")
    result = {"threads": THREADS, "count": count, "reference_spp": reference_spp,
              "reference_seconds": time.perf_counter() - started, "cost": cost, "budgets": []}
    mean = float(np.mean(reference))
    for budget_spp in budgets:
        budget = cost["World"]["a"] + cost["World"]["b"] * budget_spp
        rows = {}
        for kind in kinds:
            spp = max(1, round((budget - cost[kind]["a"]) / cost[kind]["b"])) if kind != "World" else budget_spp
            light(kind)
            runs, walls = [], []
            for seed in (1, 2):
                runs.append(render(spp, seed))
                walls.append(wall[0])
            rows[kind] = {"spp": spp, "seconds": float(np.mean([s for s, _ in runs])),
                          "wall_seconds": float(np.mean(walls)),
                          "error": float(np.mean([np.sqrt(np.mean((y - reference) ** 2)) / mean for _, y in runs])),
                          "noise": float(np.sqrt(np.mean((runs[0][1] - runs[1][1]) ** 2)) / mean / np.sqrt(2)),
                          "mean": float(np.mean([np.mean(y) for _, y in runs])) / mean}
        result["budgets"].append({"budget_spp": budget_spp, "budget_seconds": budget, "rows": rows})
        print("budget", budget_spp, json.dumps(rows), flush=True)
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    try:
        main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), [int(v) for v in sys.argv[4].split(",")])
    except Exception:
        traceback.print_exc()
        sys.exit(1)
