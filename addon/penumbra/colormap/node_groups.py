"""Shader node groups that sample pre-filtered colour-map lookups.

- "Penumbra Filtered Ramp" (one per lookup image): Mean, Sigma -> Color,
  Alpha. Maps (mean, σ) to the lookup's texel centres and interpolates it
  bilinearly from four Image Texture nodes set to Closest / EXTEND (no
  mipmaps, no wrap at the edges).
- "Penumbra Pixel Footprint": Pixel Size, Orthographic, Raster Offset X/Y
  -> Footprint, Minor, Major, Axis U, Axis V, Centre Offset: the pixel's
  footprint on the surface from the Jacobian of the camera projection, and
  the offset to the pixel's centre (see docs/colormap.md, "Footprint").
- "Penumbra Noise Filter" (per noise setting): Vector, Scale, Units per
  World, Minor, Major, Axis U, Axis V, Samples, W -> Mean, Sigma, Offsets,
  Variances, the octave-wise filter of the noise with 16 taps (8 or 4 in
  EEVEE for costly noises) over the sample's share of the footprint, as one
  Gaussian (Mean, Sigma) and as a mixture of four (Offsets, Variances).
- "Penumbra Height Filtered Ramp" / "Penumbra Slope Filtered Ramp": paper
  Sec. 5.1 / 5.2, reading the microsurface statistics image.
Groups are built with interface.add_socket, so the same code makes them in
Blender 3.4 (inputs/outputs) and 4.x (interface)."""

import math
import os
import statistics
import tempfile

import bpy
import numpy as np

from . import interface, noise_model

FILTERED_RAMP = "Penumbra Filtered Ramp"
FOOTPRINT = "Penumbra Pixel Footprint"
NOISE_FILTER = "Penumbra Noise Filter"
HEIGHT_RAMP = "Penumbra Height Filtered Ramp"
SLOPE_RAMP = "Penumbra Slope Filtered Ramp"
MICROSURFACE_IMAGE = "Penumbra Microsurface Statistics"
MICROSURFACE_TABLE_SIZE = 256
# A pixel ray that misses the tangent plane (beyond the horizon) is taken to
# meet it at this many times the sample's own distance: the footprint is
# bounded there instead of infinite.
HORIZON_REACH = 20.0
# Bumped whenever the Noise Filter's nodes change, so a re-bake in a .blend
# saved by an older version builds the group anew (2: Closest texel fetches;
# 3: taps outermost, within Cycles' SVM stack; 4: kernels at the sample, no
# Centre Offset input, the four-Gaussian mixture's Offsets and Variances).
NOISE_FILTER_VERSION = 4
# Components of the Gaussian mixture the Noise Filter hands the filtered ramp
# (docs/colormap.md, "A mixture of Gaussians"): the taps in four equal groups.
MIXTURE_COMPONENTS = 4
# Noise evaluations per shading point the Noise Filter may spend in EEVEE:
# llvmpipe (and GPU drivers) compile the whole material as one shader, and
# its memory grows faster than linearly with the Noise nodes in it (Blender
# 3.4, llvmpipe, 48×27, 1 sample, peak memory and first render: 16 Noise
# evaluations 1.1 GiB, 6 s; 48 3.3 GiB, 42 s; 80 6.8 GiB, 88 s; Detail 8
# with Distortion at 16 taps, 192, went past 24 GiB). Detail 4 gets 8 taps
# (40: 2.5 GiB, 25 s), Detail 8 with Distortion 4 (48: 3.3 GiB).
EEVEE_NOISE_BUDGET = 48
TAP_COUNTS = (16, 8, 4)
# The kernel's standard deviation at N samples is κ·N^(−KERNEL_SHARE_EXPONENT):
# each sample's share of the footprint, τ² = κ²/N. A slower hand-over
# (N^(−3/8)) was 8–12 % better at 4 and 16 spp but kept a blur at silhouettes
# that made the torus worse than the plain ramp at 256 spp (docs/colormap.md).
KERNEL_SHARE_EXPONENT = 0.5


def major_taps(count):
    """Tap positions along the footprint's major axis, in kernel standard
    deviations: the Gaussian's quantiles at (k + 1/2)/count scaled to unit
    variance (equal weights). With two taps (±1) along the minor axis they
    make 2·count taps."""
    quantiles = [statistics.NormalDist().inv_cdf((k + 0.5) / count) for k in range(count)]
    rms = math.sqrt(sum(q * q for q in quantiles) / count)
    return tuple(q / rms for q in quantiles)


MAJOR_TAPS = major_taps(8)
TAP_COUNT = 2 * len(MAJOR_TAPS)


def noise_evaluations_per_tap(model):
    """Noise Textures one tap evaluates: one per octave, plus one per axis of
    the distortion's offset."""
    return len(model.coefficients) + (model.axes if model.distortion != 0.0 else 0)


def tap_count(model, engine):
    """Taps of the Noise Filter for a render engine: 16 in Cycles; in EEVEE
    the most of TAP_COUNTS within EEVEE_NOISE_BUDGET Noise evaluations (at
    least 4)."""
    if engine not in ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"):
        return TAP_COUNTS[0]
    per_tap = noise_evaluations_per_tap(model)
    return next((n for n in TAP_COUNTS if n * per_tap <= EEVEE_NOISE_BUDGET), TAP_COUNTS[-1])


class _Builder:
    """Small helpers to write node arithmetic: math('MULTIPLY', a, 2.0)."""

    def __init__(self, group):
        self.group = group
        self.nodes = group.nodes
        self.links = group.links
        self.x = 0
        self.placed = 0

    def _place(self, node):
        # A counter, not len(self.nodes): counting a node collection walks it,
        # and a Noise Filter has thousands of nodes.
        self.placed += 1
        node.location = (self.x, -200 * (self.placed % 6))
        self.x += 60
        return node

    def connect(self, value, socket):
        if isinstance(value, bpy.types.NodeSocket):
            self.links.new(value, socket)
        elif isinstance(value, (tuple, list)):
            socket.default_value = value
        else:
            socket.default_value = float(value)

    def math(self, op, a, b=0.0, c=None, clamp=False):
        node = self._place(self.nodes.new("ShaderNodeMath"))
        node.operation = op
        node.use_clamp = clamp
        self.connect(a, node.inputs[0])
        self.connect(b, node.inputs[1])
        if c is not None:
            self.connect(c, node.inputs[2])
        return node.outputs[0]

    def vmath(self, op, a, b=None):
        node = self._place(self.nodes.new("ShaderNodeVectorMath"))
        node.operation = op
        self.connect(a, node.inputs[0])
        if b is not None:
            self.connect(b, node.inputs[1])
        return node.outputs["Value"] if op in ("DOT_PRODUCT", "LENGTH", "DISTANCE") else node.outputs["Vector"]

    def vscale(self, vector, factor):
        node = self._place(self.nodes.new("ShaderNodeVectorMath"))
        node.operation = "SCALE"
        self.connect(vector, node.inputs[0])
        self.connect(factor, node.inputs["Scale"])
        return node.outputs["Vector"]

    def combine(self, x, y, z=0.0):
        node = self._place(self.nodes.new("ShaderNodeCombineXYZ"))
        self.connect(x, node.inputs[0])
        self.connect(y, node.inputs[1])
        self.connect(z, node.inputs[2])
        return node.outputs[0]

    def texel_fetch(self, image, u, v):
        node = self._place(self.nodes.new("ShaderNodeTexImage"))
        node.image = image
        # Closest: EEVEE samples every other interpolation with mipmaps and
        # anisotropic filtering, chosen from the screen-space derivatives of
        # the coordinates. A lookup indexed by noise jumps across the table
        # between neighbouring pixels, so the GPU picks a coarse mip level and
        # blurs the table (measured: the filter stopped converging in EEVEE,
        # 0.028 RMSE at 64 samples against the plain ramp's 0.013).
        node.interpolation = "Closest"
        node.extension = "EXTEND"   # a lookup must not wrap at its edges
        node.projection = "FLAT"
        self.links.new(self.combine(u, v), node.inputs["Vector"])
        return node

    def image(self, image, u, v, alpha=True):
        """(Color, Alpha) of `image` at (u, v) in [0, 1]², bilinear between
        the four nearest texel centres, fetched as Closest so that no
        renderer's mipmapping takes part (see texel_fetch). alpha=False: the
        tables that keep nothing there get no nodes for it (Alpha is None)."""
        width, height = image.size

        def corners(coordinate, count):
            x = self.math("MULTIPLY_ADD", coordinate, float(count), -0.5)
            base = self.math("FLOOR", x)
            first = self.math("MULTIPLY_ADD", base, 1.0 / count, 0.5 / count)
            return first, self.math("ADD", first, 1.0 / count), self.math("SUBTRACT", x, base)

        u0, u1, fu = corners(u, width)
        v0, v1, fv = corners(v, height)
        rows = []
        for row in (v0, v1):
            left, right = self.texel_fetch(image, u0, row), self.texel_fetch(image, u1, row)
            rows.append((self.lerp_vector(left.outputs["Color"], right.outputs["Color"], fu),
                         self.lerp(left.outputs["Alpha"], right.outputs["Alpha"], fu) if alpha else None))
        return (self.lerp_vector(rows[0][0], rows[1][0], fv),
                self.lerp(rows[0][1], rows[1][1], fv) if alpha else None)

    def lerp(self, a, b, t):
        return self.math("MULTIPLY_ADD", self.math("SUBTRACT", b, a), t, a)

    def lerp_vector(self, a, b, t):
        return self.vmath("ADD", a, self.vscale(self.vmath("SUBTRACT", b, a), t))

    def separate(self, color):
        node = self._place(self.nodes.new("ShaderNodeSeparateColor"))
        self.links.new(color, node.inputs[0])
        return node.outputs[0], node.outputs[1], node.outputs[2]

    def texel(self, fraction, count):
        """Texture coordinate of a fractional table index fraction·(count−1):
        texel centres sit at (i + 0.5) / count."""
        return self.math("MULTIPLY_ADD", fraction, (count - 1) / count, 0.5 / count)


def default_folder():
    return os.path.join(bpy.app.tempdir or tempfile.gettempdir(), "penumbra_luts")


def table_image(name, pixels, folder=None):
    """A small float table (rows bottom-up as Blender stores them) written as
    EXR by the core and loaded 'Non-Color', so it survives saving the .blend
    (a generated image would come back blank)."""
    from .. import native
    folder = folder or default_folder()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, bpy.path.clean_name(name) + ".exr")
    native.require().image.write_exr(path, np.ascontiguousarray(pixels[::-1], dtype=np.float32), half=False,
                                     colorspace="Non-Color")
    image = bpy.data.images.get(name)
    if image is not None and os.path.normpath(bpy.path.abspath(image.filepath)) == path:
        image.reload()
    else:
        if image is not None:
            image.name = name + " (old)"
        image = bpy.data.images.load(path, check_existing=False)
        image.name = name
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    return image


def _new_group(name, inputs, outputs):
    group = bpy.data.node_groups.new(name, "ShaderNodeTree")
    for sock_name, sock_type, default in inputs:
        interface.add_socket(group, sock_name, "INPUT", sock_type, default)
    for sock_name, sock_type in outputs:
        interface.add_socket(group, sock_name, "OUTPUT", sock_type)
    gin = group.nodes.new("NodeGroupInput")
    gin.location = (-400, 0)
    gout = group.nodes.new("NodeGroupOutput")
    gout.location = (1800, 0)
    return group, gin, gout


def _lookup_uv(b, mean, sigma, spec):
    """(u, v) of (mean, σ) in a lookup image written with σ = 0 at the bottom row."""
    width, height = spec["width"], spec["height"]
    u = b.texel(b.math("MULTIPLY_ADD", mean, 1.0 / (spec["mean_max"] - spec["mean_min"]),
                       -spec["mean_min"] / (spec["mean_max"] - spec["mean_min"])), width)
    t = b.math("MULTIPLY", b.math("MAXIMUM", sigma, 0.0), 1.0 / spec["sigma_max"])
    t = b.math("MINIMUM", t, 1.0)
    if spec["sigma_spacing"] == "quadratic":
        t = b.math("SQRT", t)
    return u, b.texel(t, height)


def filtered_ramp_group(image, spec, name=FILTERED_RAMP, mixture=False):
    """Mean, Sigma -> Color, Alpha from `image` (a lookup with `spec`: width,
    height, sigma_max, mean_min, mean_max, sigma_spacing).

    mixture=True adds the inputs Offsets and Variances (vectors, default 0):
    the colour is then the average of the lookup over MIXTURE_COMPONENTS
    Gaussians N(Mean + δ_k, Sigma² + ε_k), (δ_k, ε_k) for k = 1..3 the
    vectors' components and, the four having the mixture's mean Mean and
    variance Sigma², δ_4 = −(δ_1 + δ_2 + δ_3), ε_4 = −(ε_1 + ε_2 + ε_3) −
    Σ_k δ_k². Left at zero, that is the one Gaussian N(Mean, Sigma²)."""
    inputs = [("Mean", "NodeSocketFloat", 0.5), ("Sigma", "NodeSocketFloat", 0.0)]
    if mixture:
        inputs += [("Offsets", "NodeSocketVector", (0.0, 0.0, 0.0)), ("Variances", "NodeSocketVector", (0.0, 0.0, 0.0))]
    group, gin, gout = _new_group(name, inputs, [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat")])
    b = _Builder(group)
    mean, sigma = gin.outputs["Mean"], gin.outputs["Sigma"]
    if not mixture:
        color, alpha = b.image(image, *_lookup_uv(b, mean, sigma, spec))
    else:
        color, alpha = _mixture_lookup(b, image, spec, mean, sigma, gin.outputs["Offsets"], gin.outputs["Variances"])
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    group["penumbra_lookup"] = dict(spec, image=image.name)
    return group


def _mixture_lookup(b, image, spec, mean, sigma, offsets, variances):
    """The average of the lookup over the mixture's four components (see
    filtered_ramp_group), each fetched after the previous one (_zero_after)."""
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
            component_mean = b.math("ADD", component_mean, _zero_after(b, alpha))
        component_sigma = b.math("SQRT", b.math("MAXIMUM", b.math("ADD", variance, extra), 0.0))
        c, a = b.image(image, *_lookup_uv(b, component_mean, component_sigma, spec))
        color = c if color is None else b.vmath("ADD", color, c)
        alpha = a if alpha is None else b.math("ADD", alpha, a)
    share = 1.0 / MIXTURE_COMPONENTS
    return b.vscale(color, share), b.math("MULTIPLY", alpha, share)


def footprint_group():
    """Pixel Size, Orthographic, Raster Offset X/Y -> Footprint, Minor, Major,
    Axis U, Axis V, Centre Offset: the pixel's footprint on the surface from
    the Jacobian J = ∂P/∂(pixel) of the point P seen through the pixel, for a
    locally flat surface of normal N: J_u = λ p (R − (R·N)/(r·N) r) (same
    with U), r = the view ray scaled to a unit component along the camera's
    forward axis F, R and U an orthonormal basis of the image plane, λ p the
    pixel's width at the point (perspective: view depth z times the pixel
    size at unit depth; orthographic: the pixel size itself). Footprint =
    sqrt|J_u × J_v| (side of the square of the same area), Major/Minor = the
    singular values of J (the footprint ellipse's axes), Axis U/V = J_u, J_v
    (world). Centre Offset = (the point where the ray through the centre of
    this sample's pixel meets the tangent plane) − P, so P + Centre Offset is
    the same for every sample of a pixel (zero where that ray misses the
    plane). The pixel is found from the image-plane position: raster =
    position / pixel size + Raster Offset (half the resolution), pixel centre
    = floor(raster) + 0.5. The camera axes come from a Vector Transform
    (Camera → World); F's sign is fixed by F·(−Incoming) > 0, so the result
    does not depend on the renderer's camera-space convention."""
    group = bpy.data.node_groups.get(FOOTPRINT)
    if group is not None and "Centre Offset" in interface.socket_names(group, "OUTPUT"):
        return group
    if group is not None:
        group.name = FOOTPRINT + " (old)"
    group, gin, gout = _new_group(FOOTPRINT, [("Pixel Size", "NodeSocketFloat", 0.001),
                                              ("Orthographic", "NodeSocketFloat", 0.0),
                                              ("Raster Offset X", "NodeSocketFloat", 0.0),
                                              ("Raster Offset Y", "NodeSocketFloat", 0.0)],
                                  [("Footprint", "NodeSocketFloat"), ("Minor", "NodeSocketFloat"),
                                   ("Major", "NodeSocketFloat"), ("Axis U", "NodeSocketVector"),
                                   ("Axis V", "NodeSocketVector"), ("Centre Offset", "NodeSocketVector")])
    b = _Builder(group)
    geometry = b.nodes.new("ShaderNodeNewGeometry")
    to_point, forward, right, up = _camera_frame(b, geometry)
    ju, jv = _footprint_jacobian(b, gin, geometry, to_point, forward, right, up)
    _footprint_ellipse(b, ju, jv, gout)
    _centre_offset(b, gin, gout, geometry, forward, right, up, ju, jv)
    return group


def _camera_transform(b, vector, kind="VECTOR"):
    node = b._place(b.nodes.new("ShaderNodeVectorTransform"))
    node.vector_type = kind
    node.convert_from = "CAMERA"
    node.convert_to = "WORLD"
    node.inputs[0].default_value = vector
    return node.outputs[0]


def _camera_frame(b, geometry):
    """The unit vector camera -> point, and the camera's forward, right and up
    axes in world space, forward's sign fixed by F·(−Incoming) > 0 whatever
    the renderer's camera convention."""
    to_point = b.vscale(geometry.outputs["Incoming"], -1.0)      # unit vector camera -> point
    f_axis = b.vmath("NORMALIZE", _camera_transform(b, (0.0, 0.0, 1.0)))
    forward = b.vscale(f_axis, b.math("SIGN", b.vmath("DOT_PRODUCT", f_axis, to_point)))
    x_axis = b.vmath("NORMALIZE", _camera_transform(b, (1.0, 0.0, 0.0)))
    right = b.vmath("NORMALIZE", b.vmath("SUBTRACT", x_axis,
                                         b.vscale(forward, b.vmath("DOT_PRODUCT", x_axis, forward))))
    return to_point, forward, right, b.vmath("CROSS_PRODUCT", forward, right)


def _footprint_jacobian(b, gin, geometry, to_point, forward, right, up):
    """J_u, J_v: the world-space steps of the surface point per pixel.
    Orthographic: the projection is affine and the derivative is exact.
    Perspective: the secant across the pixel, X(d + ½p·R) − X(d − ½p·R)
    (same with U), X(q) where the ray q from the camera meets the tangent
    plane: exact for a plane, where the derivative at the centre is too small
    for pixels that reach the horizon (their far edge projects much further).
    A ray that misses the plane (beyond the horizon) is bounded: the far point
    lies at most HORIZON_REACH times the sample's distance."""
    camera = b.nodes.new("ShaderNodeCameraData")
    cos_beta = b.math("MAXIMUM", b.vmath("DOT_PRODUCT", to_point, forward), 1e-6)
    ray = b.vscale(to_point, b.math("DIVIDE", 1.0, cos_beta))       # unit component along F
    normal = geometry.outputs["Normal"]
    ray_n = b.vmath("DOT_PRODUCT", ray, normal)
    inv_ray_n = b.math("DIVIDE", ray_n, b.math("MAXIMUM", b.math("MULTIPLY", ray_n, ray_n), 1e-12))
    ortho = gin.outputs["Orthographic"]
    depth = camera.outputs["View Z Depth"]
    half = b.math("MULTIPLY", gin.outputs["Pixel Size"], 0.5)

    def derivative(axis):
        k = b.math("MULTIPLY", b.vmath("DOT_PRODUCT", axis, normal), inv_ray_n)
        return b.vscale(b.vmath("SUBTRACT", axis, b.vscale(ray, k)), gin.outputs["Pixel Size"])

    def point(axis, sign):
        """X(ray + sign·½p·axis) − camera, over the sample's depth: the ray
        scaled to the plane, t = (ray·N)/(q·N) (q·N bounded away from 0)."""
        q = b.vmath("ADD", ray, b.vscale(axis, b.math("MULTIPLY", half, sign)))
        ratio = b.math("MULTIPLY", b.vmath("DOT_PRODUCT", q, normal), inv_ray_n)      # (q·N)/(ray·N)
        return b.vscale(q, b.math("DIVIDE", 1.0, b.math("MAXIMUM", ratio, 1.0 / HORIZON_REACH)))

    def column(axis):
        secant = b.vmath("SUBTRACT", point(axis, 1.0), point(axis, -1.0))
        mixed = b.vmath("ADD", b.vscale(secant, b.math("MULTIPLY", depth, b.math("SUBTRACT", 1.0, ortho))),
                        b.vscale(derivative(axis), ortho))
        return mixed

    return column(right), column(up)


def _footprint_ellipse(b, ju, jv, gout):
    """Footprint (sqrt of the area), Major and Minor (J's singular values), Axis U/V."""
    a = b.vmath("DOT_PRODUCT", ju, ju)
    c = b.vmath("DOT_PRODUCT", jv, jv)
    area = b.vmath("LENGTH", b.vmath("CROSS_PRODUCT", ju, jv))
    half_diff = b.math("MULTIPLY", b.math("SUBTRACT", a, c), 0.5)
    ab = b.vmath("DOT_PRODUCT", ju, jv)
    d = b.math("SQRT", b.math("MULTIPLY_ADD", half_diff, half_diff, b.math("MULTIPLY", ab, ab)))
    major = b.math("SQRT", b.math("ADD", b.math("MULTIPLY", b.math("ADD", a, c), 0.5), d))
    b.links.new(b.math("SQRT", area), gout.inputs["Footprint"])
    b.links.new(major, gout.inputs["Major"])
    b.links.new(b.math("DIVIDE", area, b.math("MAXIMUM", major, 1e-30)), gout.inputs["Minor"])
    b.links.new(ju, gout.inputs["Axis U"])
    b.links.new(jv, gout.inputs["Axis V"])


def _centre_offset(b, gin, gout, geometry, forward, right, up, ju, jv):
    """Centre Offset: where the ray through the pixel's centre meets the
    tangent plane, minus P. The pixel centre: image-plane coordinates in
    pixels (perspective: the ray's slope over the pixel size at unit depth;
    orthographic: the offset from the camera over the pixel size), snapped."""
    ortho = gin.outputs["Orthographic"]
    perspective = b.math("SUBTRACT", 1.0, ortho)
    pixel = gin.outputs["Pixel Size"]
    normal = geometry.outputs["Normal"]
    origin = _camera_transform(b, (0.0, 0.0, 0.0), "POINT")
    position = geometry.outputs["Position"]
    relative = b.vmath("SUBTRACT", position, origin)
    inv_pixel = b.math("DIVIDE", 1.0, b.math("MAXIMUM", pixel, 1e-30))
    depth_scale = b.math("ADD", b.math("MULTIPLY", b.math("DIVIDE", 1.0, b.math(
        "MAXIMUM", b.vmath("DOT_PRODUCT", relative, forward), 1e-12)), perspective), ortho)

    def centre(axis, offset):
        raster = b.math("MULTIPLY_ADD", b.math("MULTIPLY", b.vmath("DOT_PRODUCT", relative, axis), depth_scale),
                        inv_pixel, offset)
        snapped = b.math("SUBTRACT", b.math("ADD", b.math("FLOOR", raster), 0.5), offset)
        return b.math("MULTIPLY", snapped, pixel)

    lateral = b.vmath("ADD", b.vscale(right, centre(right, gin.outputs["Raster Offset X"])),
                      b.vscale(up, centre(up, gin.outputs["Raster Offset Y"])))
    ray_origin = b.vmath("ADD", origin, b.vscale(lateral, ortho))
    direction = b.vmath("ADD", forward, b.vscale(lateral, perspective))
    dir_n = b.vmath("DOT_PRODUCT", direction, normal)
    safe_dir_n = b.math("DIVIDE", dir_n, b.math("MAXIMUM", b.math("MULTIPLY", dir_n, dir_n), 1e-24))
    t = b.math("MULTIPLY", b.vmath("DOT_PRODUCT", b.vmath("SUBTRACT", position, ray_origin), normal), safe_dir_n)
    offset = b.vmath("SUBTRACT", b.vmath("ADD", ray_origin, b.vscale(direction, t)), position)
    # Keep the offset only where the centre ray meets the plane in front of
    # the camera and not absurdly far from the sample (near the horizon).
    in_front = b.math("MAXIMUM", b.math("GREATER_THAN", t, 0.0), ortho)
    reach = b.math("MULTIPLY", b.math("ADD", b.vmath("LENGTH", ju), b.vmath("LENGTH", jv)), 2.0)
    near = b.math("LESS_THAN", b.vmath("LENGTH", offset), reach)
    b.links.new(b.vscale(offset, b.math("MULTIPLY", in_front, near)), gout.inputs["Centre Offset"])


def noise_filter_group(octave_image, table, model, filter_stddev_px, taps=TAP_COUNT):
    """Vector, Scale, Units per World, Minor, Major, Axis U, Axis V, Samples,
    W -> Mean, Sigma, Offsets, Variances: the octave-wise filter of the noise
    `model` (noise_model.NoiseModel: offset + Σ c_i (Fac_i − 0.5), Fac_i a
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
    k = 1..3 (filtered_ramp_group(mixture=True) reads them)."""
    coefficients, offset, lacunarity = model.coefficients, model.offset, model.lacunarity
    if taps not in TAP_COUNTS:
        raise ValueError(f"taps must be one of {TAP_COUNTS}, not {taps}")
    key = (f"{model.dimensions} " + "/".join(f"{c:.6g}" for c in coefficients) +
           f" o{offset:g} l{lacunarity:g} d{model.distortion:g} w{model.w} k{filter_stddev_px:.4g} t{taps}")
    name = f"{NOISE_FILTER} ({key} spp)"
    group = bpy.data.node_groups.get(name)
    if group is not None and group.get("penumbra_version") == NOISE_FILTER_VERSION:
        return group
    if group is not None:   # built by an older Penumbra: materials that use it keep it
        group.name = name + " (old)"
    group, gin, gout = _new_group(name, [("Vector", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                         ("Scale", "NodeSocketFloat", 5.0),
                                         ("Units per World", "NodeSocketFloat", 1.0),
                                         ("Minor", "NodeSocketFloat", 0.0), ("Major", "NodeSocketFloat", 0.0),
                                         ("Axis U", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                         ("Axis V", "NodeSocketVector", (0.0, 0.0, 0.0)),
                                         ("Samples", "NodeSocketFloat", 1.0),
                                         ("W", "NodeSocketFloat", 0.0)],
                                  [("Mean", "NodeSocketFloat"), ("Sigma", "NodeSocketFloat"),
                                   ("Offsets", "NodeSocketVector"), ("Variances", "NodeSocketVector")])
    group["penumbra_octave_coefficients"] = list(coefficients)
    group["penumbra_octave_offset"] = offset
    group["penumbra_taps"] = taps
    b = _Builder(group)
    share = _kernel_share(b, gin.outputs["Samples"])
    log2_s, v = _footprint_table_coordinates(b, gin, table, filter_stddev_px, share)
    variance, weights = 0.0, []       # weights: c_i g_i, the shrunk octave's weight in the mean
    for i, c in enumerate(coefficients):
        q = _octave_fraction(b, octave_image, table, log2_s, v, i * math.log2(lacunarity),
                             weights[-1] if weights else None)
        g, term = _octave_shrinkage(b, q, taps)
        weights.append(b.math("MULTIPLY", g, c))
        variance = b.math("MULTIPLY_ADD", term, table["total_var"] * c * c, variance)
    mean, spread, offsets, variances = _tap_groups(b, gin, model, weights, filter_stddev_px, share, taps)
    b.connect(b.math("ADD", mean, offset), gout.inputs["Mean"])
    variance = b.math("ADD", variance, spread)
    b.links.new(b.math("SQRT", b.math("MAXIMUM", variance, 0.0)), gout.inputs["Sigma"])
    b.links.new(offsets, gout.inputs["Offsets"])
    b.links.new(variances, gout.inputs["Variances"])
    group["penumbra_version"] = NOISE_FILTER_VERSION
    return group


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
    outermost, octaves inside, each tap after the previous one (_zero_after):
    only the running sums stay live."""
    major = major_taps(taps // 2)
    per_group = len(major) // MIXTURE_COMPONENTS if len(major) >= MIXTURE_COMPONENTS else 1
    groups = [[0.0, 0.0] for _ in range(MIXTURE_COMPONENTS)]
    tap_at = _pixel_taps(b, gin, filter_stddev_px, share)
    s_t = 0.0
    for side in (-1.0, 1.0):
        for index, t in enumerate(major):
            tap = noise_model.distorted_vector(b, tap_at(side, t, s_t), gin.outputs["Scale"], model, gin.outputs["W"])
            s_t = 0.0
            for i, weight in enumerate(weights):
                scale = b.math("MULTIPLY", gin.outputs["Scale"], model.lacunarity ** i)
                fac = noise_model.octave_fac(b, tap, scale, model)
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
    looked up after the value `after` (see _zero_after)."""
    logs = table["log2_footprint"]
    u = b.texel(b.math("MULTIPLY_ADD", log2_s, 1.0 / (logs[-1] - logs[0]),
                       (log2_octave - logs[0]) / (logs[-1] - logs[0])), len(logs))
    if after is not None:
        u = b.math("ADD", u, _zero_after(b, after))
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
    node = b._place(b.nodes.new("ShaderNodeVectorTransform"))
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
            offset = b.vmath("ADD", offset, _zero_after(b, after))   # a float read as (z, z, z)
        return b.vmath("ADD", base, offset)
    return tap


def _zero_after(b, value):
    """A zero that Cycles can only compute once `value` is: min(|value|, 0)
    (fminf, so NaN gives 0 too). Cycles' SVM compiler emits, pass after pass,
    every node whose inputs are ready, so independent work (the 16 taps, the
    octave table's lookups) is evaluated level by level and all its values
    held at once on the 255-float SVM stack: 16 taps × 9 octaves, or 5
    octaves with Distortion, overflowed it and the shader rendered black.
    Chaining each tap (each lookup) after the previous one keeps one's values
    live at a time, for any Detail; EEVEE's GLSL does not care."""
    return b.math("MINIMUM", b.math("ABSOLUTE", value), 0.0)


def microsurface_image(folder=None):
    """256 × 2 float image, 'Non-Color'. Row 0 (bottom) against u in [0, 1):
    R = Λ/(1+Λ) at a = u/(1−u) (a = cot θ / σ_s), G = μ_d/σ_h and
    B = σ_d/σ_h (exact) at Λ_sum = u/(1−u). Row 1: R = E[z], G = sd[z] of the
    slope filtering distribution at c = u/(1−u) (c = cot θ_o / σ_s)."""
    from .. import native
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


def _table(b, image, x, row):
    """Sample row `row` of the microsurface image at u = x / (1 + x) (x >= 0)."""
    x = b.math("MAXIMUM", x, 0.0)
    u = b.math("DIVIDE", x, b.math("ADD", x, 1.0))
    return b.separate(b.image(image, b.texel(u, MICROSURFACE_TABLE_SIZE), (row + 0.5) / 2.0, alpha=False)[0])


def _cot_over_sigma(b, cos_theta, sigma):
    """cot θ / σ from cos θ (clamped to [0, 1])."""
    c = b.math("MINIMUM", b.math("MAXIMUM", cos_theta, 0.0), 1.0)
    sin = b.math("SQRT", b.math("MAXIMUM", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", c, c)), 1e-12))
    return b.math("DIVIDE", b.math("DIVIDE", c, sin), b.math("MAXIMUM", sigma, 1e-6))


def _lambda(b, image, a):
    g, _, _ = _table(b, image, a, 0)
    return b.math("DIVIDE", g, b.math("MAXIMUM", b.math("SUBTRACT", 1.0, g), 1e-6))  # Λ = g / (1 − g)


def height_ramp_group(lookup_image, spec, name=HEIGHT_RAMP):
    """Paper Sec. 5.1: Height Mean (the ramp's input at the mean surface),
    Height Sigma σ_h, Slope Sigma σ_s, Light Direction (world) -> Color (the
    ramp filtered over the visible and lit heights, N(mean + μ_d σ_h, σ_d σ_h))
    and Visibility V̄ (Eq. 13)."""
    group, gin, gout = _new_group(name, [("Height Mean", "NodeSocketFloat", 0.5),
                                         ("Height Sigma", "NodeSocketFloat", 0.1),
                                         ("Slope Sigma", "NodeSocketFloat", 0.3),
                                         ("Light Direction", "NodeSocketVector", (0.0, 0.0, 1.0))],
                                  [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat"),
                                   ("Visibility", "NodeSocketFloat")])
    b = _Builder(group)
    table = microsurface_image()
    geometry = b.nodes.new("ShaderNodeNewGeometry")
    normal = geometry.outputs["Normal"]
    cos_o = b.vmath("DOT_PRODUCT", geometry.outputs["Incoming"], normal)
    cos_i = b.vmath("DOT_PRODUCT", b.vmath("NORMALIZE", gin.outputs["Light Direction"]), normal)
    lam_o = _lambda(b, table, _cot_over_sigma(b, cos_o, gin.outputs["Slope Sigma"]))
    lam_i = _lambda(b, table, _cot_over_sigma(b, cos_i, gin.outputs["Slope Sigma"]))
    lam_sum = b.math("ADD", lam_o, lam_i)
    _, mu_d, sigma_d = _table(b, table, lam_sum, 0)
    mean = b.math("MULTIPLY_ADD", mu_d, gin.outputs["Height Sigma"], gin.outputs["Height Mean"])
    sigma = b.math("MULTIPLY", sigma_d, gin.outputs["Height Sigma"])
    color, alpha = b.image(lookup_image, *_lookup_uv(b, mean, sigma, spec))
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    one_plus_o = b.math("ADD", lam_o, 1.0)
    b.links.new(b.math("DIVIDE", one_plus_o, b.math("ADD", one_plus_o, lam_i)), gout.inputs["Visibility"])
    group["penumbra_lookup"] = dict(spec, image=lookup_image.name)
    return group


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
    group, gin, gout = _new_group(name, [("Value at Zero Slope", "NodeSocketFloat", 0.5),
                                         ("Value per Slope", "NodeSocketFloat", 1.0),
                                         ("Slope Sigma", "NodeSocketFloat", 0.3),
                                         ("Direction", "NodeSocketVector", (1.0, 0.0, 0.0)),
                                         ("Value Sigma", "NodeSocketFloat", 0.0)],
                                  [("Color", "NodeSocketColor"), ("Alpha", "NodeSocketFloat")])
    b = _Builder(group)
    table = microsurface_image()
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
    ez, sdz, _ = _table(b, table, _cot_over_sigma(b, cos_o, gin.outputs["Slope Sigma"]), 1)
    k_sigma = b.math("MULTIPLY", gin.outputs["Value per Slope"], gin.outputs["Slope Sigma"])
    mean = b.math("MULTIPLY_ADD", b.math("MULTIPLY", k_sigma, ez), cos_psi, gin.outputs["Value at Zero Slope"])
    shrink = b.math("MULTIPLY", b.math("SUBTRACT", 1.0, b.math("MULTIPLY", sdz, sdz)),
                    b.math("MULTIPLY", cos_psi, cos_psi))
    slope_variance = b.math("MULTIPLY", b.math("MULTIPLY", k_sigma, k_sigma),
                            b.math("MAXIMUM", b.math("SUBTRACT", 1.0, shrink), 0.0))
    sigma = b.math("SQRT", b.math("MULTIPLY_ADD", gin.outputs["Value Sigma"], gin.outputs["Value Sigma"],
                                  slope_variance))
    color, alpha = b.image(lookup_image, *_lookup_uv(b, mean, sigma, spec))
    b.links.new(color, gout.inputs["Color"])
    b.links.new(alpha, gout.inputs["Alpha"])
    group["penumbra_lookup"] = dict(spec, image=lookup_image.name)
    return group
