"""The one-evaluation Noise Filter (quality presets with one tap): the
paper's "few lines of shader code". Each octave is evaluated once, at the
sample, and shrunk towards its mean by how much of it the sample's kernel
averages away; what it loses is carried as variance into one lookup. No
table: the shrinkage is closed form (noise_maths.point_shrinkage), so a
sample costs one noise evaluation and a handful of arithmetic nodes more
than the plain ramp. See docs/colormap.md, "One evaluation per sample"."""

from . import noise_nodes
from .noise_maths import OCTAVE_CORRELATION_LENGTH


def point_estimate(b, gin, model, total_var, filter_stddev_px, share, analytic_octaves=0):
    """(mean, variance) of the noise under the sample's kernel N(P, τ²),
    τ = share·κ, from the octaves' values at P (group inputs Point Minor and
    Point Major: the footprint's axes, point_footprint.py).

    Octave i, correlation ρ(d) ≈ exp(−d²/2l²) (l = OCTAVE_CORRELATION_LENGTH
    at Scale 1, fitted to the measured table of noise_statistics.json), seen
    through a kernel of standard deviations t_j·L^i (t = τ·Minor, τ·Major in
    noise units): g_i = E_kernel[ρ] = Π_j (1 + (t_j L^i/l)²)^(−1/2) is the
    regression of the kernel's values on the value at P, and 1 − g_i² their
    variance left around g_i·(Fac_i − 0.5), averaged over Fac_i. Mean =
    offset + Σ c_i g_i (Fac_i − 0.5), variance = V₀ Σ c_i² (1 − g_i²).
    The finest `analytic_octaves` octaves are not evaluated (g = 0): their
    whole variance is carried."""
    coefficients, lacunarity = model.coefficients, model.lacunarity
    units = b.math("MULTIPLY", b.math("MULTIPLY", gin.outputs["Scale"], gin.outputs["Units per World"]),
                   b.math("MULTIPLY", share, filter_stddev_px / OCTAVE_CORRELATION_LENGTH))
    minor = b.math("MULTIPLY", gin.outputs["Point Minor"], units)
    major = b.math("MULTIPLY", b.math("MAXIMUM", gin.outputs["Point Major"], gin.outputs["Point Minor"]), units)
    minor_sq, major_sq = b.math("MULTIPLY", minor, minor), b.math("MULTIPLY", major, major)
    evaluated = max(len(coefficients) - analytic_octaves, 0)
    coordinates = noise_nodes.distorted_vector(b, gin.outputs["Vector"], gin.outputs["Scale"], model,
                                               gin.outputs["W"]) if evaluated else None
    if coordinates is not None:
        # Scaled once here, so each octave's Scale is a constant lacunarity^i
        # (one node fewer per octave: the same point, as Blender computes p·Scale).
        coordinates = noise_nodes.Coordinates(
            b.vscale(coordinates.vector, gin.outputs["Scale"]) if model.uses_vector else coordinates.vector,
            b.math("MULTIPLY", coordinates.w, gin.outputs["Scale"]) if model.uses_w else coordinates.w)
    mean, kept = 0.0, 0.0       # kept: Σ c_i² g_i², the variance the values carry
    for i, c in enumerate(coefficients[:evaluated]):
        growth = lacunarity ** (2 * i)
        spread = b.math("MULTIPLY", b.math("MULTIPLY_ADD", minor_sq, growth, 1.0),
                        b.math("MULTIPLY_ADD", major_sq, growth, 1.0))
        g = b.math("POWER", spread, -0.5)
        fac = noise_nodes.octave_fac(b, coordinates, lacunarity ** i, model)
        mean = b.math("MULTIPLY_ADD", b.math("SUBTRACT", fac, 0.5), b.math("MULTIPLY", g, c), mean)
        kept = b.math("MULTIPLY_ADD", b.math("MULTIPLY", g, g), c * c, kept)
    total = sum(c * c for c in coefficients)
    variance = b.math("MULTIPLY", b.math("SUBTRACT", total, kept), total_var)
    return b.math("ADD", mean, model.offset), variance


def select(b, factor, a, b_value, data_type="FLOAT"):
    """a where `factor` is 0, b_value where it is 1, through a Mix node:
    with a factor that is a constant for the render (the Samples driver),
    Cycles' constant folding bypasses the Mix and removes the other branch,
    so the branch not taken costs nothing per sample (measured:
    docs/colormap.md, "One evaluation per sample")."""
    node = b.place(b.nodes.new("ShaderNodeMix"))
    node.data_type = data_type
    node.blend_type = "MIX"
    node.clamp_factor = False
    suffix = "_Float" if data_type == "FLOAT" else "_Color"
    sockets = {s.identifier: s for s in node.inputs}
    b.connect(factor, sockets["Factor_Float"])
    b.connect(a, sockets["A" + suffix])
    b.connect(b_value, sockets["B" + suffix])
    return next(s for s in node.outputs if s.identifier == "Result" + suffix)
