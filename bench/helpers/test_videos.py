"""Test data for the light-rig tool, made from Blender's bundled HDR worlds
(datafiles/studiolights/world/*.exr) and from synthetic maps with known
irradiance: the one maker the light-rig tests (tests/python/lights/,
tests/blender/lights_scenes.py) and benchmarks (bench/lights_*_benchmark.py)
import. `scripts/lights_make_test_videos.py OUT` writes a set into a folder.

Every frame is scene-linear radiance in Blender's equirectangular convention.
Effects (all deterministic):
  rotation     the map turns about +Z by `degrees_per_frame`
  crossfade    linear blend from map A to map B
  exposure     exposure ramp, 2^(stops · t/(n−1))
  flicker      mains flicker: brightness · (1 + depth·sin(2π·100 Hz·t/fps)),
               a 50 Hz supply lights lamps at 100 Hz, aliased by the frame rate
  noise        multiplicative Gaussian sensor noise (seeded)
Videos: frames are tone-compressed x/(1+x), encoded to sRGB with OpenColorIO
(Blender's config) and written losslessly (PNG in .mov) with the ffmpeg CLI; a
video is display-referred, so reading it back needs colorspace "sRGB" and
only recovers the compressed range (see docs/lights.md)."""

import math
import os
import shutil
import subprocess
import tempfile

import numpy as np

from bench.helpers.paths import ROOT, compiled_core

_penumbra = compiled_core()

WORLD_FOLDERS = (
    "/usr/share/blender/datafiles/studiolights/world",
    os.path.join(ROOT, ".venv/lib/python3.11/site-packages/bpy/4.5/datafiles/studiolights/world"),
)
WORLDS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


def world_path(name):
    for folder in WORLD_FOLDERS:
        path = os.path.join(folder, name + ".exr")
        if os.path.isfile(path):
            return path
    raise FileNotFoundError(f"Blender's bundled world '{name}.exr' was not found in {WORLD_FOLDERS}")


def load_world(name, width=None):
    """A bundled world, optionally reduced (area-weighted) to `width` columns."""
    image = _penumbra.image.read(world_path(name))
    if width and width < image.shape[1]:
        f = image.shape[1] // width
        h, w = image.shape[0] // f, image.shape[1] // f
        image = image[: h * f, : w * f].reshape(h, f, w, f, 3)
        # Weight rows by solid angle inside each block so energy is kept.
        theta = (np.arange(h * f) + 0.5) / (h * f) * math.pi
        weight = np.sin(theta).reshape(h, f, 1, 1, 1)
        image = ((image * weight).sum(axis=(1, 3)) / (weight.sum(axis=1).reshape(h, 1, 1) * f)).astype(np.float32)
    return image


def directions(height, width):
    """Unit direction of each pixel centre, Blender's convention."""
    theta = (np.arange(height) + 0.5) / height * math.pi
    phi = math.pi - 2 * math.pi * (np.arange(width) + 0.5) / width
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def solid_angles(height, width):
    """Exact solid angle of each row's pixels (H,)."""
    edges = np.arange(height + 1) / height * math.pi
    return (2 * math.pi / width) * (np.cos(edges[:-1]) - np.cos(edges[1:]))


def sky(height, width, radiance=1.0):
    """Uniform sky over the whole sphere: E(n) = π·radiance for every normal."""
    return np.full((height, width, 3), radiance, dtype=np.float32)


def sun_disc(height, width, sun, radius, radiance, sky_radiance=0.0):
    """A disc of angular radius `radius` around `sun` (cell centres inside),
    over a uniform sky (`sky_radiance`: grey, or an RGB triple):
    E(n) = E_sun·cos + π·sky for a normal seeing the whole disc."""
    d = directions(height, width)
    s = np.asarray(sun, dtype=float)
    s = s / np.linalg.norm(s)
    inside = d @ s >= math.cos(radius)
    image = np.full((height, width, 3), sky_radiance, dtype=np.float32)
    image[inside] = radiance
    return image


def rotation_frames(image, frames, degrees_per_frame):
    return [_penumbra.lights.rotate_map_z(image, math.radians(degrees_per_frame * i)) for i in range(frames)]


def crossfade_frames(a, b, frames):
    return [((1 - t) * a + t * b).astype(np.float32) for t in np.linspace(0.0, 1.0, frames)]


def exposure_frames(image, frames, stops):
    return [(image * 2.0 ** (stops * i / max(1, frames - 1))).astype(np.float32) for i in range(frames)]


def flicker_frames(image, frames, fps, depth=0.2, mains_hz=50.0):
    return [(image * (1 + depth * math.sin(2 * math.pi * 2 * mains_hz * i / fps))).astype(np.float32)
            for i in range(frames)]


def noisy(frames, sigma=0.05, seed=1):
    rng = np.random.default_rng(seed)
    return [np.maximum(0, f * (1 + sigma * rng.standard_normal(f.shape))).astype(np.float32) for f in frames]


def write_map(path, image):
    """One map as a float EXR in Blender's scene-linear space; returns `path`."""
    _penumbra.image.write_exr(path, np.asarray(image, np.float32), half=False, colorspace="Linear")
    return path


def write_sequence(folder, frames, stem="frame_"):
    """frame_0001.exr ... (float EXR); returns the first frame's path."""
    os.makedirs(folder, exist_ok=True)
    paths = [write_map(os.path.join(folder, f"{stem}{i:04d}.exr"), f) for i, f in enumerate(frames, start=1)]
    return paths[0]


def write_video(path, frames, fps=21, config_path=None):
    """Lossless .mov (PNG frames, 16-bit) of x/(1+x) in sRGB, through ffmpeg."""
    if shutil.which("ffmpeg") is None:
        raise RuntimeError("the ffmpeg command is needed to make test videos (apt install ffmpeg)")
    config = _penumbra.color.Config(config_path or "/usr/share/blender/datafiles/colormanagement/config.ocio")
    with tempfile.TemporaryDirectory() as tmp:
        for i, f in enumerate(frames):
            display = config.convert((f / (1 + f)).astype(np.float32), config.scene_linear, "sRGB")
            _penumbra.image.write_png16(os.path.join(tmp, f"f{i:04d}.png"), display, colorspace="sRGB")
        subprocess.run(["ffmpeg", "-loglevel", "error", "-y", "-framerate", str(fps), "-i",
                        os.path.join(tmp, "f%04d.png"), "-c:v", "png", "-pix_fmt", "rgb48be", path], check=True)
    return path

