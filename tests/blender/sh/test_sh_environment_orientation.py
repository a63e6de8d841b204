"""`_penumbra.sh.project_environment` is oriented exactly as Blender's World maps
an Environment Texture: checked against Cycles itself.

Cycles bakes the diffuse lighting (irradiance / π, albedo excluded) of a
convex ico-sphere lit only by a World that shows a strongly directional
equirectangular image. The same image projected with sh.project_environment and
convolved with the clamped cosine (coefficients computed here by quadrature,
independently of the core) must predict every vertex. A mirrored or rotated
mapping would be off by far more than the tolerance."""

import math
import os

import bpy
import numpy as np
import pytest

from penumbra import compat, native

_penumbra = native.require()

ORDER = 9  # bands 0..8: the clamped cosine's truncation error is < 1 % here


def directional_image(height=48, width=96):
    """Dim blue sky with two bright warm patches at asymmetric spots, so any
    flip or rotation of the mapping changes the lighting visibly."""
    rows, cols = np.mgrid[0:height, 0:width]
    image = np.zeros((height, width, 3), np.float32)
    image[...] = (0.05, 0.08, 0.12)
    for (r, c, radius, rgb) in ((14, 30, 7, (6.0, 4.0, 2.0)), (30, 70, 5, (1.0, 3.0, 1.5))):
        blob = np.exp(-((rows - r) ** 2 + (cols - c) ** 2) / (2 * radius ** 2))
        image += blob[..., None] * np.array(rgb, np.float32)
    return image


def clamped_cosine_bands(order):
    """Â_l/π: the clamped cosine's zonal coefficients (Ramamoorthy–Hanrahan),
    by Gauss–Legendre quadrature of 2π ∫_0^1 P_l(μ) μ dμ, then / π."""
    mu, w = np.polynomial.legendre.leggauss(64)
    mu = 0.5 * (mu + 1)
    w = 0.5 * w
    out = []
    for l in range(order):
        p = np.polynomial.legendre.Legendre.basis(l)(mu)
        out.append(2 * math.pi * np.sum(w * p * mu) / math.pi)
    return np.array(out)


def predicted_diffuse_light(coeffs, normals):
    """E(n)/π = Σ_l (Â_l/π) Σ_m L_lm y_lm(n)."""
    y = _penumbra.sh.eval(ORDER, normals)
    a = clamped_cosine_bands(ORDER)
    scale = np.concatenate([[a[l]] * (2 * l + 1) for l in range(ORDER)])
    return (y * scale) @ coeffs


def bake_world_lighting(image_path, samples):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.cycles.max_bounces = 0

    world = bpy.data.worlds.new("probe")
    nodes = compat.ensure_nodes(world).nodes
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(image_path)
    env.image.colorspace_settings.name = _linear_name()
    env.interpolation = "Closest"
    world.node_tree.links.new(env.outputs["Color"], nodes["Background"].inputs["Color"])
    scene.world = world

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=1.0)
    sphere = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    material = bpy.data.materials.new("white")
    compat.ensure_nodes(material).nodes["Principled BSDF"].inputs["Base Color"].default_value = (1, 1, 1, 1)
    sphere.data.materials.append(material)
    attribute = sphere.data.color_attributes.new("light", "FLOAT_COLOR", "POINT")
    sphere.data.color_attributes.active_color = attribute
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, target="VERTEX_COLORS")

    mesh = sphere.data
    normals = np.array([v.normal[:] for v in mesh.vertices])
    colors = np.zeros(len(mesh.vertices) * 4, np.float32)
    attribute = mesh.color_attributes["light"]
    attribute.data.foreach_get("color", colors)
    return normals, colors.reshape(-1, 4)[:, :3]


def _linear_name():
    names = {item.identifier for item in bpy.types.ColorManagedInputColorspaceSettings.bl_rna.properties["name"].enum_items}
    return "Linear Rec.709" if "Linear Rec.709" in names else "Linear"


def test_projection_predicts_cycles_world_lighting(factory_scene, tmp_path):
    image = directional_image()
    path = str(tmp_path / "probe.exr")
    _penumbra.image.write_exr(path, image, half=False)
    normals, baked = bake_world_lighting(path, samples=256)

    coeffs = _penumbra.sh.project_environment(ORDER, image)
    predicted = predicted_diffuse_light(coeffs, normals)

    # Orientation is the point: a mirrored mapping must fail. Build it and
    # check it is far off, so this test can tell the two apart.
    mirrored = predicted_diffuse_light(_penumbra.sh.project_environment(ORDER, image[:, ::-1].copy()), normals)
    error = np.abs(predicted - baked).max() / baked.max()
    mirrored_error = np.abs(mirrored - baked).max() / baked.max()
    print(f"relative error {error:.4f}, mirrored mapping {mirrored_error:.4f}, peak {baked.max():.3f}")
    assert mirrored_error > 0.2, mirrored_error
    assert error < 0.04, (error, mirrored_error)
