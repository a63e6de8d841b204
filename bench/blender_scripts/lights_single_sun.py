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
import numpy as np

ANGLES = (0, 30, 90, 120)


def eevee_engine():
    """EEVEE's engine id in this Blender: Legacy before 4.2, Next as BLENDER_EEVEE_NEXT in 4.2-4.5."""
    return "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"


def scene_with_sun(size=32, samples=16):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    data = bpy.data.lights.new("Sun", "SUN")
    sun = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.radians(60.0), 0.0, 0.0)  # 30° above the horizon
    data.energy = 1.0
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type, cam.data.ortho_scale = "ORTHO", 4.0
    cam.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    r = scene.render
    r.resolution_x = r.resolution_y = size
    r.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 64, False
    scene.cycles.max_bounces = 0
    scene.eevee.taa_render_samples = samples
    return scene, data


def mean_of_render(scene, engine, out):
    scene.render.engine = engine
    bpy.ops.render.render()
    path = os.path.join(out, "r.exr")
    s = scene.render.image_settings
    s.file_format, s.color_depth = "OPEN_EXR", "32"
    bpy.data.images["Render Result"].save_render(path)
    image = bpy.data.images.load(path)
    px = np.array(image.pixels[:], dtype=np.float64).reshape(-1, 4)
    bpy.data.images.remove(image)
    return float(np.mean(px[:, :3] @ np.array([0.2126, 0.7152, 0.0722])))


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
        cycles = mean_of_render(scene, "CYCLES", out)
        for shadow in (True, False):
            light.use_shadow = shadow
            result[f"{angle} {'on' if shadow else 'off'}"] = mean_of_render(scene, eevee_engine(), out) / cycles
        print(angle, result, flush=True)
    print("RESULT " + json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
