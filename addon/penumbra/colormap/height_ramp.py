"""The "Penumbra Height Filtered Ramp" group (paper Sec. 5.1): the colour map
filtered over the micro-heights the viewer sees and the light reaches."""

from . import microsurface
from .lookup_layout import lookup_uv
from .node_builder import Builder, new_group
from .node_groups import HEIGHT_RAMP


def height_ramp_group(lookup_image, spec, name=HEIGHT_RAMP):
    """Paper Sec. 5.1: Height Mean (the ramp's input at the mean surface),
    Height Sigma σ_h, Slope Sigma σ_s, Light Direction (world) -> Color (the
    ramp filtered over the visible and lit heights, N(mean + μ_d σ_h, σ_d σ_h))
    and Visibility V̄ (Eq. 13)."""
    group, gin, gout = new_group(name, [("Height Mean", "NodeSocketFloat", 0.5),
                                        ("Height Sigma", "NodeSocketFloat", 0.1),
                                        ("Slope Sigma", "NodeSocketFloat", 0.3),
                                        ("Light Direction", "NodeSocketVector", (0.0, 0.0, 1.0))],
                                 [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat"),
                                  ("Visibility", "NodeSocketFloat")])
    b = Builder(group)
    table = microsurface.microsurface_image()
    geometry = b.nodes.new("ShaderNodeNewGeometry")
    normal = geometry.outputs["Normal"]
    cos_o = b.vmath("DOT_PRODUCT", geometry.outputs["Incoming"], normal)
    cos_i = b.vmath("DOT_PRODUCT", b.vmath("NORMALIZE", gin.outputs["Light Direction"]), normal)
    lam_o = microsurface.smith_lambda(b, table, microsurface.cot_over_sigma(b, cos_o, gin.outputs["Slope Sigma"]))
    lam_i = microsurface.smith_lambda(b, table, microsurface.cot_over_sigma(b, cos_i, gin.outputs["Slope Sigma"]))
    lam_sum = b.math("ADD", lam_o, lam_i)
    _, mu_d, sigma_d = microsurface.table_row(b, table, lam_sum, 0)
    mean = b.math("MULTIPLY_ADD", mu_d, gin.outputs["Height Sigma"], gin.outputs["Height Mean"])
    sigma = b.math("MULTIPLY", sigma_d, gin.outputs["Height Sigma"])
    color, alpha = b.image(lookup_image, *lookup_uv(b, mean, sigma, spec))
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    one_plus_o = b.math("ADD", lam_o, 1.0)
    b.links.new(b.math("DIVIDE", one_plus_o, b.math("ADD", one_plus_o, lam_i)), gout.inputs["Visibility"])
    group["penumbra_lookup"] = dict(spec, image=lookup_image.name)
    return group
