"""The EEVEE part of bench/lights_eevee_benchmark.py, inside a Blender:
Debian's 3.4 (EEVEE Legacy, under Xvfb) or the bpy 4.5 module (EEVEE Next).
Renders the sunrise scene (bench/helpers/lights_render_scene.py) and prints
one line "RESULT {json}":

    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/lights_eevee_render.py -- OUT ENGINE
    .venv/bin/python bench/blender_scripts/lights_eevee_render.py OUT ENGINE"""

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
from bench.lights_eevee_benchmark import COUNTS, CYCLES_SPP, EEVEE_SAMPLES, LEGACY, NEXT  # noqa: E402  (its settings)


class Renderer:
    """Renders to OUT/name.exr (and .png for pictures); luminance and times."""

    def __init__(self, scene, out, core):
        self.scene, self.out, self.core = scene, out, core
        self.seconds = {}

    def __call__(self, engine, name, picture=False, seed=1):
        self.scene.render.engine = engine
        self.scene.cycles.seed = seed
        started = time.perf_counter()
        bpy.ops.render.render()
        self.seconds[name] = time.perf_counter() - started
        result = bpy.data.images["Render Result"]
        settings = self.scene.render.image_settings
        settings.file_format, settings.color_depth = "OPEN_EXR", "32"
        path = os.path.join(self.out, name + ".exr")
        result.save_render(path)
        if picture:
            settings.file_format, settings.color_depth, settings.color_mode = "PNG", "8", "RGBA"
            result.save_render(os.path.join(self.out, name + ".png"))
        return self.core.image.read(path) @ LUMINANCE


def render_all(out, eevee):
    """Cycles' World render (the truth) and a second seed of it, EEVEE's World
    render, and EEVEE renders of rigs of COUNTS suns (Legacy: every sun asking
    for a shadow, then only the 8 strongest; Next: every sun), each rig also
    in Cycles; returns the errors, means, counts and times."""
    penumbra.register()
    scene, strength = sunrise_sphere_scene(CYCLES_SPP, EEVEE_SAMPLES)
    render = Renderer(scene, out, native.require())
    truth = render("CYCLES", "cycles_world", picture=True)
    mean = float(np.mean(truth))

    def error(luma, reference=truth):
        return float(np.sqrt(np.mean((luma - reference) ** 2)) / mean)

    result = {"blender": bpy.app.version_string, "engine": eevee, "eevee samples": EEVEE_SAMPLES,
              "cycles noise": error(render("CYCLES", "cycles_world_b", seed=2))}
    eevee_world = render(eevee, "eevee_world", picture=True)
    result["eevee world"] = {"error": error(eevee_world), "mean": float(np.mean(eevee_world)) / mean}
    middle = COUNTS[len(COUNTS) // 2]
    for n in COUNTS:
        for limit in ((False, True) if eevee == LEGACY else (False,)):
            strength.default_value = 1.0
            r = bpy.ops.penumbra.build_light_rig(filepath="", count=n, limit_shadows=limit, target_renderer="EEVEE",
                                                 json_path=os.path.join(out, "rig.json"))
            assert r == {"FINISHED"}, r
            strength.default_value = 0.0
            suns = [o for o in scene.objects if o.type == "LIGHT"]
            key = f"{n} {'limited' if limit else 'all'}"
            luma = render(eevee, f"eevee_{n}_{'limited' if limit else 'all'}",
                          picture=n == middle and (limit or eevee == NEXT))
            entry = {"error": error(luma), "vs eevee world": error(luma, eevee_world),
                     "mean": float(np.mean(luma)) / mean, "suns": len(suns),
                     "shadowed": sum(o.data.use_shadow for o in suns)}
            if not limit:
                cycles = render("CYCLES", f"cycles_{n}")
                entry["cycles error"], entry["cycles mean"] = error(cycles), float(np.mean(cycles)) / mean
            result[key] = entry
    result["seconds"] = render.seconds
    return result


if __name__ == "__main__":
    try:
        out_folder, engine_name = sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1:][:2]
        print("RESULT " + json.dumps(render_all(out_folder, engine_name)), flush=True)
    except Exception:
        traceback.print_exc()
        sys.exit(1)
