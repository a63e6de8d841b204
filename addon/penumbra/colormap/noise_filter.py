"""The "Penumbra Noise Filter" group (one per noise setting): Vector, Scale,
Units per World, Minor, Major, Axis U, Axis V, Samples, W -> Mean, Sigma,
Offsets, Variances: the octave-wise filter of the noise over the sample's
share of the footprint, as one Gaussian (Mean, Sigma) and as a mixture of
four (Offsets, Variances). With 16 taps (8 or 4 in EEVEE for costly noises,
noise_maths.tap_count), or with one evaluation at the sample
(point_filter.py; Offsets and Variances then stay zero)."""

import math

import bpy

from . import native_filter, noise_nodes, point_filter
from .node_builder import Builder, new_group, zero_after
from .node_groups import NOISE_FILTER
from .noise_maths import MIXTURE_COMPONENTS, TAP_COUNT, TAP_COUNTS, major_taps

# Bumped whenever the Noise Filter's nodes change, so a re-bake in a .blend
# saved by an older version builds the group anew (2: Closest texel fetches;
# 3: taps outermost, within Cycles' SVM stack; 4: kernels at the sample, no
# Centre Offset input, the four-Gaussian mixture's Offsets and Variances).
NOISE_FILTER_VERSION = 4
# The band-limited groups (native_filter.py, new since 0.2.0) carry their own
# revision in their name's key (" n2": the curves read ln s), so a re-bake
# builds them anew without a format change for the groups 0.2.0 made.
# The kernel's standard deviation at N samples is κ·N^(−KERNEL_SHARE_EXPONENT):
# each sample's share of the footprint, τ² = κ²/N. A slower hand-over
# (N^(−3/8)) was 8–12 % better at 4 and 16 spp but kept a blur at silhouettes
# that made the torus worse than the plain ramp at 256 spp (docs/colormap.md).
KERNEL_SHARE_EXPONENT = 0.5


def noise_filter_group(octave_image, table, model, filter_stddev_px, taps=TAP_COUNT, analytic_octaves=0,
                       point=False, with_taps=True, native=False):
    """Vector, Scale, Units per World, Minor, Major, Axis U, Axis V, Samples,
    W -> Mean, Sigma, Offsets, Variances: the octave-wise filter of the noise
    `model` (noise_maths.NoiseModel: offset + Σ c_i (Fac_i − 0.5), Fac_i a
    normalized Noise Texture at Detail 0 and Scale·lacunarity^i on the
    distorted position; normalized fBm: offset 0.5, c_i = w_i). See
    docs/colormap.md, "Octave filter", "Sample-count-aware filter" and "A
    mixture of Gaussians".

    Each sample filters what the renderer will not: with N = Samples, a
    Gaussian kernel of standard deviation τ = κ/√N (κ the pixel filter's)
    centred at the sample. At one sample (at the pixel's centre in Cycles and
    EEVEE) it is the pixel's estimate; as N grows it shrinks onto the sample
    and the result tends to the plain ramp.

    `taps` (16, 8 or 4) taps sit at P + τ(n·m + t·M): n = ±1 along the
    footprint ellipse's minor axis m, t = major_taps(taps/2) along its major
    axis M (offsets taken to the noise's coordinates by the object's inverse
    transform and Units per World), then moved by the noise's Distortion;
    their average A_i estimates octave i's mean over the kernel. Over a
    kernel of standard deviations s·(1, e) (s = τ·Minor·Scale·Units per
    World, e = Major/Minor) octave i keeps the fraction q_i = q(s·lacunarity^i,
    e) of its variance inside (measured table); the taps estimate the mean
    with an error of about e_i = q_i²/taps of the octave's variance.
    s_t = Σ c_i g_i (Fac_i(tap) − 0.5), g_i = (1 − q_i)/(1 − q_i + e_i)
    (least-squares shrinkage); Mean = offset + the taps' average of s_t.
    Sigma² = the taps' spread of s_t + V_u, V_u = V₀ Σ c_i² (max(q_i − g_i²
    q_i (1 − q_i/taps), 0) + (1 − q_i) e_i/(1 − q_i + e_i)): the variance the
    spread misses on average, plus the remaining uncertainty of the mean.
    Offsets and Variances describe the taps in four equal groups k (taps
    next to each other along M, both sides): δ_k = the group's mean of s_t −
    their average, ε_k = the group's spread − all the taps' spread, for
    k = 1..3 (filtered_ramp_group(mixture=True) reads them).

    point=True: above one sample, one evaluation of each octave at the
    sample instead, the finest `analytic_octaves` left out and carried as
    variance (point_filter.point_estimate, with the inputs Point Minor and
    Point Major of point_footprint.py); at one sample the taps as above.
    The output Mixture is 1 at one sample, else 0: a number fixed for the
    whole render (Samples is set by its driver), so Cycles folds the choice
    and removes the branch it does not take (point_filter.select).
    with_taps=False (point only): the same interface without the taps, for
    more than one sample (Mixture, Offsets and Variances stay 0).
    native=True (point only): the one evaluation is one Noise Texture with
    its Detail cut at the sample's resolution (native_filter.py) where that
    noise allows it (native_filter.applies), else as point=True."""
    coefficients, offset, lacunarity = model.coefficients, model.offset, model.lacunarity
    if taps not in TAP_COUNTS:
        raise ValueError(f"taps must be one of {TAP_COUNTS}, not {taps}")
    if analytic_octaves and not point:
        raise ValueError("only the one-evaluation filter (point=True) leaves octaves out")
    native = native and point and native_filter.applies(model)
    group, gin, gout = _filter_group(model, filter_stddev_px, taps, analytic_octaves, point, with_taps, native)
    if gin is None:   # this filter, built by this version: reuse it
        return group
    b = Builder(group)
    share = _kernel_share(b, gin.outputs["Samples"])
    if point and not with_taps:
        mean, sigma = _one_evaluation(b, gin, model, table, filter_stddev_px, share, analytic_octaves, native)
        b.connect(mean, gout.inputs["Mean"])
        b.links.new(sigma, gout.inputs["Sigma"])
        group["penumbra_version"] = NOISE_FILTER_VERSION
        return group
    log2_s, v = _footprint_table_coordinates(b, gin, table, filter_stddev_px, share)
    variance, weights = 0.0, []       # weights: c_i g_i, the shrunk octave's weight in the mean
    for i, c in enumerate(coefficients):
        q = _octave_fraction(b, octave_image, table, log2_s, v, i * math.log2(lacunarity),
                             weights[-1] if weights else None)
        g, term = _octave_shrinkage(b, q, taps)
        weights.append(b.math("MULTIPLY", g, c))
        variance = b.math("MULTIPLY_ADD", term, table["total_var"] * c * c, variance)
    mean, spread, offsets, variances = _tap_groups(b, gin, model, weights, filter_stddev_px, share, taps)
    mean = b.math("ADD", mean, offset)
    sigma = b.math("SQRT", b.math("MAXIMUM", b.math("ADD", variance, spread), 0.0))
    if point:
        one_sample = b.math("LESS_THAN", gin.outputs["Samples"], 1.5)
        point_mean, point_sigma = _one_evaluation(b, gin, model, table, filter_stddev_px, share,
                                                  analytic_octaves, native)
        mean = point_filter.select(b, one_sample, point_mean, mean)
        sigma = point_filter.select(b, one_sample, point_sigma, sigma)
        b.links.new(one_sample, gout.inputs["Mixture"])
    b.connect(mean, gout.inputs["Mean"])
    b.links.new(sigma, gout.inputs["Sigma"])
    b.links.new(offsets, gout.inputs["Offsets"])
    b.links.new(variances, gout.inputs["Variances"])
    group["penumbra_version"] = NOISE_FILTER_VERSION
    return group



def _filter_group(model, filter_stddev_px, taps, analytic_octaves, point, with_taps, native):
    """The Noise Filter group named for its settings: (group, None, None) when
    this version built it already, else a new empty one with its sockets and
    settings recorded, and its Group Input and Output nodes."""
    coefficients, offset, lacunarity = model.coefficients, model.offset, model.lacunarity
    key = (f"{model.dimensions} " + "/".join(f"{c:.6g}" for c in coefficients) +
           f" o{offset:g} l{lacunarity:g} d{model.distortion:g} w{model.w} k{filter_stddev_px:.4g} t{taps}" +
           (f" p{analytic_octaves}" if point else "") + (" n2" if native else "") +
           ("" if with_taps else " only"))
    name = f"{NOISE_FILTER} ({key} spp)"
    group = bpy.data.node_groups.get(name)
    if group is not None and group.get("penumbra_version") == NOISE_FILTER_VERSION:
        return group, None, None
    if group is not None:   # built by an older Penumbra: materials that use it keep it
        group.name = name + " (old)"
    group, gin, gout = new_group(name, [("Vector", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                        ("Scale", "NodeSocketFloat", 5.0),
                                        ("Units per World", "NodeSocketFloat", 1.0),
                                        ("Minor", "NodeSocketFloat", 0.0), ("Major", "NodeSocketFloat", 0.0),
                                        ("Axis U", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                        ("Axis V", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                        ("Samples", "NodeSocketFloat", 1.0),
                                        ("W", "NodeSocketFloat", 0.0)] +
                                 ([("Point Minor", "NodeSocketFloat", 0.0), ("Point Major", "NodeSocketFloat", 0.0)]
                                  if point else []),
                                 [("Mean", "NodeSocketFloat"), ("Sigma", "NodeSocketFloat"),
                                  ("Offsets", "NodeSocketVector"), ("Variances", "NodeSocketVector")] +
                                 ([("Mixture", "NodeSocketFloat")] if point else []))
    group["penumbra_octave_coefficients"] = list(coefficients)
    group["penumbra_octave_offset"] = offset
    group["penumbra_taps"] = taps
    group["penumbra_point"] = point
    group["penumbra_analytic_octaves"] = analytic_octaves
    group["penumbra_native"] = native
    return group, gin, gout

def _one_evaluation(b, gin, model, table, filter_stddev_px, share, analytic_octaves, native):
    """(mean, sigma) of the one-evaluation filters: the band-limited Noise
    Texture (native; its curve gives sigma) or the octaves at the sample
    (point_filter)."""
    if native:
        return native_filter.native_estimate(b, gin, model, table["total_var"], filter_stddev_px, share)
    mean, variance = point_filter.point_estimate(b, gin, model, table["total_var"], filter_stddev_px, share,
                                                 analytic_octaves)
    return mean, b.math("SQRT", b.math("MAXIMUM", variance, 0.0))


def _kernel_share(b, samples):
    """τ/κ = N^(−KERNEL_SHARE_EXPONENT) = 1/√N, N = Samples clamped to ≥ 1:
    the kernel's share of the pixel filter's standard deviation
    (docs/colormap.md, "Sample-count-aware filter")."""
    return b.math("POWER", b.math("MAXIMUM", samples, 1.0), -KERNEL_SHARE_EXPONENT)


def _tap_groups(b, gin, model, weights, filter_stddev_px, share, taps):
    """The taps' s_t = Σ_i c_i g_i (Fac_i(tap) − 0.5), summed in four equal
    groups: neighbouring positions along the major axis, both sides of the
    minor axis (16 taps: 2 positions × 2 sides; 8: 1 × 2; 4: one tap each).
    Returns the taps' mean of s_t, their
    spread, and the mixture's (δ_1..3) and (ε_1..3) as vectors. Taps
    outermost, octaves inside, each tap after the previous one (zero_after):
    only the running sums stay live."""
    major = major_taps(taps // 2)
    per_group = len(major) // MIXTURE_COMPONENTS if len(major) >= MIXTURE_COMPONENTS else 1
    groups = [[0.0, 0.0] for _ in range(MIXTURE_COMPONENTS)]
    tap_at = _pixel_taps(b, gin, filter_stddev_px, share)
    s_t = 0.0
    for side in (-1.0, 1.0):
        for index, t in enumerate(major):
            tap = noise_nodes.distorted_vector(b, tap_at(side, t, s_t), gin.outputs["Scale"], model, gin.outputs["W"])
            s_t = 0.0
            for i, weight in enumerate(weights):
                scale = b.math("MULTIPLY", gin.outputs["Scale"], model.lacunarity ** i)
                fac = noise_nodes.octave_fac(b, tap, scale, model)
                s_t = b.math("MULTIPLY_ADD", b.math("SUBTRACT", fac, 0.5), weight, s_t)
            k = index // per_group if len(major) >= MIXTURE_COMPONENTS else index + (side > 0) * len(major)
            groups[k][0] = b.math("ADD", groups[k][0], s_t)
            groups[k][1] = b.math("MULTIPLY_ADD", s_t, s_t, groups[k][1])
    size = taps // MIXTURE_COMPONENTS
    means = [b.math("MULTIPLY", total, 1.0 / size) for total, _ in groups]
    spreads = [b.math("SUBTRACT", b.math("MULTIPLY", square, 1.0 / size), b.math("MULTIPLY", m, m))
               for m, (_, square) in zip(means, groups)]
    mean = b.math("MULTIPLY", b.math("ADD", b.math("ADD", means[0], means[1]), b.math("ADD", means[2], means[3])),
                  1.0 / MIXTURE_COMPONENTS)
    square = b.math("ADD", b.math("ADD", groups[0][1], groups[1][1]), b.math("ADD", groups[2][1], groups[3][1]))
    # The taps' spread: the local within-pixel variance of the octaves the
    # mean keeps (exact for a field linear across the pixel).
    spread = b.math("MAXIMUM", b.math("SUBTRACT", b.math("MULTIPLY", square, 1.0 / taps),
                                      b.math("MULTIPLY", mean, mean)), 0.0)
    offsets = b.combine(*[b.math("SUBTRACT", m, mean) for m in means[:3]])
    variances = b.combine(*[b.math("SUBTRACT", b.math("MAXIMUM", w, 0.0), spread) for w in spreads[:3]])
    return mean, spread, offsets, variances


def _octave_fraction(b, octave_image, table, log2_s, v, log2_octave, after=None):
    """q: the fraction of one octave's variance inside the kernel (table),
    looked up after the value `after` (see zero_after)."""
    logs = table["log2_footprint"]
    u = b.texel(b.math("MULTIPLY_ADD", log2_s, 1.0 / (logs[-1] - logs[0]),
                       (log2_octave - logs[0]) / (logs[-1] - logs[0])), len(logs))
    if after is not None:
        u = b.math("ADD", u, zero_after(b, after))
    q, _, _ = b.separate(b.image(octave_image, u, v, alpha=False)[0])
    return q


def _octave_shrinkage(b, q, tap_count):
    """g = (1 − q)/(1 − q + e), e = q²/taps, and the variance term the taps'
    spread does not see: q − g² q (1 − q/taps) (the expected spread of the
    taps) plus the uncertainty of the shrunk mean (1 − q) e/(1 − q + e)."""
    kept = b.math("SUBTRACT", 1.0, q)
    tap_error = b.math("MULTIPLY", b.math("MULTIPLY", q, q), 1.0 / tap_count)
    g = b.math("DIVIDE", kept, b.math("MAXIMUM", b.math("ADD", kept, tap_error), 1e-9))
    captured = b.math("MULTIPLY", b.math("MULTIPLY", g, g),
                      b.math("MULTIPLY", q, b.math("MULTIPLY_ADD", q, -1.0 / tap_count, 1.0)))
    term = b.math("ADD", b.math("MAXIMUM", b.math("SUBTRACT", q, captured), 0.0), b.math("MULTIPLY", g, tap_error))
    return g, term


def _footprint_table_coordinates(b, gin, table, filter_stddev_px, share):
    """log2 s (the kernel's minor standard deviation in noise units) and the
    octave table's v coordinate of the footprint's elongation."""
    elongations = table["log2_elongation"]
    minor = b.math("MAXIMUM", gin.outputs["Minor"], 1e-12)
    s = b.math("MULTIPLY", b.math("MULTIPLY", minor, gin.outputs["Scale"]),
               b.math("MULTIPLY", gin.outputs["Units per World"], b.math("MULTIPLY", share, filter_stddev_px)))
    log2_s = b.math("LOGARITHM", b.math("MAXIMUM", s, 1e-12), 2.0)
    log2_e = b.math("LOGARITHM", b.math("MAXIMUM", b.math("DIVIDE", gin.outputs["Major"], minor), 1.0), 2.0)
    v = b.texel(b.math("MINIMUM", b.math("MULTIPLY", log2_e, 1.0 / elongations[-1]), 1.0), len(elongations))
    return log2_s, v


def _world_to_object(b, vector):
    node = b.place(b.nodes.new("ShaderNodeVectorTransform"))
    node.vector_type = "VECTOR"
    node.convert_from = "WORLD"
    node.convert_to = "OBJECT"
    b.links.new(vector, node.inputs[0])
    return node.outputs[0]


def _footprint_principal_axes(b, axis_u, axis_v):
    """p1 = the unit pixel-space direction J stretches most (eigenvector of
    JᵀJ = [[a, h], [h, c]]), p2 ⟂ p1; returned as world vectors J p1, J p2."""
    a = b.vmath("DOT_PRODUCT", axis_u, axis_u)
    c = b.vmath("DOT_PRODUCT", axis_v, axis_v)
    h = b.vmath("DOT_PRODUCT", axis_u, axis_v)
    half_diff = b.math("MULTIPLY", b.math("SUBTRACT", a, c), 0.5)
    root = b.math("SQRT", b.math("MULTIPLY_ADD", half_diff, half_diff, b.math("MULTIPLY", h, h)))
    tiny = b.math("MULTIPLY", b.math("ADD", a, c), 1e-6)
    u_wider = b.math("GREATER_THAN", a, c)       # 1: use (λ1 − c, h), else (h, λ1 − a)
    x1 = b.math("ADD", b.math("MULTIPLY", b.math("ADD", b.math("ADD", half_diff, root), tiny), u_wider),
                b.math("MULTIPLY", h, b.math("SUBTRACT", 1.0, u_wider)))
    y1 = b.math("ADD", b.math("MULTIPLY", h, u_wider),
                b.math("MULTIPLY", b.math("ADD", b.math("SUBTRACT", root, half_diff), tiny),
                       b.math("SUBTRACT", 1.0, u_wider)))
    norm = b.math("DIVIDE", 1.0, b.math("MAXIMUM", b.math("SQRT", b.math("MULTIPLY_ADD", x1, x1,
                                                                          b.math("MULTIPLY", y1, y1))), 1e-30))
    x1, y1 = b.math("MULTIPLY", x1, norm), b.math("MULTIPLY", y1, norm)
    major_axis = b.vmath("ADD", b.vscale(axis_u, x1), b.vscale(axis_v, y1))
    minor_axis = b.vmath("SUBTRACT", b.vscale(axis_v, x1), b.vscale(axis_u, y1))
    return major_axis, minor_axis


def _pixel_taps(b, gin, filter_stddev_px, share):
    """A function making the tap at (n, t) in the noise's coordinates,
    P + τ(n·m + t·M), τ = share·κ: world offsets taken there by the object's
    inverse transform (directions) and Units per World (lengths)."""
    axis_u, axis_v = gin.outputs["Axis U"], gin.outputs["Axis V"]
    ref = b.vmath("ADD", axis_u, axis_v)
    k = b.math("DIVIDE", b.math("MULTIPLY", b.vmath("LENGTH", ref), gin.outputs["Units per World"]),
               b.math("MAXIMUM", b.vmath("LENGTH", _world_to_object(b, ref)), 1e-30))
    major_axis, minor_axis = _footprint_principal_axes(b, axis_u, axis_v)
    tau = b.math("MULTIPLY", b.math("MULTIPLY", k, filter_stddev_px), share)
    km = b.vscale(_world_to_object(b, major_axis), tau)
    kn = b.vscale(_world_to_object(b, minor_axis), tau)
    base = gin.outputs["Vector"]

    def tap(side, t, after):
        """The tap at n = side, t along M, ordered after the value `after`."""
        offset = b.vmath("ADD", b.vscale(kn, side), b.vscale(km, t))
        if isinstance(after, bpy.types.NodeSocket):
            offset = b.vmath("ADD", offset, zero_after(b, after))   # a float read as (z, z, z)
        return b.vmath("ADD", base, offset)
    return tap
