"""Colour-map filtering demo: a Noise Texture through a sharp ColorRamp on a
plane receding to the horizon; press "Bake Filtered Colour Map" (the operator
penumbra.bake_colormap_lut) and render the plain ramp and Penumbra's node
group at 4 samples per pixel, side by side. run(out_folder) -> dict."""

import os
import sys
import time

import bpy
import numpy as np

from penumbra import native

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import colormap_scene  # noqa: E402  (examples/colormap_scene.py)


def _scene(out_folder):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.cycles.samples = 4
    scene.render.resolution_x, scene.render.resolution_y = 192, 108
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.penumbra.colormap.output_folder = out_folder
    plane, material, ramp, emission, camera = colormap_scene.noise_ramp_plane()
    return scene, material, ramp, emission


def _render(scene, out_folder, name):
    scene.render.filepath = os.path.join(out_folder, name + ".exr")
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - started
    core = native.require()
    image = core.image.read(scene.render.filepath)
    srgb = np.where(image <= 0.0031308, 12.92 * image, 1.055 * np.power(np.clip(image, 0, None), 1 / 2.4) - 0.055)
    png = os.path.join(out_folder, name + ".png")
    core.image.write_png16(png, np.clip(srgb, 0, 1).astype(np.float32), "sRGB")
    return image, png, seconds


def run(out_folder):
    scene, material, ramp, emission = _scene(out_folder)
    plain, plain_png, plain_s = _render(scene, out_folder, "plain_ramp_4spp")
    started = time.perf_counter()
    result = bpy.ops.penumbra.bake_colormap_lut()
    bake_s = time.perf_counter() - started
    filtered, filtered_png, filtered_s = _render(scene, out_folder, "penumbra_4spp")
    group = material.node_tree.nodes["Penumbra Filtered Ramp"]
    return {
        "bake": sorted(result),
        "bake_seconds": round(bake_s, 3),
        "lookup_image": group.node_tree["penumbra_lookup"]["image"],
        "pictures": [plain_png, filtered_png],
        "render_seconds": {"plain": round(plain_s, 3), "penumbra": round(filtered_s, 3)},
        "far_half_pixel_std": {  # the sparkle in the distance: lower is calmer
            "plain": float(plain[: plain.shape[0] // 2].std(axis=(0, 1)).mean()),
            "penumbra": float(filtered[: filtered.shape[0] // 2].std(axis=(0, 1)).mean()),
        },
    }
