"""The "Penumbra Pixel Footprint" group: Pixel Size, Orthographic, Raster
Offset X/Y -> Footprint, Minor, Major, Axis U, Axis V, Centre Offset: the
pixel's footprint on the surface from the Jacobian of the camera
projection, and the offset to the pixel's centre (docs/colormap.md,
"Footprint")."""

import bpy

from . import interface
from .node_builder import Builder, new_group
from .node_groups import FOOTPRINT

# A pixel ray that misses the tangent plane (beyond the horizon) is taken to
# meet it at this many times the sample's own distance: the footprint is
# bounded there instead of infinite.
HORIZON_REACH = 20.0


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
    group, gin, gout = new_group(FOOTPRINT, [("Pixel Size", "NodeSocketFloat", 0.001),
                                             ("Orthographic", "NodeSocketFloat", 0.0),
                                             ("Raster Offset X", "NodeSocketFloat", 0.0),
                                             ("Raster Offset Y", "NodeSocketFloat", 0.0)],
                                 [("Footprint", "NodeSocketFloat"), ("Minor", "NodeSocketFloat"),
                                  ("Major", "NodeSocketFloat"), ("Axis U", "NodeSocketVector"),
                                  ("Axis V", "NodeSocketVector"), ("Centre Offset", "NodeSocketVector")])
    b = Builder(group)
    geometry = b.nodes.new("ShaderNodeNewGeometry")
    to_point, forward, right, up = _camera_frame(b, geometry)
    ju, jv = _footprint_jacobian(b, gin, geometry, to_point, forward, right, up)
    _footprint_ellipse(b, ju, jv, gout)
    _centre_offset(b, gin, gout, geometry, forward, right, up, ju, jv)
    return group


def _camera_transform(b, vector, kind="VECTOR"):
    node = b.place(b.nodes.new("ShaderNodeVectorTransform"))
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
