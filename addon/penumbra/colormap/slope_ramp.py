"""The "Penumbra Slope Filtered Ramp" group (paper Sec. 5.2): the colour map
driven by the microfacet slope, filtered over the facets the viewer sees."""

from . import microsurface
from .lookup_layout import lookup_uv
from .node_builder import Builder, new_group
from .node_groups import SLOPE_RAMP


def slope_ramp_group(lookup_image, spec, name=SLOPE_RAMP):
    """Paper Sec. 5.2: the ramp driven by v = Value at Zero Slope + Value per
    Slope · (s · Direction), s the microfacet slope (isotropic, σ_s), filtered
    over the facets the viewer sees: along the view's azimuth d the slope
    shifts by σ_s E[z] and narrows to σ_s sd[z] (microsurface.hpp), so
    v ~ N(v0 + k σ_s E[z] cos ψ, (k σ_s)² (1 − (1 − sd²) cos² ψ)), ψ the angle
    between d and Direction projected onto the surface (s · Direction means
    the slope along that unit tangent). Value Sigma is the value's own spread
    over the pixel (the Noise Filter's Sigma), independent of the facets'
    slopes, so the variances add."""
    group, gin, gout = new_group(name, [("Value at Zero Slope", "NodeSocketFloat", 0.5),
                                        ("Value per Slope", "NodeSocketFloat", 1.0),
                                        ("Slope Sigma", "NodeSocketFloat", 0.3),
                                        ("Direction", "NodeSocketVector", (1.0, 0.0, 0.0)),
                                        ("Value Sigma", "NodeSocketFloat", 0.0)],
                                 [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat")])
    b = Builder(group)
    table = microsurface.microsurface_image()
    geometry = b.nodes.new("ShaderNodeNewGeometry")
    normal = geometry.outputs["Normal"]
    incoming = geometry.outputs["Incoming"]
    cos_o = b.vmath("DOT_PRODUCT", incoming, normal)
    tangential = b.vmath("SUBTRACT", incoming, b.vscale(normal, cos_o))
    d = b.vmath("NORMALIZE", tangential)
    # The slope is taken along Direction's projection onto the surface (a
    # world vector is rarely tangent to a tilted surface): the unit tangent.
    raw = gin.outputs["Direction"]
    direction = b.vmath("NORMALIZE", b.vmath("SUBTRACT", raw, b.vscale(normal, b.vmath("DOT_PRODUCT", raw, normal))))
    cos_psi = b.vmath("DOT_PRODUCT", d, direction)
    ez, sdz, _ = microsurface.table_row(b, table, microsurface.cot_over_sigma(b, cos_o, gin.outputs["Slope Sigma"]), 1)
    k_sigma = b.math("MULTIPLY", gin.outputs["Value per Slope"], gin.outputs["Slope Sigma"])
    mean = b.math("MULTIPLY_ADD", b.math("MULTIPLY", k_sigma, ez), cos_psi, gin.outputs["Value at Zero Slope"])
    shrink = b.math("MULTIPLY", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", sdz, sdz)),
                    b.math("MULTIPLY", cos_psi, cos_psi))
    slope_variance = b.math("MULTIPLY", b.math("MULTIPLY", k_sigma, k_sigma),
                            b.math("MAXIMUM", b.math("SUBTRACT", 1.0, shrink), 0.0))
    sigma = b.math("SQRT", b.math("MULTIPLY_ADD", gin.outputs["Value Sigma"], gin.outputs["Value Sigma"],
                                  slope_variance))
    color, alpha = b.image(lookup_image, *lookup_uv(b, mean, sigma, spec))
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    group["penumbra_lookup"] = dict(spec, image=lookup_image.name)
    return group
