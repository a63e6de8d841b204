"""Issue #26 goal 1 at a small size, inside one Blender: the sunrise sphere on
a plane (bench/helpers/lights_render_scene.py) at 48x36, Cycles' World
render (default bounces, and no bounces) against the fitted default rig built
for EEVEE (target_renderer='EEVEE') at 16/32/64 suns, and, for comparison,
the rig built for Cycles drawn by EEVEE. Prints "RESULT {json}" of mean
luminances / the Cycles World's:

    .venv/bin/python bench/blender_scripts/lights_eevee_goal1.py OUT
    .venv313/bin/python bench/blender_scripts/lights_eevee_goal1.py OUT
    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/lights_eevee_goal1.py -- OUT"""

import json
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.helpers.lights_eevee import eevee_engine, mean_luminance  # noqa: E402

COUNTS = (16, 32, 64)


def main(out):
    if bpy.app.version >= (5, 0, 0) and bpy.app.background:
        import gpu
        gpu.init()
    penumbra.register()
    scene, strength = sunrise_sphere_scene(256, 16)
    scene.render.resolution_x, scene.render.resolution_y = 48, 36
    started = time.time()
    truth = mean_luminance(scene, "CYCLES", out)
    scene.cycles.max_bounces = 0
    direct = mean_luminance(scene, "CYCLES", out)
    scene.cycles.max_bounces = 12
    result = {"blender": bpy.app.version_string, "cycles no bounces": direct / truth}
    for n, target in [(n, "EEVEE") for n in COUNTS] + [(32, "CYCLES")]:
        strength.default_value = 1.0
        r = bpy.ops.penumbra.build_light_rig(filepath="", count=n, target_renderer=target,
                                             json_path=os.path.join(out, "rig.json"))
        assert r == {"FINISHED"}, r
        strength.default_value = 0.0
        result[f"{n} for {target}"] = mean_luminance(scene, eevee_engine(), out) / truth
        print(result, flush=True)
    result["seconds"] = time.time() - started
    print("RESULT " + json.dumps(result), flush=True)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1])
