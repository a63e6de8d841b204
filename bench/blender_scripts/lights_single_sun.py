"""Issue #26's single-sun measurement, inside one Blender: one sun at 30°
elevation over a plane seen from above, EEVEE (32x32, 16 samples) against
Cycles with no bounces, for sun angles 0/30/90/120° with its shadow on and
off, then a point sun at the elevations in ELEVATIONS (how each EEVEE
shades the surface under low light). Prints one line "RESULT {json}" of
EEVEE's mean / Cycles' mean:

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
ELEVATIONS = (3, 6, 10, 20, 30, 60)  # degrees above the plane


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
    point_sun_at(sun, 30.0)
    data.energy = 1.0
    scene.cycles.max_bounces = 0
    scene.eevee.taa_render_samples = samples
    return scene, data


def point_sun_at(sun, elevation):
    """Turns the sun to `elevation` degrees above the horizon."""
    sun.rotation_euler = (math.radians(90.0 - elevation), 0.0, 0.0)


def by_elevation(scene, light, out):
    """EEVEE's mean / Cycles' for a point sun at each of ELEVATIONS."""
    sun, ratios = bpy.data.objects["Sun"], {}
    light.angle, light.use_shadow = 0.0, True
    for elevation in ELEVATIONS:
        point_sun_at(sun, elevation)
        ratios[f"point at {elevation}°"] = (mean_luminance(scene, eevee_engine(), out)
                                            / mean_luminance(scene, "CYCLES", out))
    point_sun_at(sun, 30.0)
    return ratios


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
    result.update(by_elevation(scene, light, out))
    print("RESULT " + json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
