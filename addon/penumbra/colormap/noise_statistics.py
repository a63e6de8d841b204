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

_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "noise_statistics.json")
_data = None


def data():
    global _data
    if _data is None:
        with open(_PATH) as f:
            _data = json.load(f)
    return _data


def _table_for_this_blender():
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
    from . import node_groups
    name = f"Penumbra Noise Statistics d{detail:g} r{roughness:g}"
    stats = statistics(detail, roughness)
    n = len(stats["log2_footprint"])
    pixels = np.ones((1, n, 4), np.float32)
    pixels[0, :, 0] = stats["rho"]
    pixels[0, :, 1] = stats["sigma"]
    pixels[0, :, 2] = stats["mean"]
    return node_groups.table_image(name, pixels, folder), stats


def pixel_filter_stddev(scene):
    """Standard deviation, in pixels, of the render's pixel filter (one axis):
    Cycles' Blackman-Harris over `filter_width` pixels (0.2078 px at the
    default 1.5), Gaussian (about width/6) or box (width/√12)."""
    cycles = getattr(scene, "cycles", None)
    width = getattr(cycles, "filter_width", 1.5) if cycles else 1.5
    kind = getattr(cycles, "pixel_filter_type", "BLACKMAN_HARRIS") if cycles else "BLACKMAN_HARRIS"
    if kind == "BOX":
        return width / math.sqrt(12.0)
    if kind == "GAUSSIAN":
        return width / 6.0
    return 0.20776 * width / 1.5
