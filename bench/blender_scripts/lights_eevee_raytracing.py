"""What EEVEE Next's ray tracing gives a light rig (issue #26, outside its
goals: they judge factory render settings, and the operator sets only its
own lights). The EEVEE benchmark's five scenes and cached references
(bench/lights_eevee_benchmark.py, bench/blender_scripts/lights_eevee_render.py),
each rendered in EEVEE Next with ray tracing off (factory), on (factory ray
tracing and Fast GI settings: screen trace, Fast GI "Global Illumination")
and on with a finer Fast GI (full resolution, 16 steps, quality 1): the
World alone, the benchmark's baseline for the scene (its best World render,
from docs/lights/eevee-results/result_<blender>.json), the default 32-sun
rig for EEVEE and the same rig with `shadow_budget` 8. With ray tracing on,
lamp light bounces in screen space, which the reference (Cycles with
default bounces) has and factory EEVEE lacks. Prints "RESULT {json}":

    .venv/bin/python bench/blender_scripts/lights_eevee_raytracing.py OUT CACHE OPPOSITE
    .venv313/bin/python bench/blender_scripts/lights_eevee_raytracing.py OUT CACHE OPPOSITE

CACHE: the EEVEE benchmark's references of this Blender
(build/bench/lights_eevee/references/<4.5|5.2>); OPPOSITE: its map with two
opposite sources (build/bench/lights_eevee/opposite.exr)."""

import json
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.blender_scripts.lights_eevee_render import (  # noqa: E402
    Renderer, build_rig, reference, start_blender, world_variants)
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.lights_eevee import bundled_map, eevee_engine, light_by_map  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.lights_eevee_benchmark import (  # noqa: E402
    EEVEE_SAMPLES, GOAL2_COUNT, HEIGHT, REFERENCE_SPP, SCENES, WIDTH, baseline, result_path)

# (key, use_raytracing, Fast GI resolution, steps, quality); None keeps factory values.
TRACING = (("off", False, None, None, None), ("on", True, None, None, None), ("fine", True, "1", 16, 1.0))
LIGHTING = (("world", None), ("baseline", None), ("rig", 0), ("budget8", 8))


def set_tracing(eevee, factory, on, resolution, steps, quality):
    """Ray tracing as `on`, Fast GI from the factory values `factory` unless given."""
    eevee.use_raytracing = on
    eevee.fast_gi_resolution = resolution or factory["fast_gi_resolution"]
    eevee.fast_gi_step_count = steps or factory["fast_gi_step_count"]
    eevee.fast_gi_quality = quality or factory["fast_gi_quality"]


def set_lighting(scene, strength, lighting, budget, baseline_key, out):
    """The World alone, the baseline's World variant, or a rig of GOAL2_COUNT suns."""
    scene.world.sun_threshold = 0.0  # no sun extraction (its default is on)
    if lighting == "baseline":
        dict(world_variants(scene.world))[baseline_key]()
    elif budget is not None:
        build_rig(strength, out, GOAL2_COUNT, budget)


def render_scene(name, map_path, core, out, cache, baseline_key):
    scene, strength = sunrise_sphere_scene(REFERENCE_SPP, EEVEE_SAMPLES)
    light_by_map(scene, map_path)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    factory = {k: getattr(scene.eevee, k) for k in ("fast_gi_resolution", "fast_gi_step_count", "fast_gi_quality")}
    render = Renderer(scene, core)
    truth, facts = reference(render, cache, name)
    mean = float(np.mean(truth))
    rows = {"reference": {"spp": facts["spp"], "noise": facts["noise"]}, "baseline_key": baseline_key}
    for lighting, budget in LIGHTING:
        set_lighting(scene, strength, lighting, budget, baseline_key, out)
        for key, *tracing in TRACING:
            set_tracing(scene.eevee, factory, *tracing)
            started = time.perf_counter()
            luma, _ = render(eevee_engine(), os.path.join(out, f"{name}_{lighting}_{key}"))
            rows[f"{lighting}_{key}"] = {"error": float(np.sqrt(np.mean((luma - truth) ** 2)) / mean),
                                         "mean": float(np.mean(luma)) / mean,
                                         "seconds": time.perf_counter() - started}
            print(name, lighting, key, rows[f"{lighting}_{key}"], flush=True)
    return rows


def main(result, out, cache, opposite):
    core = start_blender()
    os.makedirs(out, exist_ok=True)
    started = time.time()
    load = [os.getloadavg()[0]]
    tag = f"{bpy.app.version[0]}.{bpy.app.version[1]}"
    with open(result_path(tag)) as f:
        stored = json.load(f)["scenes"]  # the EEVEE benchmark's, for each scene's baseline
    result.update(tag=tag, scenes={})
    for name in SCENES:
        map_path = opposite if name == "opposite" else bundled_map(name)
        result["scenes"][name] = render_scene(name, map_path, core, out, cache, baseline(stored[name])[0])
        load.append(os.getloadavg()[0])
    result.update(blender=bpy.app.version_string, load=load, seconds=time.time() - started)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1:][:3]
    report(lambda result: main(result, *args))
