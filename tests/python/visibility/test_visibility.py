"""The visibility baker through _penumbra: shapes and errors at the Python
boundary, files, progress/cancel, and a bake of two spheres checked against a
closed form (a lone convex sphere sees exactly its upper hemisphere)."""

import numpy as np
import pytest

import _penumbra as p
from visibility_sphere_scenes import bake, rot_z, two_sphere_character


def test_far_side_of_the_body_sees_its_whole_upper_hemisphere():
    ts = bake([0.0])
    ao = p.visibility.ambient_occlusion(ts.visibility(0).astype(np.float64))
    positions, _, _, n_body = two_sphere_character()
    far = np.where(positions[:n_body, 0] < -0.9)[0]
    near = np.where((positions[:n_body, 0] > 0.95))[0]
    np.testing.assert_allclose(ao[far], 1.0, atol=0.02)
    assert ao[near].mean() < 0.9  # the arm shadows the side facing it


def test_fit_save_load_and_synthesize_round_trip(tmp_path):
    ts = bake(np.linspace(0.0, np.pi / 2, 12))
    model, report = p.visibility.fit_model(ts, [(True, True), (True, False)], lobes=2)
    assert [j["active"] for j in report["joints"]] == [False, True]
    assert report["holdout_frames"] == 3
    path = str(tmp_path / "m.pzh")
    model.save(path)
    loaded = p.visibility.PoseModel.load(path)
    assert loaded.joints == ["arm"] and loaded.vertex_count == ts.vertex_count
    axes, bands, params = loaded.synthesize(np.stack([rot_z(0.3)]))
    assert axes.shape == (ts.vertex_count, 2, 3) and bands.shape == (ts.vertex_count, 2, 4)
    np.testing.assert_allclose(np.linalg.norm(axes, axis=2), 1.0, atol=1e-5)
    sh = p.visibility.zh_params_to_sh(params.astype(np.float64))
    assert sh.shape == (ts.vertex_count, 16)
    unseen = bake([0.05, 0.7, 1.2])
    errors = loaded.evaluate(unseen)
    assert errors["samples"] == 3 * ts.vertex_count
    assert errors["ao_mean_abs"] < 0.05


def test_training_set_pieces_save_load_and_merge(tmp_path):
    a, b = bake([0.0, 0.2]), bake([0.4])
    a.save(str(tmp_path / "a.pvis"))
    b.save(str(tmp_path / "b.pvis"))
    merged = p.visibility.TrainingSet.merge([p.visibility.TrainingSet.load(str(tmp_path / "b.pvis")),
                                            p.visibility.TrainingSet.load(str(tmp_path / "a.pvis"))])
    # Frame 0 is in both pieces: kept once, from the first piece given (b).
    assert merged.frame_numbers == [0.0, 1.0]
    np.testing.assert_array_equal(merged.visibility(0), b.visibility(0))
    np.testing.assert_array_equal(merged.visibility(1), a.visibility(1))


def test_bad_files_are_os_errors(tmp_path):
    with pytest.raises(OSError, match="no such file"):
        p.visibility.PoseModel.load(str(tmp_path / "missing.pzh"))
    (tmp_path / "junk.pzh").write_bytes(b"x" * 100)
    with pytest.raises(p.IoError, match="magic"):
        p.visibility.PoseModel.load(str(tmp_path / "junk.pzh"))
    ts = bake([0.0])
    ts.save(str(tmp_path / "s.pvis"))
    with pytest.raises(OSError, match="other kind"):
        p.visibility.PoseModel.load(str(tmp_path / "s.pvis"))


def test_bad_shapes_are_value_errors():
    positions, normals, tris, _ = two_sphere_character()
    ts = p.visibility.TrainingSet(len(positions), 0, ["a"], rays=16)
    nb = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    with pytest.raises(ValueError, match="positions"):
        ts.bake_frame(0, positions[:, :2], normals, tris, nb, np.eye(3, dtype=np.float32)[None])
    with pytest.raises(ValueError, match="expected 1 rotations"):
        ts.bake_frame(0, positions, normals, tris, nb, np.stack([np.eye(3)] * 2))
    with pytest.raises(ValueError, match="vertices"):
        ts.bake_frame(0, positions[:10], normals[:10], tris[:2], nb[:10], np.eye(3)[None])
    with pytest.raises(ValueError, match="below_horizon"):
        p.visibility.TrainingSet(3, 0, [], below_horizon="sometimes")
    with pytest.raises(ValueError, match="rays"):
        p.visibility.TrainingSet(3, 0, [], rays=1)


def test_the_visibility_order_limit_is_the_bake_settings_and_every_bindings():
    limit = p.visibility.MAX_ORDER
    assert limit < p.sh.MAX_ORDER  # the SH engine's own limit is another (core/visibility/order_limit.hpp)
    assert p.settings_spec()["visibility.sh_order"]["max"] == limit
    p.visibility.TrainingSet(3, 0, [], order=limit)
    with pytest.raises(ValueError, match="SH order"):
        p.visibility.TrainingSet(3, 0, [], order=limit + 1)
    within, beyond = np.zeros((1, limit ** 2)), np.zeros((1, (limit + 1) ** 2))
    assert p.visibility.ambient_occlusion(within).shape == (1,)
    for call in (p.visibility.ambient_occlusion, p.visibility.fit_zh_lobes):
        with pytest.raises(ValueError, match=rf"{limit ** 2}\), got {(limit + 1) ** 2}"):
            call(beyond)
    assert p.visibility.zh_params_to_sh(np.zeros((1, 1, 2 + limit))).shape == (1, limit ** 2)
    with pytest.raises(ValueError, match=f"order 1..{limit}"):
        p.visibility.zh_params_to_sh(np.zeros((1, 1, 3 + limit)))


def test_progress_false_cancels_and_keeps_the_set_unchanged():
    positions, normals, tris, _ = two_sphere_character()
    nb = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    ts = p.visibility.TrainingSet(len(positions), 0, ["a"], rays=65536)
    with pytest.raises(p.Cancelled):
        ts.bake_frame(0, positions, normals, tris, nb, np.eye(3)[None], progress=lambda f: False)
    assert len(ts) == 0
    with pytest.raises(ZeroDivisionError):
        ts.bake_frame(0, positions, normals, tris, nb, np.eye(3)[None], progress=lambda f: 1 / 0)
    assert len(ts) == 0


def test_scene_builds_give_the_same_visibility_and_a_bad_name_is_a_value_error():
    positions, normals, tris, n_body = two_sphere_character()
    neighbours = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    results = {}
    for build in ("high", "medium", "low", "refit"):
        ts = p.visibility.TrainingSet(len(positions), 0, ["root", "arm"], rays=64)
        stats = []
        for i, angle in enumerate((0.0, 0.4, 0.8)):  # the arm moves: the kept scene is updated
            r = rot_z(angle)
            posed = positions.copy()
            posed[n_body:] = positions[n_body:] @ r.T
            posed_normals = normals.copy()
            posed_normals[n_body:] = normals[n_body:] @ r.T
            stats.append(ts.bake_frame(i, posed, posed_normals, tris, neighbours,
                                       np.stack([np.eye(3, dtype=np.float32), r]), scene_build=build))
        assert [s["scene_updated"] for s in stats] == [False, True, True]
        assert all(s["seconds_cast"] > 0 for s in stats)
        results[build] = [ts.visibility(i) for i in range(3)]
    for build in ("medium", "low", "refit"):
        for a, b in zip(results["high"], results[build]):
            np.testing.assert_array_equal(a, b)
    p.visibility.release_bake_cache()
    ts = p.visibility.TrainingSet(len(positions), 0, ["root", "arm"], rays=64)
    with pytest.raises(ValueError, match="scene_build"):
        ts.bake_frame(0, positions, normals, tris, neighbours, np.stack([np.eye(3, dtype=np.float32)] * 2),
                      scene_build="fast")


def test_shading_from_many_threads_at_once_equals_one_at_a_time():
    # The shader of an order is shared by every call (and keeps its Phong
    # operators); concurrent calls with different BRDFs must not disturb each other.
    import threading
    ts = bake(np.linspace(0.0, np.pi / 2, 8))
    model, _ = p.visibility.fit_model(ts, [(True, True), (True, False)], lobes=2)
    positions, normals, tris, n_body = two_sphere_character()
    neighbours = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    rng = np.random.default_rng(1)
    lighting = rng.normal(size=(16, 3))
    lighting[0] += 5.0
    calls = [dict(model="diffuse"), dict(model="phong", phong_exponent=8.0), dict(model="phong", phong_exponent=40.0),
             dict(model="translucent", transmission=np.array([0.5, 0.2, 0.1]))]

    def shade(kwargs):
        return model.shade(np.stack([rot_z(0.3)]), positions, normals, tris, neighbours, lighting,
                           camera=np.array([0.0, -5.0, 1.0]), **kwargs)[0]
    expected = [shade(c) for c in calls]
    assert not np.allclose(expected[1], expected[2])  # the exponents do differ
    got = [None] * (3 * len(calls))

    def worker(k):
        got[k] = shade(calls[k % len(calls)])
    threads = [threading.Thread(target=worker, args=(k,)) for k in range(len(got))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, result in enumerate(got):
        np.testing.assert_array_equal(result, expected[k % len(calls)])
