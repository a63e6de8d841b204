"""The band-limited Noise Filter (preset "1 Noise"): the user's own noise as
ONE Blender Noise Texture whose Detail is linked to the octaves the sample
resolves, so the renderer's fBm loop stops before the octaves finer than the
sample's kernel, and their variance is carried analytically into the one
lookup (the paper's "one noise evaluation that leaves out the octaves above
the pixel's frequency"). Applies to a normalized fBm Noise Texture with
Detail above 1 (noise_maths.fbm_detail_roughness); other noises use the
one-evaluation filter (point_filter.py). See docs/colormap.md."""

import math

from . import interface, noise_maths
from .noise_maths import OCTAVE_CORRELATION_LENGTH

# Where the Detail is cut: D' = x + DETAIL_BIAS (x: see native_estimate;
# at D' = x octave D' has its kernel-averaged correlation, noise_maths.
# point_shrinkage, near 1/√2). Measured on the benchmark plane at 96×54
# (equal-time ratios at 16 and 64 spp): −1: 1.02, 1.11; 0: 0.93, 0.90;
# 0.5: 0.87, 0.86; 1: 0.87, 0.87 (docs/colormap.md).
DETAIL_BIAS = 0.5


def applies(model):
    """Whether a native Noise Texture with a lower Detail is `model` with its
    finest octaves left out: a normalized fBm Noise Texture whose Detail and
    Roughness the coefficients give back, with octaves that grow finer
    (Lacunarity above 1: x is a logarithm in it). Musgrave (3.4), the 4.1+
    types, an unnormalized noise and Detail up to 1 are not."""
    return model.node_type == "ShaderNodeTexNoise" and model.noise_type == "FBM" and model.offset == 0.5 \
        and model.lacunarity > 1.01 and noise_maths.fbm_detail_roughness(model.coefficients) is not None


def native_estimate(b, gin, model, total_var, filter_stddev_px, share):
    """(mean, sigma) of the noise under the sample's kernel: one Noise
    Texture at Detail D' ≤ D, mapped so its kept octaves have the model's
    weights (band_limited_terms). The kernel enters through one number,
    x = −½ log_L((1 + m²)(1 + M²) − 1) (m, M: its axes over the octave
    correlation length at Scale 1); Detail, the mean's scale and Sigma are
    functions of x alone, read from three Float Curves (a table each in
    the renderer) instead of some forty arithmetic nodes per sample. The
    curves read u = ln s = −2 ln(L)·x, s = m² + M²(1 + m²): seven Math
    nodes per sample where x took ten (measured on the 96×54 plane at 64
    spp: 0.199 CPU s against 0.208, the same image; docs/colormap-benchmark.md,
    "Tried on the default")."""
    detail, roughness = noise_maths.fbm_detail_roughness(model.coefficients)
    units = b.math("MULTIPLY", b.math("MULTIPLY", gin.outputs["Scale"], gin.outputs["Units per World"]),
                   b.math("MULTIPLY", share, filter_stddev_px / OCTAVE_CORRELATION_LENGTH))
    minor = b.math("MULTIPLY", gin.outputs["Point Minor"], units)
    # Point Major ≥ Point Minor (point_footprint.py divides by |N·I| ≤ 1).
    major = b.math("MULTIPLY", gin.outputs["Point Major"], units)
    # (1 + m²)(1 + M²) − 1 without the cancellation of the subtraction; the
    # 1e-30 keeps the logarithm finite for a zero footprint (full Detail).
    spread = b.math("MULTIPLY_ADD", b.math("MULTIPLY", major, major), b.math("MULTIPLY_ADD", minor, minor, 1.0),
                    b.math("MULTIPLY_ADD", minor, minor, 1e-30))
    u = b.math("LOGARITHM", spread, math.e)
    grid = curve_grid(detail)
    terms = [noise_maths.band_limited_terms(v, model.coefficients, detail, roughness, model.lacunarity, total_var,
                                               DETAIL_BIAS) for v in grid]
    u_grid = [-2.0 * math.log(model.lacunarity) * v for v in reversed(grid)]
    cut, scale, sigma = (_curve(b, u, u_grid, [t[k] for t in reversed(terms)]) for k in range(3))
    noise = _noise_node(b, gin, model, roughness, cut)
    mean = b.math("MULTIPLY_ADD", b.math("SUBTRACT", noise, 0.5), scale, 0.5)
    return mean, sigma


def curve_grid(detail, step=0.125):
    """The x of the curves' points: from where octave 0 is averaged away
    (g₀ ≈ 1/256) to two octaves past full Detail (beyond, the curves hold
    their ends)."""
    low, high = -8.0, detail + 2.0 - DETAIL_BIAS
    count = int(math.ceil((high - low) / step))
    return [low + (high - low) * i / count for i in range(count + 1)]


def _curve(b, x, grid, values):
    """A Float Curve through (grid, values) (grid increasing), straight
    between its points, held at its ends."""
    node = b.place(b.nodes.new("ShaderNodeFloatCurve"))
    mapping = node.mapping
    mapping.use_clip = False
    mapping.extend = "HORIZONTAL"
    curve = mapping.curves[0]
    while len(curve.points) < len(grid):
        curve.points.new(0.0, 0.0)
    for point, gx, value in zip(curve.points, grid, values):
        point.location = (gx, value)
        point.handle_type = "VECTOR"
    mapping.update()
    interface.input_socket(node, "Factor").default_value = 1.0
    b.connect(x, interface.input_socket(node, "Value"))
    return node.outputs["Value"]


def _noise_node(b, gin, model, roughness, detail):
    """The user's noise (normalized fBm, its Distortion, Roughness and
    Lacunarity) with Detail linked to `detail`: its Fac."""
    node = b.place(b.nodes.new("ShaderNodeTexNoise"))
    node.noise_dimensions = model.dimensions
    if hasattr(node, "noise_type"):
        node.noise_type = "FBM"
    if hasattr(node, "normalize"):
        node.normalize = True
    for identifier, value in (("Roughness", roughness), ("Lacunarity", model.lacunarity),
                              ("Distortion", model.distortion)):
        socket = interface.input_socket(node, identifier)
        if socket is not None:      # 3.4 has no Lacunarity
            socket.default_value = value
    if model.uses_vector:
        b.connect(gin.outputs["Vector"], interface.input_socket(node, "Vector"))
    if model.uses_w:
        b.connect(gin.outputs["W"], interface.input_socket(node, "W"))
    b.connect(gin.outputs["Scale"], interface.input_socket(node, "Scale"))
    b.connect(detail, interface.input_socket(node, "Detail"))
    return node.outputs["Fac"]
