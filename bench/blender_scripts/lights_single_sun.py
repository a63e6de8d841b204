"""Issue #26's single-sun measurement, inside one Blender: one sun at 30°
elevation over a plane seen from above, EEVEE (32x32, 16 samples) against
Cycles with no bounces, for sun angles 0/30/90/120° with its shadow on and
off. Prints one line "RESULT {json}" of EEVEE's mean / Cycles' mean:

    .venv/bin/python bench/blender_scripts/lights_single_sun.py
    .venv313/bin/python bench/blender_scripts/lights_single_sun.py
    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/lights_single_sun.py"""

import json
import math
import os
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.lights_eevee import eevee_engine, mean_luminance, plane_seen_from_above  # noqa: E402

ANGLES = (0, 30, 90, 120)


def scene_with_sun(size=32, samples=16):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    plane_seen_from_above(scene, size, size)
    data = bpy.data.lights.new("Sun", "SUN")
    sun = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.radians(60.0), 0.0, 0.0)  # 30° above the horizon
    data.energy = 1.0
    scene.cycles.max_bounces = 0
    scene.eevee.taa_render_samples = samples
    return scene, data


def main():
    if bpy.app.version >= (5, 0, 0) and bpy.app.background:
        import gpu
        if hasattr(gpu, "init"):
            gpu.init()
    scene, light = scene_with_sun()
    out = tempfile.mkdtemp(prefix="penumbra_sun_")
    result = {"blender": bpy.app.version_string, "engine": eevee_engine()}
    for angle in ANGLES:
        light.angle = math.radians(angle)
        light.use_shadow = True
        cycles = mean_luminance(scene, "CYCLES", out)
        for shadow in (True, False):
            light.use_shadow = shadow
            result[f"{angle} {'on' if shadow else 'off'}"] = mean_luminance(scene, eevee_engine(), out) / cycles
        print(angle, result, flush=True)
    print("RESULT " + json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
