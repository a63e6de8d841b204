"""Error measures shared by the light-rig benchmarks and tests."""

import math

import numpy as np

# Rec. 709 / sRGB luminance weights of linear RGB (Blender's scene-linear primaries).
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def rel_rmse(estimate, reference):
    """Relative RMSE on luminance of linear RGB (..., 3) against `reference`:
    sqrt(Σ ΔY²) / sqrt(Σ Y_ref²) over every leading index (normals, pixels)."""
    difference = (np.asarray(estimate) - reference) @ LUMINANCE
    luminance = np.asarray(reference) @ LUMINANCE
    return math.sqrt(float((difference ** 2).sum() / (luminance ** 2).sum()))
