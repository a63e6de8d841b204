"""Rendering for the demo's contact sheets, shared by examples/demo_<tool>.py
(inside Blender): Cycles on the CPU with few samples, renders written as
EXR and read back with their alpha, and renders turned into display
pictures through Blender's own OpenColorIO config."""

import bpy
import numpy as np

from penumbra import color


def use_cycles(scene, width, height, transparent=False):
    """Cycles on the CPU at width × height, no denoiser (Debian's Blender has
    no OpenImageDenoise), every sample taken (no adaptive stop), small tiles,
    EXR output."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    if hasattr(scene.cycles, "tile_size"):
        scene.cycles.use_auto_tile = True
        scene.cycles.tile_size = 128
    scene.render.film_transparent = transparent
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"


def render(scene, path, samples, seed=0):
    """Renders the scene camera to `path` (EXR) and returns its pixels
    (H, W, 4), scene-linear RGB and alpha, row 0 at the top."""
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return read_rgba(path)


def read_rgba(path):
    """An EXR's RGBA through Blender's image loader (the core's reader keeps
    RGB only, and the sheets need the alpha of transparent renders)."""
    image = bpy.data.images.load(path, check_existing=False)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
    finally:
        bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[::-1].copy()  # Blender's rows are bottom-up


def display(rgb, exposure=0.0):
    """Scene-linear render RGB (in this file's working space) → sRGB display
    values in [0, 1], through Blender's config; `exposure` in stops."""
    config = color.blender_config()
    scaled = np.ascontiguousarray(np.asarray(rgb, dtype=np.float32)[..., :3] * 2.0 ** exposure)
    return np.clip(config.convert(scaled, color.working_space(config), "sRGB"), 0.0, 1.0)


def unpremultiply(rgba):
    """RGB of a transparent render divided by its coverage (0 where empty)."""
    alpha = rgba[..., 3:4]
    return np.where(alpha > 1e-4, rgba[..., :3] / np.maximum(alpha, 1e-4), 0.0).astype(np.float32)
