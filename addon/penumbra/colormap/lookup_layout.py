"""Where a lookup image (operators.BakePlan.spec: width, height, sigma_max,
mean_min, mean_max, sigma_spacing) keeps (mean, σ), as node arithmetic:
every group that samples a lookup reads it through lookup_uv."""


def lookup_uv(b, mean, sigma, spec):
    """(u, v) of (mean, σ) in a lookup image written with σ = 0 at the bottom row."""
    width, height = spec["width"], spec["height"]
    u = b.texel(b.math("MULTIPLY_ADD", mean, 1.0 / (spec["mean_max"] - spec["mean_min"]),
                       -spec["mean_min"] / (spec["mean_max"] - spec["mean_min"])), width)
    t = b.math("MULTIPLY", b.math("MAXIMUM", sigma, 0.0), 1.0 / spec["sigma_max"])
    t = b.math("MINIMUM", t, 1.0)
    if spec["sigma_spacing"] == "quadratic":
        t = b.math("SQRT", t)
    return u, b.texel(t, height)
