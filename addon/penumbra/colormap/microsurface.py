"""The microsurface table the height and slope filters read (paper Sec. 5):
a 256 × 2 image of the core's Smith Λ, visible-height and slope-shift
statistics, and the node arithmetic that samples it."""

import math

import bpy
import numpy as np

from .. import native
from .node_groups import MICROSURFACE_IMAGE
from .table_image import table_image

MICROSURFACE_TABLE_SIZE = 256


def microsurface_image(folder=None):
    """256 × 2 float image, 'Non-Color'. Row 0 (bottom) against u in [0, 1):
    R = Λ/(1+Λ) at a = u/(1−u) (a = cot θ / σ_s), G = μ_d/σ_h and
    B = σ_d/σ_h (exact) at Λ_sum = u/(1−u). Row 1: R = E[z], G = sd[z] of the
    slope filtering distribution at c = u/(1−u) (c = cot θ_o / σ_s)."""
    core = native.require()
    n = MICROSURFACE_TABLE_SIZE
    image = bpy.data.images.get(MICROSURFACE_IMAGE)
    if image is not None and tuple(image.size) == (n, 2) and image.has_data:
        return image
    u = np.arange(n) / (n - 1)
    u[-1] = 1.0 - 1.0 / (4 * n)  # Λ, c = ∞ stand-ins: the last texel
    x = u / (1.0 - u)
    pixels = np.ones((2, n, 4), np.float32)  # bottom-up rows
    for i, xi in enumerate(x):
        lam = core.colormap.smith_lambda_of_a(xi) if xi > 0 else math.inf
        pixels[0, i, 0] = 1.0 if math.isinf(lam) else lam / (1.0 + lam)
        mean, sd = core.colormap.effective_height(xi, "exact")
        pixels[0, i, 1], pixels[0, i, 2] = mean, sd
        pixels[1, i, 0], pixels[1, i, 1] = core.colormap.slope_shift(xi)
    return table_image(MICROSURFACE_IMAGE, pixels, folder)


def table_row(b, image, x, row):
    """Sample row `row` of the microsurface image at u = x / (1 + x) (x >= 0)."""
    x = b.math("MAXIMUM", x, 0.0)
    u = b.math("DIVIDE", x, b.math("ADD", x, 1.0))
    return b.separate(b.image(image, b.texel(u, MICROSURFACE_TABLE_SIZE), (row + 0.5) / 2.0, alpha=False)[0])


def cot_over_sigma(b, cos_theta, sigma):
    """cot θ / σ from cos θ (clamped to [0, 1])."""
    c = b.math("MINIMUM", b.math("MAXIMUM", cos_theta, 0.0), 1.0)
    sin = b.math("SQRT", b.math("MAXIMUM", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", c, c)), 1e-12))
    return b.math("DIVIDE", b.math("DIVIDE", c, sin), b.math("MAXIMUM", sigma, 1e-6))


def smith_lambda(b, image, a):
    g, _, _ = table_row(b, image, a, 0)
    return b.math("DIVIDE", g, b.math("MAXIMUM", b.math("SUBTRACT", 1.0, g), 1e-6))  # Λ = g / (1 − g)
