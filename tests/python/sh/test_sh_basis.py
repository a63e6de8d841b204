"""The contract of the `_penumbra.sh` bindings: shapes, dtypes, accepted
inputs and errors. The maths (closed forms, recurrences, orthonormality,
rotation, projection, the latlong convention) is tested once, in C++:
tests/cpp/sh/. A single value per function is checked here only so that a
binding wired to the wrong arguments cannot pass."""

import math

import numpy as np
import pytest

import _penumbra as pen


def test_sh_eval_gives_float64_rows_of_order_squared_and_takes_lists_or_one_direction():
    y = pen.sh.eval(3, [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    assert y.shape == (2, 9) and y.dtype == np.float64
    assert y[0, 0] == pytest.approx(1 / math.sqrt(4 * math.pi))
    flat = pen.sh.eval(3, np.array([0.0, 0.0, 5.0], np.float32))
    assert flat.shape == (9,)
    np.testing.assert_allclose(flat, y[0])


@pytest.mark.parametrize("bad", [np.zeros((4, 2)), np.zeros((2, 3, 3)), np.zeros(4)])
def test_sh_eval_rejects_wrong_shapes(bad):
    with pytest.raises(ValueError, match="shape"):
        pen.sh.eval(3, bad)


@pytest.mark.parametrize("order, direction", [(3, [0, 0, 0]), (3, [math.nan, 0, 1]), (0, [0, 0, 1]),
                                              (pen.sh.MAX_ORDER + 1, [0, 0, 1])])
def test_sh_eval_rejects_zero_or_non_finite_directions_and_bad_orders(order, direction):
    with pytest.raises(ValueError):
        pen.sh.eval(order, [direction])


def test_rotate_keeps_the_coefficient_shape_and_refuses_non_rotations():
    c = np.arange(36 * 3, dtype=float).reshape(36, 3)
    assert pen.sh.rotate(c, np.eye(3)).shape == (36, 3)
    np.testing.assert_allclose(pen.sh.rotate(c[:, 0], np.eye(3)), c[:, 0])
    for coefficients, rotation in [(np.zeros(5), np.eye(3)), (c, np.eye(3)[:2]), (c, -np.eye(3))]:
        with pytest.raises(ValueError):
            pen.sh.rotate(coefficients, rotation)


def test_zh_to_sh_and_rotate_zh_shapes_and_errors():
    axes, bands = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), np.ones((2, 4))
    assert pen.sh.zh_to_sh(4, axes, bands).shape == (16,)
    quarter = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    np.testing.assert_allclose(pen.sh.rotate_zh(axes, quarter), [[0, 0, 1], [0, 1, 0]], atol=1e-15)
    with pytest.raises(ValueError, match="bands"):
        pen.sh.zh_to_sh(4, axes, bands[:, :3])


def test_projections_return_coefficients_and_check_lengths():
    d = pen.sh.fibonacci_directions(50)
    assert d.shape == (50, 3) and d.dtype == np.float64
    values, weights = np.ones(50), np.full(50, 4 * math.pi / 50)
    c = pen.sh.project_points(4, d, values, weights)
    assert c.shape == (16,) and c[0] == pytest.approx(math.sqrt(4 * math.pi), rel=1e-9)
    with pytest.raises(ValueError):
        pen.sh.project_points(4, d, values[:-1], weights)
    with pytest.raises(ValueError):
        pen.sh.project_points(4, d, values, weights[:-1])
    assert pen.sh.project_lights(5, d[:3], np.ones((3, 3))).shape == (25, 3)
    with pytest.raises(ValueError, match="rgb"):
        pen.sh.project_lights(5, d[:3], np.ones((3, 2)))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_project_environment_takes_rgb_or_rgba_and_reports_non_finite_pixels(dtype):
    image = np.ones((8, 16, 4), dtype)
    image[2, 3, 1] = np.nan
    c, stats = pen.sh.project_environment(2, image, with_stats=True)
    assert c.shape == (4, 3) and c.dtype == np.float64 and np.isfinite(c).all()
    assert stats["non_finite_pixels"] == 1
    assert pen.sh.project_environment(2, image[..., :3]).shape == (4, 3)
    for bad in (np.ones((8, 16), dtype), np.ones((8, 16, 2), dtype)):
        with pytest.raises(ValueError, match="shape"):
            pen.sh.project_environment(2, bad)
