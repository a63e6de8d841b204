"""The microsurface (height and slope) groups evaluated by Cycles against the
core's effective height and visible slope distributions, one small plane
per pixel."""

import os

import bpy
import numpy as np

from penumbra import compat, native

from penumbra.colormap import height_ramp, microsurface, slope_ramp, table_image

# One tiny plane per pixel under an orthographic camera looking down −Z: each
# plane has its own tilt (so its own view angle: Incoming is +Z everywhere)
# and carries the group's inputs as custom properties, read by Attribute
# nodes (Object). A 0.01-px box filter at 1 spp shades each pixel at its
# centre, which sees only its own plane (side 0.5 px).
GRID = 8
# Colour map of the tests: R = v (the filtered mean itself), G a wave
# (sensitive to σ), B = v², 129 knots joined linearly.
_KNOTS = np.linspace(0.0, 1.0, 129)
_MAP = np.column_stack([_KNOTS, 0.5 + 0.4 * np.sin(3.0 * np.pi * _KNOTS), _KNOTS ** 2])


def _pixel_planes(scene, normals, props):
    """An orthographic GRID × GRID render of one small plane per pixel; pixel
    (row j from the top, column i) holds planes[j * GRID + i], whose normal is
    normals[k] and whose custom properties are props[k] (name -> 3-vector).
    Returns the emission node's material tree and the emission node."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.samples = 1
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x = scene.render.resolution_y = GRID
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = GRID
    camera.location = (0.0, 0.0, 10.0)
    scene.camera = camera
    mesh = bpy.data.meshes.new("quad")
    s = 0.25
    mesh.from_pydata([(-s, -s, 0), (s, -s, 0), (s, s, 0), (-s, s, 0)], [], [(0, 1, 2, 3)])
    material = bpy.data.materials.new("probe")
    tree = compat.ensure_nodes(material)
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    mesh.materials.append(material)
    from mathutils import Vector
    for k, (normal, values) in enumerate(zip(normals, props)):
        obj = bpy.data.objects.new(f"probe{k}", mesh)
        scene.collection.objects.link(obj)
        j, i = divmod(k, GRID)
        obj.location = (-GRID / 2 + i + 0.5, GRID / 2 - j - 0.5, 0.0)
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(normal))
        for name, value in values.items():
            obj[name] = [float(v) for v in value]
    bpy.context.view_layer.update()
    return tree, emission


def _object_vector(tree, name):
    node = tree.nodes.new("ShaderNodeAttribute")
    node.attribute_type = "OBJECT"
    node.attribute_name = name
    return node.outputs["Vector"]


def _separate(tree, vector):
    node = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(vector, node.inputs[0])
    return node.outputs


def _lookup(tmp_path, mean_min, mean_max, sigma_max, width=256, height=64):
    """The lookup image and a function giving, at given (mean, σ), the
    bilinear error of its table (read as a texture: texel centres, clamped
    edges) against the exact filtered map: the error the group cannot avoid."""
    core = native.require()
    table = core.colormap.lut_knots(_KNOTS, _MAP, "linear", width, height, sigma_max, mean_min, mean_max)
    spec = {"width": width, "height": height, "sigma_max": sigma_max, "mean_min": mean_min, "mean_max": mean_max,
            "sigma_spacing": "linear"}
    image = table_image.table_image("probe lookup", table, str(tmp_path))

    def bilinear_error(means, sigmas):
        x = np.clip((means - mean_min) / (mean_max - mean_min) * (width - 1), 0, width - 1)
        y = np.clip(sigmas / sigma_max * (height - 1), 0, height - 1)
        x0 = np.minimum(np.floor(x).astype(int), width - 2)
        y0 = np.minimum(np.floor(y).astype(int), height - 2)
        fx, fy = (x - x0)[:, None], (y - y0)[:, None]
        value = ((table[y0, x0] * (1 - fx) + table[y0, x0 + 1] * fx) * (1 - fy)
                 + (table[y0 + 1, x0] * (1 - fx) + table[y0 + 1, x0 + 1] * fx) * fy)
        return np.abs(value - core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)).max(axis=1)
    return image, spec, bilinear_error


def _table_interp(values_at, x):
    """Linear interpolation of a 256-entry table over u = x/(1+x) (the
    microsurface image's layout: node i at u = i/255, the last at 1 − 1/1024)."""
    u = np.arange(microsurface.MICROSURFACE_TABLE_SIZE) / (microsurface.MICROSURFACE_TABLE_SIZE - 1)
    u[-1] = 1.0 - 1.0 / (4 * microsurface.MICROSURFACE_TABLE_SIZE)
    nodes = np.array([values_at(v / (1.0 - v)) for v in u])
    x = np.asarray(x, float)
    return np.array([np.interp(xi / (1.0 + xi) if np.isfinite(xi) else 1.0, u, nodes[:, c])
                     for xi in x for c in range(nodes.shape[1])]).reshape(len(x), -1)


def _render_pixels(scene, path):
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return native.require().image.read(path)[..., :3].astype(np.float64).reshape(-1, 3)


def _random_normals(rng, count, min_deg, max_deg):
    theta = np.radians(rng.uniform(min_deg, max_deg, count))
    phi = rng.uniform(0.0, 2 * np.pi, count)
    return np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]), theta


def _tangent_frame(normal):
    from mathutils import Vector
    rotation = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(normal)).to_matrix()
    return np.array(rotation.col[0]), np.array(rotation.col[1]), np.array(rotation.col[2])


def test_height_filtered_ramp_renders_the_effective_height_distribution(addon, tmp_path):
    """Penumbra Height Filtered Ramp in Cycles against the core: per pixel,
    Λ_o, Λ_i = smith_lambda(θ, σ_s), (μ_d, σ_d) = effective_height(Λ_o + Λ_i,
    'exact'), Color = the exact filtered map at (mean + μ_d σ_h, σ_d σ_h)
    (colormap.filtered) and Visibility = average_visibility(Λ_o, Λ_i)."""
    core = native.require()
    rng = np.random.default_rng(11)
    count = GRID * GRID
    normals, theta_o = _random_normals(rng, count, 40.0, 86.0)
    theta_o[:4] = 0.0
    normals[:4] = (0.0, 0.0, 1.0)
    # Light: random polar angle from each plane's normal (0 for some, the view for others).
    lights = np.empty((count, 3))
    theta_i = np.radians(rng.uniform(0.0, 85.0, count))
    theta_i[4:10] = 0.0
    for k in range(count):
        t1, t2, n = _tangent_frame(normals[k])
        psi = rng.uniform(0, 2 * np.pi)
        lights[k] = 2.5 * (np.sin(theta_i[k]) * (np.cos(psi) * t1 + np.sin(psi) * t2) + np.cos(theta_i[k]) * n)
    lights[10:16] = (0.0, 0.0, 3.0)  # the light at the viewer
    theta_i[10:16] = theta_o[10:16]
    height_mean = rng.uniform(0.25, 0.55, count)
    height_sigma = rng.uniform(0.05, 0.3, count)
    slope_sigma = rng.uniform(0.15, 1.0, count)
    props = [{"inputs": (height_mean[k], height_sigma[k], slope_sigma[k]), "light": lights[k]} for k in range(count)]
    tree, emission = _pixel_planes(addon, normals, props)
    image, spec, bilinear_error = _lookup(tmp_path, -0.25, 1.75, 0.4)
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = height_ramp.height_ramp_group(image, spec)
    inputs = _separate(tree, _object_vector(tree, "inputs"))
    for index, name in enumerate(("Height Mean", "Height Sigma", "Slope Sigma")):
        tree.links.new(inputs[index], group.inputs[name])
    tree.links.new(_object_vector(tree, "light"), group.inputs["Light Direction"])
    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    color = _render_pixels(addon, str(tmp_path / "height.exr"))
    # Visibility, with the plane's location as a check of the pixel layout.
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    location = _separate(tree, tree.nodes.new("ShaderNodeObjectInfo").outputs["Location"])
    tree.links.new(group.outputs["Visibility"], combine.inputs[0])
    tree.links.new(location[0], combine.inputs[1])
    tree.links.new(location[1], combine.inputs[2])
    tree.links.new(combine.outputs[0], emission.inputs["Color"])
    visibility = _render_pixels(addon, str(tmp_path / "visibility.exr"))
    rows, cols = np.divmod(np.arange(count), GRID)
    np.testing.assert_allclose(visibility[:, 1:], np.column_stack([cols - GRID / 2 + 0.5, GRID / 2 - rows - 0.5]),
                               atol=1e-5)

    lam_o = np.array([core.colormap.smith_lambda(t, s) for t, s in zip(theta_o, slope_sigma)])
    lam_i = np.array([core.colormap.smith_lambda(t, s) for t, s in zip(theta_i, slope_sigma)])

    def filtering(lam_view, lam_light, shift=True):
        stats = np.array([core.colormap.effective_height(lo + li, "exact") for lo, li in zip(lam_view, lam_light)])
        return height_mean + (stats[:, 0] * height_sigma if shift else 0.0), stats[:, 1] * height_sigma

    means, sigmas = filtering(lam_o, lam_i)
    truth = core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)
    # Tolerance per pixel: the lookup's bilinear error at (mean, σ), plus what
    # linear interpolation of the 256-entry microsurface tables of Λ/(1+Λ)
    # and (μ_d, σ_d) changes (the tables' values from the core at their
    # nodes), plus float32.
    def lam_table(a):
        lam = core.colormap.smith_lambda_of_a(a) if a > 0 else np.inf
        return (1.0 if np.isinf(lam) else lam / (1.0 + lam),)

    def lam_from_table(theta):
        cot = np.cos(theta) / np.maximum(np.sin(theta), 1e-6)
        g = _table_interp(lam_table, cot / slope_sigma)[:, 0]
        return g / np.maximum(1.0 - g, 1e-6)

    lam_sum = lam_from_table(theta_o) + lam_from_table(theta_i)
    stats = _table_interp(lambda x: core.colormap.effective_height(x, "exact"), lam_sum)
    tabled = core.colormap.filtered(_KNOTS, _MAP, "linear", height_mean + stats[:, 0] * height_sigma,
                                    stats[:, 1] * height_sigma)
    tolerance = bilinear_error(means, sigmas) + np.abs(tabled - truth).max(axis=1) + 2e-4
    error = np.abs(color - truth).max(axis=1)
    print(f"height group: max error {error.max():.2e}, max error/tolerance {(error / tolerance).max():.2f}, "
          f"median tolerance {np.median(tolerance):.1e}")
    assert (error < tolerance).all(), (error.max(), int(np.argmax(error / tolerance)))
    np.testing.assert_allclose(visibility[:, 0],
                               [core.colormap.average_visibility(lo, li) for lo, li in zip(lam_o, lam_i)], atol=2e-3)
    # The test can fail: ignoring the view angle or the shift of the height
    # distribution moves many pixels far outside the tolerance.
    for wrong in (filtering(np.zeros(count), lam_i), filtering(lam_o, lam_i, shift=False)):
        off = np.abs(color - core.colormap.filtered(_KNOTS, _MAP, "linear", *wrong)).max(axis=1)
        assert (off > 5 * tolerance).sum() > count // 3, (off / tolerance)


def test_slope_filtered_ramp_renders_the_visible_slope_distribution(addon, tmp_path):
    """Penumbra Slope Filtered Ramp in Cycles against the core's brute-force
    slope filtering distribution: per pixel, slope_filtering(θ_o, φ_o, 0,
    σ_s² I, 'numerical') in the plane's tangent frame, v = v0 + k s·D (D the
    Direction input projected onto the plane), Color = the exact filtered map
    at (v0 + k mean·D, |k| √(Dᵀ Cov D))."""
    core = native.require()
    rng = np.random.default_rng(5)
    count = GRID * GRID
    normals, theta_o = _random_normals(rng, count, 0.0, 86.0)
    theta_o[:4] = 0.0
    normals[:4] = (0.0, 0.0, 1.0)
    directions = rng.normal(size=(count, 3))  # world vectors, not in the plane
    slope_sigma = rng.uniform(0.15, 0.8, count)
    per_slope = rng.uniform(0.15, 0.35, count) / slope_sigma * rng.choice([-1.0, 1.0], count)
    at_zero = rng.uniform(0.3, 0.7, count)
    props = [{"inputs": (at_zero[k], per_slope[k], slope_sigma[k]), "direction": directions[k]} for k in range(count)]
    tree, emission = _pixel_planes(addon, normals, props)
    image, spec, bilinear_error = _lookup(tmp_path, -0.5, 1.5, 0.4)
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = slope_ramp.slope_ramp_group(image, spec)
    inputs = _separate(tree, _object_vector(tree, "inputs"))
    for index, name in enumerate(("Value at Zero Slope", "Value per Slope", "Slope Sigma")):
        tree.links.new(inputs[index], group.inputs[name])
    tree.links.new(_object_vector(tree, "direction"), group.inputs["Direction"])
    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    color = _render_pixels(addon, str(tmp_path / "slope.exr"))

    def expected(view=True):
        means, sigmas = np.empty(count), np.empty(count)
        for k in range(count):
            t1, t2, n = _tangent_frame(normals[k])
            d = np.array([directions[k] @ t1, directions[k] @ t2])
            d /= np.linalg.norm(d)
            eye = np.array([0.0, 0.0, 1.0])
            theta = np.arccos(np.clip(eye @ n, -1, 1)) if view else 0.0
            phi = np.arctan2(eye @ t2, eye @ t1)
            var = slope_sigma[k] ** 2
            mean, cov = core.colormap.slope_filtering(theta, phi, (0.0, 0.0), (var, 0.0, var), "numerical", 401)
            means[k] = at_zero[k] + per_slope[k] * (np.array(mean) @ d)
            c = np.array([[cov[0], cov[1]], [cov[1], cov[2]]])
            sigmas[k] = abs(per_slope[k]) * np.sqrt(d @ c @ d)
        return means, sigmas

    means, sigmas = expected()
    truth = core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)
    # Tolerance per pixel: the lookup's bilinear error at (mean, σ), plus what
    # linear interpolation of the 256-entry table of (E[z], sd[z]) changes
    # (and the brute force's own error), plus float32.
    cot = np.cos(theta_o) / np.maximum(np.sin(theta_o), 1e-6)
    shift = _table_interp(lambda c: core.colormap.slope_shift(c), cot / slope_sigma)
    cos_psi = np.empty(count)
    for k in range(count):
        t1, t2, n = _tangent_frame(normals[k])
        d = np.array([directions[k] @ t1, directions[k] @ t2])
        view = np.array([t1[2], t2[2]])  # the eye (+Z) in the plane's frame
        cos_psi[k] = d @ view / np.linalg.norm(d) / max(np.linalg.norm(view), 1e-12)
    k_sigma = per_slope * slope_sigma
    tabled = core.colormap.filtered(
        _KNOTS, _MAP, "linear", at_zero + k_sigma * shift[:, 0] * cos_psi,
        np.abs(k_sigma) * np.sqrt(np.maximum(1.0 - (1.0 - shift[:, 1] ** 2) * cos_psi ** 2, 0.0)))
    tolerance = bilinear_error(means, sigmas) + np.abs(tabled - truth).max(axis=1) + 2e-4
    error = np.abs(color - truth).max(axis=1)
    print(f"slope group: max error {error.max():.2e}, max error/tolerance {(error / tolerance).max():.2f}, "
          f"median tolerance {np.median(tolerance):.1e}")
    assert (error < tolerance).all(), (error.max(), int(np.argmax(error / tolerance)))
    # The test can fail: ignoring the view (the slopes' unshifted
    # distribution) moves many pixels far outside the tolerance.
    off = np.abs(color - core.colormap.filtered(_KNOTS, _MAP, "linear", *expected(view=False))).max(axis=1)
    assert (off > 5 * tolerance).sum() > count // 3, (off / tolerance)
