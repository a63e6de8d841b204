"""The "Penumbra Filtered Ramp" group (one per lookup image): Mean, Sigma ->
Color, Alpha, the colour map filtered by a Gaussian (or, after a Noise
Filter, a mixture of four), read from the lookup image bilinearly."""

from .lookup_layout import lookup_uv
from .node_builder import Builder, new_group, zero_after
from .node_groups import FILTERED_RAMP
from .noise_maths import MIXTURE_COMPONENTS
from .point_filter import select


def filtered_ramp_group(image, spec, name=FILTERED_RAMP, mixture=False, single_fetch=False, point=False,
                        with_mixture=True):
    """Mean, Sigma -> Color, Alpha from `image` (a lookup with `spec`: width,
    height, sigma_max, mean_min, mean_max, sigma_spacing).

    mixture=True adds the inputs Offsets and Variances (vectors, default 0):
    the colour is then the average of the lookup over MIXTURE_COMPONENTS
    Gaussians N(Mean + δ_k, Sigma² + ε_k), (δ_k, ε_k) for k = 1..3 the
    vectors' components and, the four having the mixture's mean Mean and
    variance Sigma², δ_4 = −(δ_1 + δ_2 + δ_3), ε_4 = −(ε_1 + ε_2 + ε_3) −
    Σ_k δ_k². Left at zero, that is the one Gaussian N(Mean, Sigma²).

    point=True (with mixture=True): one more input, Mixture, the Noise
    Filter's: the mixture where it is 1 (one sample), the one Gaussian
    N(Mean, Sigma²) where it is 0, chosen by a Mix that Cycles folds
    (point_filter.select). with_mixture=False: the same inputs, the one
    Gaussian only (the group for more than one sample, sample_count.py).

    single_fetch=True (the one Gaussian): one Image Texture set to Linear
    instead of four Closest fetches interpolated in nodes: the same numbers
    in Cycles (bilinear between texel centres, no mipmaps) for about a
    sixth of the nodes, but EEVEE would read it through mipmaps (see
    node_builder.Builder.texel_fetch), so the bake uses it for Cycles only."""
    inputs = [("Mean", "NodeSocketFloat", 0.5), ("Sigma", "NodeSocketFloat", 0.0)]
    if mixture:
        inputs += [("Offsets", "NodeSocketVector", (0.0, 0.0, 0.0)), ("Variances", "NodeSocketVector", (0.0, 0.0, 0.0))]
    if mixture and point:
        inputs += [("Mixture", "NodeSocketFloat", 0.0)]
    group, gin, gout = new_group(name, inputs, [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat")])
    b = Builder(group)
    mean, sigma = gin.outputs["Mean"], gin.outputs["Sigma"]
    if single_fetch and (point or not mixture):
        node = b.texel_fetch(image, *lookup_uv(b, mean, sigma, spec))
        node.interpolation = "Linear"
        color, alpha = node.outputs["Color"], node.outputs["Alpha"]
    elif point or not mixture:
        color, alpha = b.image(image, *lookup_uv(b, mean, sigma, spec))
    if mixture and with_mixture:
        mixed = _mixture_lookup(b, image, spec, mean, sigma, gin.outputs["Offsets"], gin.outputs["Variances"])
        if point:
            which = gin.outputs["Mixture"]
            color, alpha = select(b, which, color, mixed[0], "RGBA"), select(b, which, alpha, mixed[1])
        else:
            color, alpha = mixed
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    group["penumbra_lookup"] = dict(spec, image=image.name)
    return group


def _mixture_lookup(b, image, spec, mean, sigma, offsets, variances):
    """The average of the lookup over the mixture's four components (see
    filtered_ramp_group), each fetched after the previous one (zero_after)."""
    d = b.separate(offsets)
    e = b.separate(variances)
    d4 = b.math("MULTIPLY", b.math("ADD", b.math("ADD", d[0], d[1]), d[2]), -1.0)
    squares = b.math("MULTIPLY_ADD", d4, d4, b.math("MULTIPLY_ADD", d[2], d[2], b.math(
        "MULTIPLY_ADD", d[1], d[1], b.math("MULTIPLY", d[0], d[0]))))
    e4 = b.math("SUBTRACT", b.math("MULTIPLY", b.math("ADD", b.math("ADD", e[0], e[1]), e[2]), -1.0), squares)
    variance = b.math("MULTIPLY", sigma, sigma)
    color, alpha = None, None
    for offset, extra in zip(d + (d4,), e + (e4,)):
        component_mean = b.math("ADD", mean, offset)
        if alpha is not None:
            component_mean = b.math("ADD", component_mean, zero_after(b, alpha))
        component_sigma = b.math("SQRT", b.math("MAXIMUM", b.math("ADD", variance, extra), 0.0))
        c, a = b.image(image, *lookup_uv(b, component_mean, component_sigma, spec))
        color = c if color is None else b.vmath("ADD", color, c)
        alpha = a if alpha is None else b.math("ADD", alpha, a)
    share = 1.0 / MIXTURE_COMPONENTS
    return b.vscale(color, share), b.math("MULTIPLY", alpha, share)
