"""The contract of `_penumbra.sh.shade_pose`: shapes and dtypes in and out,
the caller's arrays left alone, invalid vertices, errors, and the GIL
released while it shades. The shading itself (closed forms, brute-force
hemisphere quadrature, energy conservation, rotation invariance, thread
counts) is tested in C++: tests/cpp/sh/pose_shading_test.cpp."""

import math
import threading
import time

import numpy as np
import pytest

import _penumbra

FOUR_PI = 4.0 * math.pi


def random_directions(rng, n):
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def random_pose(rng, n, lobes, order):
    return dict(
        lobe_axes=rng.normal(size=(n, lobes, 3)),
        lobe_bands=rng.uniform(-1, 1, size=(n, lobes, order)),
        normals=random_directions(rng, n) * rng.uniform(0.5, 2.0, size=(n, 1)),
        tangents=rng.normal(size=(n, 3)),
        positions=rng.uniform(-1, 1, size=(n, 3)),
    )


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
@pytest.mark.parametrize("brdf", ["diffuse", "phong", "translucent"])
def test_takes_float32_or_float64_and_returns_float32_rgb_and_visibility(dtype, brdf):
    # Fully visible under unit radiance: 1 for every BRDF's reflection, which
    # a binding that mixed up its arguments would not give.
    rng = np.random.default_rng(1)
    pose = fully_visible(rng, 20, 4, dtype)
    extra = dict(exponent=7.0, positions=pose["positions"], camera=(0.0, 0.0, 3.0)) if brdf == "phong" else {}
    if brdf == "translucent":
        extra = dict(transmission=(0.0, 0.0, 0.0))
    rgb, stats = shade(4, unit_radiance(4).astype(dtype), pose, brdf=brdf, with_stats=True, **extra)
    assert rgb.shape == (20, 3) and rgb.dtype == np.float32
    assert stats["visibility"].shape == (20,) and stats["visibility"].dtype == np.float32
    np.testing.assert_allclose(rgb, 1.0, atol=2e-3 if brdf == "phong" else 1e-5)


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


def test_the_gil_is_released_while_it_shades():
    rng = np.random.default_rng(11)
    pose = random_pose(rng, 200_000, 4, 8)
    lighting = rng.normal(size=(64, 3))
    ticks, done = 0, threading.Event()
    worker = threading.Thread(target=lambda: (shade(8, lighting, pose, threads=1), done.set()))
    started = time.perf_counter()
    worker.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    seconds = time.perf_counter() - started
    # Holding the GIL, the call would leave this loop one or two ticks; with
    # it released the loop ticks about once a millisecond (~350 here).
    assert seconds > 0.05, "too little work to tell"
    assert ticks >= 10, (ticks, seconds)
