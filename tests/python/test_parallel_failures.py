"""A failure on a worker thread of any tool's parallel stage reaches Python as
an exception (MemoryError for std::bad_alloc), and the process lives on and
runs the same operation again to the same result. The failure is injected
through _penumbra.testing; the core's one parallel helper (common/parallel.hpp)
carries it to the caller."""

import threading
import time

import numpy as np
import pytest

import _penumbra as p
from visibility_sphere_scenes import bake, two_sphere_character

from bench.helpers import test_videos as videos


def lights_region_powers():
    return p.lights.frame_lights(videos.sky(64, 128, 2.0), count=64)["rgb"]


def colormap_lookup():
    colors = np.array([[0, 0, 0, 1], [1, 0.5, 0.2, 1]], np.float32)
    return p.colormap.lut(colors, 256, 64, 0.3, -0.25, 1.25)


def pose_shading():
    rng = np.random.default_rng(3)
    n = 6000  # three blocks of the shader: a worker gets one
    axes = rng.normal(size=(n, 2, 3))
    axes /= np.linalg.norm(axes, axis=2, keepdims=True)
    bands = rng.uniform(0, 1, size=(n, 2, 3))
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    tangents = np.tile([1.0, 0.0, 0.0], (n, 1))
    lighting = rng.normal(size=(9, 3))
    return p.sh.shade_pose(3, lighting, axes, bands, normals, tangents)[0]


def visibility_bake():
    return bake([0.0, 0.5], rays=32).visibility(1)


def visibility_fit_and_shade():
    ts = bake([0.0, 0.4, 0.8], rays=32)
    model, _ = p.visibility.fit_model(ts, [(True, True), (True, False)], lobes=1)
    positions, normals, tris, _ = two_sphere_character()
    neighbours = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    rotations = np.stack([np.eye(3, dtype=np.float32)] * len(model.joints))
    return model.shade(rotations, positions, normals, tris, neighbours, np.eye(16, 3))[0]


CASES = [
    ("lights.region_powers", lights_region_powers),
    ("colormap.lookup", colormap_lookup),
    ("sh.pose_shading", pose_shading),
    ("visibility.bake", visibility_bake),
    ("visibility.zh_fit", visibility_fit_and_shade),
    ("visibility.pose_lobes", visibility_fit_and_shade),
]


@pytest.mark.parametrize("kind, error", [("runtime_error", RuntimeError), ("bad_alloc", MemoryError)])
@pytest.mark.parametrize("stage, run", CASES, ids=[c[0] for c in CASES])
def test_a_worker_failure_becomes_a_python_exception_and_the_operation_runs_again(stage, run, kind, error):
    expected = run()
    p.testing.inject_worker_failure(stage, kind)
    try:
        with pytest.raises(error):
            run()
    finally:
        p.testing.inject_worker_failure(stage, "none")
    np.testing.assert_array_equal(run(), expected)


def test_cancel_from_python_stops_the_workers_within_100_ms():
    started = time.perf_counter()
    cancelled_at = []

    def progress(fraction):
        if time.perf_counter() - started < 0.03:
            return True
        cancelled_at.append(time.perf_counter())
        return False
    with pytest.raises(p.Cancelled):
        p.testing.parallel_probe(64, block_seconds=20.0, progress=progress)
    assert cancelled_at and time.perf_counter() - cancelled_at[0] < 0.1


def test_progress_comes_from_the_calling_thread():
    threads = set()
    p.testing.parallel_probe(200, block_seconds=0.002,
                             progress=lambda f: threads.add(threading.get_ident()) or True)
    assert threads == {threading.get_ident()}
