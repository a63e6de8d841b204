"""The SH bindings against references written here in numpy: hand-written
closed forms for bands 0-3, an angle-based associated-Legendre recurrence for
higher bands, and numpy's own Gauss-Legendre quadrature."""

import math

import numpy as np
import pytest

import _penumbra as pen

RNG = np.random.default_rng(1234)


def random_directions(n):
    d = RNG.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def random_rotation():
    q = RNG.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def closed_form_bands_0_to_3(d):
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    pi = math.pi
    return np.stack([
        np.full_like(x, 0.5 / math.sqrt(pi)),
        math.sqrt(3 / (4 * pi)) * y,
        math.sqrt(3 / (4 * pi)) * z,
        math.sqrt(3 / (4 * pi)) * x,
        0.5 * math.sqrt(15 / pi) * x * y,
        0.5 * math.sqrt(15 / pi) * y * z,
        0.25 * math.sqrt(5 / pi) * (3 * z * z - 1),
        0.5 * math.sqrt(15 / pi) * x * z,
        0.25 * math.sqrt(15 / pi) * (x * x - y * y),
        0.25 * math.sqrt(35 / (2 * pi)) * (3 * x * x - y * y) * y,
        0.5 * math.sqrt(105 / pi) * x * y * z,
        0.25 * math.sqrt(21 / (2 * pi)) * y * (5 * z * z - 1),
        0.25 * math.sqrt(7 / pi) * (5 * z ** 3 - 3 * z),
        0.25 * math.sqrt(21 / (2 * pi)) * x * (5 * z * z - 1),
        0.25 * math.sqrt(105 / pi) * (x * x - y * y) * z,
        0.25 * math.sqrt(35 / (2 * pi)) * (x * x - 3 * y * y) * x,
    ], axis=1)


def reference_sh(order, d):
    """y_lm from θ, φ: unnormalized P_l^m (no Condon-Shortley phase) by the
    textbook recurrence in cosθ, factorial normalization."""
    theta = np.arccos(np.clip(d[:, 2], -1, 1))
    phi = np.arctan2(d[:, 1], d[:, 0])
    ct, st = np.cos(theta), np.sin(theta)
    out = np.zeros((len(d), order * order))
    for m in range(order):
        p_mm = math.prod(range(1, 2 * m, 2)) * st ** m  # (2m-1)!! sin^m θ
        p = {m: p_mm}
        if m + 1 < order:
            p[m + 1] = (2 * m + 1) * ct * p_mm
        for l in range(m + 2, order):
            p[l] = ((2 * l - 1) * ct * p[l - 1] - (l + m - 1) * p[l - 2]) / (l - m)
        for l in range(m, order):
            k = math.sqrt((2 * l + 1) / (4 * math.pi) * math.factorial(l - m) / math.factorial(l + m))
            if m == 0:
                out[:, l * (l + 1)] = k * p[l]
            else:
                out[:, l * (l + 1) + m] = math.sqrt(2) * k * np.cos(m * phi) * p[l]
                out[:, l * (l + 1) - m] = math.sqrt(2) * k * np.sin(m * phi) * p[l]
    return out


def sphere_quadrature(n_theta, n_phi):
    mu, w = np.polynomial.legendre.leggauss(n_theta)
    phi = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    r = np.sqrt(1 - mu ** 2)
    d = np.stack([np.outer(r, np.cos(phi)), np.outer(r, np.sin(phi)), np.outer(mu, np.ones(n_phi))], axis=-1)
    return d.reshape(-1, 3), np.repeat(w * 2 * math.pi / n_phi, n_phi)


def test_sh_eval_matches_closed_forms_for_bands_0_to_3():
    d = random_directions(200)
    np.testing.assert_allclose(pen.sh.eval(4, d), closed_form_bands_0_to_3(d), atol=1e-14)


def test_sh_eval_matches_an_angle_based_recurrence_to_order_12():
    d = random_directions(100)
    np.testing.assert_allclose(pen.sh.eval(12, d), reference_sh(12, d), atol=1e-11)


def test_sh_eval_is_orthonormal_to_order_8_under_gauss_legendre():
    d, w = sphere_quadrature(8, 15)
    y = pen.sh.eval(8, d)
    np.testing.assert_allclose((y * w[:, None]).T @ y, np.eye(64), atol=1e-12)


def test_sh_eval_of_a_single_direction_is_flat_and_normalizes():
    y = pen.sh.eval(3, np.array([0.0, 0.0, 5.0]))
    assert y.shape == (9,)
    np.testing.assert_allclose(y, pen.sh.eval(3, [[0.0, 0.0, 1.0]])[0])


def test_sh_eval_at_the_poles_keeps_only_zonal_terms():
    y = pen.sh.eval(6, np.array([[0, 0, 1.0], [0, 0, -1.0], [1e-12, 0, 1.0]]))
    for l in range(6):
        zonal = math.sqrt((2 * l + 1) / (4 * math.pi))
        expected = np.zeros(2 * l + 1)
        expected[l] = zonal
        np.testing.assert_allclose(y[0, l * l:(l + 1) ** 2], expected, atol=1e-13)
        np.testing.assert_allclose(y[1, l * l:(l + 1) ** 2], expected * (-1) ** l, atol=1e-13)
        np.testing.assert_allclose(y[2, l * l:(l + 1) ** 2], expected, atol=1e-10)


@pytest.mark.parametrize("bad", [np.zeros((4, 2)), np.zeros((2, 3, 3)), np.zeros(4)])
def test_sh_eval_rejects_wrong_shapes(bad):
    with pytest.raises(ValueError, match="shape"):
        pen.sh.eval(3, bad)


def test_sh_eval_rejects_zero_directions_and_bad_orders():
    with pytest.raises(ValueError):
        pen.sh.eval(3, np.zeros((1, 3)))
    with pytest.raises(ValueError):
        pen.sh.eval(3, [[np.nan, 0, 1]])
    with pytest.raises(ValueError):
        pen.sh.eval(0, [[0, 0, 1]])
    with pytest.raises(ValueError):
        pen.sh.eval(pen.sh.MAX_ORDER + 1, [[0, 0, 1]])


def test_rotate_sh_turns_the_function_with_the_rotation():
    # g(ω) = f(Rᵀω): g(R d) must equal f(d).
    c = RNG.normal(size=(36, 3))
    r = random_rotation()
    d = random_directions(50)
    g = pen.sh.rotate(c, r)
    np.testing.assert_allclose(pen.sh.eval(6, d @ r.T) @ g, pen.sh.eval(6, d) @ c, atol=1e-11)
    assert pen.sh.rotate(c[:, 0], r).shape == (36,)
    with pytest.raises(ValueError):
        pen.sh.rotate(np.zeros(5), r)
    with pytest.raises(ValueError):
        pen.sh.rotate(c, np.eye(3)[:2])
    with pytest.raises(ValueError):
        pen.sh.rotate(c, -np.eye(3))  # a reflection


def test_zh_to_sh_equals_projecting_the_zonal_function():
    order = 6
    axes = random_directions(2)
    bands = RNG.normal(size=(2, order))
    d, w = sphere_quadrature(order + 1, 2 * order + 1)
    f = np.zeros(len(d))
    for axis, g in zip(axes, bands):
        mu = d @ axis
        for l in range(order):
            f += g[l] * math.sqrt((2 * l + 1) / (4 * math.pi)) * np.polynomial.legendre.Legendre.basis(l)(mu)
    direct = (pen.sh.eval(order, d) * (w * f)[:, None]).sum(axis=0)
    np.testing.assert_allclose(pen.sh.zh_to_sh(order, axes, bands), direct, atol=1e-12)
    rotated = pen.sh.rotate_zh(axes, np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]))
    np.testing.assert_allclose(rotated, np.stack([-axes[:, 1], axes[:, 0], axes[:, 2]], axis=1), atol=1e-15)
    with pytest.raises(ValueError, match="bands"):
        pen.sh.zh_to_sh(order, axes, bands[:, :3])


def test_project_points_with_exact_weights_recovers_coefficients():
    c = RNG.normal(size=16)
    d, w = sphere_quadrature(4, 7)
    values = reference_sh(4, d) @ c
    np.testing.assert_allclose(pen.sh.project_points(4, d, values, w), c, atol=1e-12)
    with pytest.raises(ValueError):
        pen.sh.project_points(4, d, values[:-1], w)
    with pytest.raises(ValueError):
        pen.sh.project_points(4, d, values, w[:-1])


def test_project_lights_is_irradiance_times_the_basis():
    d = random_directions(3)
    rgb = RNG.uniform(size=(3, 3))
    np.testing.assert_allclose(pen.sh.project_lights(5, d, rgb), reference_sh(5, d).T @ rgb, atol=1e-13)
    with pytest.raises(ValueError, match="rgb"):
        pen.sh.project_lights(5, d, rgb[:, :2])


def test_fibonacci_directions_are_unit_and_spread_evenly():
    d = pen.sh.fibonacci_directions(2000)
    assert d.shape == (2000, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-15)
    assert np.linalg.norm(d.mean(axis=0)) < 1e-3


def test_project_environment_of_a_constant_image_is_sqrt_4pi_times_it():
    image = np.empty((32, 64, 4), np.float32)
    image[...] = [0.5, 1.0, 2.0, 0.25]
    c = pen.sh.project_environment(4, image)
    assert c.shape == (16, 3)
    np.testing.assert_allclose(c[0], math.sqrt(4 * math.pi) * np.array([0.5, 1.0, 2.0]), rtol=1e-12)
    np.testing.assert_allclose(c[1:], 0.0, atol=1e-12)


def test_project_environment_puts_the_image_centre_at_plus_x_and_the_top_at_plus_z():
    centre = np.zeros((64, 128, 3), np.float32)
    centre[31:33, 63:65] = 1.0
    top = np.zeros((64, 128, 3), np.float32)
    top[0] = 1.0
    c, t = pen.sh.project_environment(2, centre), pen.sh.project_environment(2, top)
    assert c[3, 0] > 0 and abs(c[1, 0]) < 1e-12 * c[3, 0] and abs(c[2, 0]) < 1e-12 * c[3, 0]
    assert t[2, 0] > 0 and abs(t[1, 0]) < 1e-12 * t[2, 0] and abs(t[3, 0]) < 1e-12 * t[2, 0]


def test_project_environment_reports_non_finite_pixels_and_rejects_bad_shapes():
    image = np.ones((8, 16, 3), np.float32)
    image[2, 3, 1] = np.nan
    c, stats = pen.sh.project_environment(2, image, with_stats=True)
    assert stats["non_finite_pixels"] == 1 and np.isfinite(c).all()
    with pytest.raises(ValueError, match="shape"):
        pen.sh.project_environment(2, np.ones((8, 16)))
    with pytest.raises(ValueError, match="shape"):
        pen.sh.project_environment(2, np.ones((8, 16, 2)))
