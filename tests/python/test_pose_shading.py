"""_penumbra.sh.shade_pose (core/sh/pose_shading.hpp) against a numpy
brute-force reference: the truncated visibility (ZH lobes as Legendre series,
no SH rotation) times the truncated lighting (sh.eval) times the kernel,
integrated over the hemisphere by Gauss-Legendre x equal steps, exact for
these polynomials. Plus closed forms (unit radiance) and the contract of the
binding (shapes, dtypes, errors, invalid vertices)."""

import math

import numpy as np
import pytest

import _penumbra

FOUR_PI = 4.0 * math.pi


def random_directions(rng, n):
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def random_pose(rng, n, lobes, order):
    return dict(
        lobe_axes=rng.normal(size=(n, lobes, 3)),
        lobe_bands=rng.uniform(-1, 1, size=(n, lobes, order)),
        normals=random_directions(rng, n) * rng.uniform(0.5, 2.0, size=(n, 1)),
        tangents=rng.normal(size=(n, 3)),
        positions=rng.uniform(-1, 1, size=(n, 3)),
    )


def frames(normals, tangents):
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    t = tangents - np.sum(tangents * n, axis=1, keepdims=True) * n
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return t, np.cross(n, t), n


def hemisphere(axis, mu_nodes=40, phi_steps=64):
    """Directions and weights of a rule exact on the hemisphere about `axis`."""
    x, w = np.polynomial.legendre.leggauss(mu_nodes)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    phi = 2 * math.pi * (np.arange(phi_steps) + 0.5) / phi_steps
    e1 = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = e1 - e1.dot(axis) * axis
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    s = np.sqrt(1 - mu ** 2)
    dirs = (mu[:, None, None] * axis + s[:, None, None] * (np.cos(phi)[None, :, None] * e1 + np.sin(phi)[None, :, None] * e2))
    weights = np.repeat(w[:, None] * 2 * math.pi / phi_steps, phi_steps, axis=1)
    return dirs.reshape(-1, 3), weights.reshape(-1), np.repeat(mu, phi_steps)


def zonal_visibility(axes_world, bands, dirs):
    """sum over lobes and l of g_l sqrt((2l+1)/4pi) P_l(axis . w)."""
    order = bands.shape[1]
    total = np.zeros(len(dirs))
    for axis, g in zip(axes_world, bands):
        if np.linalg.norm(axis) == 0:
            continue
        mu = np.clip(dirs @ (axis / np.linalg.norm(axis)), -1, 1)
        coefficients = [g[l] * math.sqrt((2 * l + 1) / FOUR_PI) for l in range(order)]
        total += np.polynomial.legendre.legval(mu, coefficients)
    return total


def reflection_axis(n, position, camera):
    w = np.asarray(camera, float) - position
    if np.linalg.norm(w) == 0:
        return n
    w /= np.linalg.norm(w)
    c = n.dot(w)
    if c >= 0:
        r = 2 * c * n - w
        return r / np.linalg.norm(r)
    h = w - c * n
    return -h / np.linalg.norm(h) if np.linalg.norm(h) > 1e-12 else n


def brute_force(order, lighting, pose, brdf, exponent=1.0, camera=None, transmission=(1, 1, 1)):
    t, b, n = frames(pose["normals"], pose["tangents"])
    out = np.zeros((len(n), 3))
    for i in range(len(n)):
        frame = np.stack([t[i], b[i], n[i]], axis=1)
        axes_world = pose["lobe_axes"][i] @ frame.T
        axis = reflection_axis(n[i], pose["positions"][i], camera) if brdf == "phong" else n[i]
        dirs, weights, mu = hemisphere(axis)
        kernel = (exponent + 1) / (2 * math.pi) * mu ** exponent if brdf == "phong" else mu / math.pi
        radiance = _penumbra.sh.eval(order, dirs) @ lighting
        vis = zonal_visibility(axes_world, pose["lobe_bands"][i], dirs)
        out[i] = (weights * kernel * vis) @ radiance
        if brdf == "translucent":
            dirs, weights, mu = hemisphere(-n[i])
            out[i] += np.asarray(transmission) * ((weights * mu / math.pi) @ (_penumbra.sh.eval(order, dirs) @ lighting))
    return out


def unit_radiance(order):
    lighting = np.zeros((order * order, 3))
    lighting[0] = math.sqrt(FOUR_PI)
    return lighting


def shade(order, lighting, pose, **kwargs):
    return _penumbra.sh.shade_pose(order, lighting, pose["lobe_axes"], pose["lobe_bands"], pose["normals"],
                                   pose["tangents"], **kwargs)


def fully_visible(rng, n, order, dtype=np.float64):
    pose = random_pose(rng, n, 2, order)
    pose["lobe_bands"][:] = 0
    pose["lobe_bands"][:, 0, 0] = math.sqrt(FOUR_PI)
    return {k: v.astype(dtype) for k, v in pose.items()}


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_fully_visible_vertex_under_unit_radiance_shades_to_one(dtype):
    rng = np.random.default_rng(1)
    order = 4
    pose = fully_visible(rng, 50, order, dtype)
    rgb, stats = shade(order, unit_radiance(order), pose, with_stats=True)
    assert rgb.dtype == np.float32 and rgb.shape == (50, 3)
    np.testing.assert_allclose(rgb, 1.0, atol=1e-6)
    np.testing.assert_allclose(stats["visibility"], 1.0, atol=1e-6)
    assert stats["invalid_vertices"] == 0


def test_unoccluded_vertex_under_environment_gives_its_truncated_irradiance():
    # A sky image as Blender's World would show it: bright zenith, warm sun
    # towards +x, dark ground; projected by the module, then shaded unoccluded.
    h, w = 64, 128
    theta = math.pi * (np.arange(h) + 0.5) / h
    phi = math.pi - 2 * math.pi * (np.arange(w) + 0.5) / w
    z = np.cos(theta)[:, None] * np.ones(w)
    x = np.sin(theta)[:, None] * np.cos(phi)[None, :]
    sky = np.where(z > 0, 1 + 3 * z * z, 0.2)
    sun = np.exp(8 * (0.8 * x + 0.6 * z - 1))
    image = np.stack([sky + 4 * sun, sky + 2 * sun, 1.5 * sky], axis=-1).astype(np.float32)
    rng = np.random.default_rng(2)
    for order in (2, 3, 4):
        lighting = _penumbra.sh.project_environment(order, image)
        pose = fully_visible(rng, 20, order)
        rgb = shade(order, lighting, pose)
        n = pose["normals"] / np.linalg.norm(pose["normals"], axis=1, keepdims=True)
        for i in range(len(n)):
            dirs, weights, mu = hemisphere(n[i])
            irradiance_over_pi = (weights * mu / math.pi) @ (_penumbra.sh.eval(order, dirs) @ lighting)
            np.testing.assert_allclose(rgb[i], irradiance_over_pi, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("brdf", ["diffuse", "phong"])
def test_fully_occluded_vertex_shades_to_zero(brdf):
    rng = np.random.default_rng(3)
    order = 4
    pose = random_pose(rng, 30, 2, order)
    pose["lobe_bands"][:] = 0
    lighting = rng.normal(size=(16, 3))
    rgb, stats = shade(order, lighting, pose, brdf=brdf, exponent=20.0, positions=pose["positions"],
                       camera=(0, 0, 3), with_stats=True)
    assert np.all(rgb == 0) and np.all(stats["visibility"] == 0)


@pytest.mark.parametrize("exponent", [0.0, 0.5, 1.0, 1000.0, 1e6, math.inf])
def test_normalized_phong_conserves_energy(exponent):
    rng = np.random.default_rng(4)
    order = 4
    pose = fully_visible(rng, 40, order)
    rgb = shade(order, unit_radiance(order), pose, brdf="phong", exponent=exponent,
                positions=pose["positions"], camera=(0.3, -3.0, 2.0))
    np.testing.assert_allclose(rgb, 1.0, atol=1e-6)


@pytest.mark.parametrize("brdf,exponent", [("diffuse", 1.0), ("phong", 1.0), ("phong", 15.0), ("translucent", 1.0)])
def test_matches_brute_force_hemisphere_quadrature(brdf, exponent):
    rng = np.random.default_rng(5)
    order = 4
    pose = random_pose(rng, 8, 2, order)
    lighting = rng.uniform(-1, 1, size=(16, 3))
    camera = (0.4, 1.5, 1.2)
    transmission = (0.2, 0.5, 0.9)
    rgb = shade(order, lighting, pose, brdf=brdf, exponent=exponent, positions=pose["positions"],
                camera=camera, transmission=transmission)
    expected = brute_force(order, lighting, pose, brdf, exponent, camera, transmission)
    # float32 output: 1e-6 of the size of the terms.
    np.testing.assert_allclose(rgb, expected, rtol=1e-5, atol=2e-6)


def test_turning_the_whole_scene_leaves_shades_unchanged():
    rng = np.random.default_rng(6)
    order = 5
    pose = random_pose(rng, 60, 2, order)
    lighting = rng.uniform(-1, 1, size=(25, 3))
    r = random_rotation(rng)
    turned = dict(pose, normals=pose["normals"] @ r.T, tangents=pose["tangents"] @ r.T,
                  positions=pose["positions"] @ r.T)
    camera = np.array([2.0, 1.0, -3.0])
    for brdf in ("diffuse", "phong", "translucent"):
        a = shade(order, lighting, pose, brdf=brdf, exponent=9.0, positions=pose["positions"], camera=camera)
        b = shade(order, _penumbra.sh.rotate(lighting, r), turned, brdf=brdf, exponent=9.0,
                  positions=turned["positions"], camera=r @ camera)
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6)


def test_results_do_not_depend_on_thread_count():
    rng = np.random.default_rng(7)
    pose = {k: v.astype(np.float32) for k, v in random_pose(rng, 20001, 2, 4).items()}
    lighting = rng.normal(size=(16, 3))
    results = [shade(4, lighting, pose, brdf="phong", exponent=30.0, positions=pose["positions"], camera=(0, -3, 1),
                     threads=t) for t in (1, 2, 3, 0)]
    for other in results[1:]:
        assert np.array_equal(results[0], other)


def test_float32_inputs_match_float64_inputs_to_float_precision():
    rng = np.random.default_rng(8)
    pose = {k: v.astype(np.float32) for k, v in random_pose(rng, 100, 2, 4).items()}
    pose64 = {k: v.astype(np.float64) for k, v in pose.items()}
    lighting = rng.normal(size=(16, 3))
    a = shade(4, lighting, pose, brdf="translucent", transmission=(0.5, 0.5, 0.5))
    b = shade(4, lighting, pose64, brdf="translucent", transmission=(0.5, 0.5, 0.5))
    np.testing.assert_array_equal(a, b)  # same numbers in, double arithmetic either way


def test_invalid_vertices_shade_to_zero_and_are_counted():
    rng = np.random.default_rng(9)
    pose = random_pose(rng, 6, 2, 3)
    pose["normals"][1] = (np.nan, 0, 1)
    pose["normals"][2] = 0
    pose["tangents"][3] = pose["normals"][3] * 2  # tangent along the normal
    pose["lobe_bands"][4, 1, 2] = np.inf
    lighting = rng.normal(size=(9, 3))
    rgb, stats = shade(3, lighting, pose, with_stats=True)
    assert stats["invalid_vertices"] == 4
    assert np.all(rgb[1:5] == 0) and np.all(stats["visibility"][1:5] == 0)
    assert np.all(np.isfinite(rgb)) and np.all(rgb[[0, 5]] != 0)
    # The caller's arrays are left as they were.
    assert np.isnan(pose["normals"][1, 0]) and np.isinf(pose["lobe_bands"][4, 1, 2])


def test_bad_arguments_raise_value_error():
    rng = np.random.default_rng(10)
    pose = random_pose(rng, 4, 1, 4)
    good = rng.normal(size=(16, 3))
    bad_cases = [
        dict(lighting=rng.normal(size=(9, 3))),
        dict(lighting=rng.normal(size=(16, 4))),
        dict(lighting=np.full((16, 3), np.nan)),
        dict(lobe_bands=pose["lobe_bands"][:, :, :3]),
        dict(lobe_axes=pose["lobe_axes"][:, :, :2]),
        dict(normals=pose["normals"][:3]),
        dict(tangents=pose["tangents"].T),
        dict(brdf="lambert"),
        dict(brdf="phong"),  # no positions / camera
        dict(brdf="phong", exponent=-1.0, positions=pose["positions"], camera=(0, 0, 1)),
        dict(brdf="phong", exponent=2.0, positions=pose["positions"][:2], camera=(0, 0, 1)),
        dict(brdf="phong", exponent=2.0, positions=pose["positions"], camera=(0, math.nan, 1)),
        dict(brdf="translucent", transmission=(1, math.inf, 1)),
        dict(threads=-1),
        dict(order=0),
        dict(order=17),
    ]
    for case in bad_cases:
        args = dict(order=4, lighting=good, **pose)
        args.pop("positions")
        args.update(case)
        with pytest.raises(ValueError):
            _penumbra.sh.shade_pose(args.pop("order"), args.pop("lighting"), args.pop("lobe_axes"),
                                    args.pop("lobe_bands"), args.pop("normals"), args.pop("tangents"), **args)


def test_empty_pose_gives_empty_output():
    out = _penumbra.sh.shade_pose(2, np.zeros((4, 3)), np.zeros((0, 1, 3)), np.zeros((0, 1, 2)), np.zeros((0, 3)),
                                  np.zeros((0, 3)))
    assert out.shape == (0, 3) and out.dtype == np.float32
