"""Blender's Noise Texture statistics over a pixel footprint, measured once by
scripts/colormap_measure_noise.py into noise_statistics.json, interpolated
here for a noise's Detail and Roughness and handed to node groups as a small
lookup image (R = ρ, G = σ_f, B = mean μ, against log2 of the footprint's
standard deviation in noise units). See docs/colormap.md."""

import json
import math
import os

import bpy
import numpy as np

from . import noise_maths
from .table_image import table_image

_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "noise_statistics.json")
_data = None


def data():
    global _data
    if _data is None:
        with open(_PATH) as f:
            _data = json.load(f)
    return _data


def _table_for_this_blender():
    # The nearest measured version. Blender 5.x reads 4.5's: its Noise Texture
    # is unchanged (scripts/colormap_measure_noise.py run in bpy 5.2.3 gives
    # 4.5's tables to within 7e-16, octave table identical).
    versions = data()["blender"]
    here = bpy.app.version[:2]
    key = min(versions, key=lambda v: abs(int(v.split(".")[0]) * 100 + int(v.split(".")[1]) - (here[0] * 100 + here[1])))
    return versions[key]["table"]


def statistics(detail, roughness):
    """dict(log2_footprint, rho, sigma, mean, total_std, min, max), bilinear in
    (detail, roughness) between the measured settings (clamped to their range)."""
    d = data()
    table = _table_for_this_blender()
    details, roughnesses = d["details"], d["roughnesses"]

    def bracket(values, x):
        x = min(max(x, values[0]), values[-1])
        i = max(0, min(len(values) - 2, int(np.searchsorted(values, x, side="right")) - 1))
        t = (x - values[i]) / (values[i + 1] - values[i])
        return i, t

    i, ti = bracket(details, detail)
    j, tj = bracket(roughnesses, roughness)

    def entry(a, b):
        return table[f"{details[a]:g}/{roughnesses[b]:g}"]

    out = {"log2_footprint": list(d["log2_footprint"])}
    for key in ("rho", "sigma", "mean", "total_std", "min", "max"):
        corners = [np.asarray(entry(a, b)[key], float) for a in (i, i + 1) for b in (j, j + 1)]
        value = ((1 - ti) * ((1 - tj) * corners[0] + tj * corners[1]) +
                 ti * ((1 - tj) * corners[2] + tj * corners[3]))
        out[key] = value.tolist() if value.ndim else float(value)
    return out


def statistics_image(detail, roughness, folder=None):
    """The 1D image a node group samples ('Non-Color', EXTEND), one per setting."""
    name = f"Penumbra Noise Statistics d{detail:g} r{roughness:g}"
    stats = statistics(detail, roughness)
    n = len(stats["log2_footprint"])
    pixels = np.ones((1, n, 4), np.float32)
    pixels[0, :, 0] = stats["rho"]
    pixels[0, :, 1] = stats["sigma"]
    pixels[0, :, 2] = stats["mean"]
    return table_image(name, pixels, folder), stats


def pixel_filter_stddev(scene):
    """Standard deviation, in pixels, of the render's pixel filter (one axis).
    Cycles (scene/film.cpp, filter_table) builds Blackman-Harris over twice
    `filter_width` (so its support is ±width: σ = 0.2770·width, 0.4155 px at
    the default 1.5), the Gaussian over 3·width (exp(−8 v²/width²):
    σ = width/4) and the box over width (σ = width/√12). EEVEE Legacy
    (eevee_temporal_sampling.c) jitters its samples by the inverse CDF of
    Blackman-Harris scaled to ±render.filter_size pixels (the table spans
    ±2, times filter_size, applied as an NDC shift of ofs/size, half that in
    pixels): σ = 0.2770·filter_size, its first sample at the pixel centre."""
    if scene.render.engine in ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"):
        return 0.27701 * scene.render.filter_size
    cycles = getattr(scene, "cycles", None)
    width = getattr(cycles, "filter_width", 1.5) if cycles else 1.5
    kind = getattr(cycles, "pixel_filter_type", "BLACKMAN_HARRIS") if cycles else "BLACKMAN_HARRIS"
    if kind == "BOX":
        return width / math.sqrt(12.0)
    if kind == "GAUSSIAN":
        return width / 4.0
    return 0.27701 * width


# ---- octave-wise filter (docs/colormap.md, "Octave filter") ---------------

def octave_table():
    """dict(log2_footprint, log2_elongation, q [elongation][footprint],
    total_var): one octave's within-footprint variance fraction, measured."""
    d = data()
    versions = d["blender"]
    here = bpy.app.version[0] * 100 + bpy.app.version[1]
    key = min(versions, key=lambda v: abs(int(v.split(".")[0]) * 100 + int(v.split(".")[1]) - here))
    octave = versions[key]["octave"]
    return {"log2_footprint": list(d["log2_footprint"]), "log2_elongation": list(d["log2_elongation"]),
            "q": octave["q"], "total_var": octave["total_var"]}


def octave_image(folder=None):
    """The table as an image (x: log2 of the footprint's minor standard
    deviation in octave units, y: log2 major/minor; R = q clamped to [0, 1])."""
    table = octave_table()
    q = np.clip(np.asarray(table["q"], np.float32), 0.0, 1.0)
    pixels = np.ones(q.shape + (4,), np.float32)
    pixels[..., 0] = q
    pixels[..., 1] = q
    pixels[..., 2] = q
    # table_image takes rows bottom-up: row 0 (elongation 1) is the bottom, v = 0.
    return table_image("Penumbra Noise Octave Statistics", pixels, folder), table


def filtered_sigma_max(detail, roughness):
    """Largest σ the octave filter produces: every octave averaged out."""
    total = octave_table()["total_var"]
    return math.sqrt(total * sum(w * w for w in noise_maths.octave_weights(detail, roughness, bpy.app.version)))
