"""Debevec's median-cut light-probe sampling (2005) in numpy: the baseline the
light rig is measured against, by the light-rig benchmarks and by
tests/python/lights/test_lights.py in the same run. Not part of the add-on."""

import math

import numpy as np

from bench.helpers import test_videos as data
from bench.helpers.metrics import LUMINANCE


def median_cut(image, n):
    """Directions (n, 3) and rgb (n, 3) of median_cut_suns."""
    d, rgb, _ = median_cut_suns(image, n)
    return d, rgb


def median_cut_suns(image, n):
    """Debevec 2005: split the cosθ-weighted map into n regions of equal
    energy, cutting each region across its longest side (width measured as
    cos(latitude)·columns); a light at each region's energy centroid with the
    region's summed L·Ω, and its spread (RMS angular radius about the
    centroid, what the add-on makes a sun's angle from). n must be a power of
    two (it is here)."""
    h, w = image.shape[:2]
    omega = data.solid_angles(h, w)[:, None]
    flux = image * omega[..., None]                      # L·Ω per pixel
    lum = flux @ LUMINANCE
    sat = np.zeros((h + 1, w + 1))
    sat[1:, 1:] = lum.cumsum(0).cumsum(1)

    def energy(r0, r1, c0, c1):
        return sat[r1, c1] - sat[r0, c1] - sat[r1, c0] + sat[r0, c0]

    regions = [(0, h, 0, w)]
    while len(regions) < n:
        new = []
        for r0, r1, c0, c1 in regions:
            lat = math.sin(math.pi * (r0 + r1) / (2 * h))  # cos(latitude) at the region's middle
            width = (c1 - c0) * lat * 2.0  # columns span 2π, rows π
            if r1 - r0 < 2 and c1 - c0 < 2:
                new.append((r0, r1, c0, c1))
                continue
            total = energy(r0, r1, c0, c1)
            if (width >= (r1 - r0) and c1 - c0 >= 2) or r1 - r0 < 2:
                cuts = [energy(r0, r1, c0, c) for c in range(c0 + 1, c1)]
                k = c0 + 1 + int(np.argmin(np.abs(np.array(cuts) - total / 2)))
                new += [(r0, r1, c0, k), (r0, r1, k, c1)]
            else:
                cuts = [energy(r0, r, c0, c1) for r in range(r0 + 1, r1)]
                k = r0 + 1 + int(np.argmin(np.abs(np.array(cuts) - total / 2)))
                new += [(r0, k, c0, c1), (k, r1, c0, c1)]
        regions = new
    dirs = data.directions(h, w)
    out_d, out_rgb, out_spread = [], [], []
    for r0, r1, c0, c1 in regions:
        f = flux[r0:r1, c0:c1].reshape(-1, 3)
        l = lum[r0:r1, c0:c1].reshape(-1)
        d = dirs[r0:r1, c0:c1].reshape(-1, 3)
        m = (l[:, None] * d).sum(0)
        centroid = m / np.linalg.norm(m) if np.linalg.norm(m) > 0 else d[len(d) // 2]
        out_d.append(centroid)
        out_rgb.append(f.sum(0))
        # RMS angular radius about the centroid, as the rig's regions (the sun's angle).
        angle = np.arccos(np.clip(d @ centroid, -1.0, 1.0))
        out_spread.append(math.sqrt((l * angle ** 2).sum() / l.sum()) if l.sum() > 0 else 0.0)
    return np.array(out_d), np.array(out_rgb), np.array(out_spread)
