"""The light-rig bindings: lights of synthetic maps against closed forms and
a numpy reference, bad input, sequences and videos made by
bench/helpers/test_videos.py."""

import math
import os
import subprocess

import numpy as np
import pytest

import _penumbra

from bench.helpers import test_videos as videos
from bench.helpers.median_cut import median_cut, median_cut_suns
from bench.helpers.metrics import rel_rmse

from conftest import BLENDER_OCIO  # noqa: E402


def numpy_irradiance(image, normals):
    """Independent reference: Σ L Ω max(0, n·ω) over pixel centres, in numpy."""
    h, w = image.shape[:2]
    d = videos.directions(h, w).reshape(-1, 3)
    flux = (image * videos.solid_angles(h, w)[:, None, None]).reshape(-1, 3)
    cos = np.clip(normals @ d.T, 0, None)
    return cos @ flux


def relative_irradiance_error(directions, rgb, normals, reference):
    return rel_rmse(_penumbra.lights.irradiance(directions, rgb, normals), reference)


def test_region_lights_are_within_1_2x_median_cut_irradiance_error_of_a_bundled_world():
    """Against a numpy reference over 300 normals, with Debevec's median cut
    (bench/helpers/median_cut.py) on the same map in the same test as the
    bar: Penumbra measures 0.5–0.7 %, the paper's method scores ~5 %, so a
    fixed 5 % could not catch a regression."""
    image = videos.load_world("forest", 256)
    normals = _penumbra.sh.fibonacci_directions(300)
    reference = numpy_irradiance(np.maximum(image, 0), normals)
    ours, baseline = {}, {}
    for n in (16, 64, 256):
        lights = _penumbra.lights.frame_lights(image, count=n, fit_irradiance=False)
        ours[n] = relative_irradiance_error(lights["directions"], lights["rgb"], normals, reference)
        baseline[n] = relative_irradiance_error(*median_cut(np.maximum(image, 0), n), normals, reference)
    assert ours[256] < ours[16]
    assert ours[64] <= 1.2 * baseline[64], (ours, baseline)


@pytest.mark.parametrize("sun_model", ["BLENDER3_DISC", "BLENDER4_CONE"])
def test_the_fitted_rig_has_at_most_half_median_cuts_irradiance_error_drawn_as_suns(sun_model):
    """Issue #14 goal 1 on its hardest case: sunrise.exr at 16 lights, where
    median cut puts four suns on the sun. Both rigs drawn as this Blender
    draws suns (each with its region's or rectangle's angle), against a
    numpy reference over 300 normals. The fit that kept the regions' angles
    and moved lights at most one spread scored 1.6× (3.4) and 1.4× (4.x);
    now about 0.1×."""
    image = np.maximum(videos.load_world("sunrise", 256), 0)
    normals = _penumbra.sh.fibonacci_directions(300)
    reference = numpy_irradiance(image, normals)

    def error(d, rgb, spread):
        return rel_rmse(_penumbra.lights.irradiance(d, rgb, normals, spread=spread, sun_model=sun_model), reference)

    fitted = _penumbra.lights.frame_lights(image, count=16, fit_irradiance=True, sun_model=sun_model)
    np.testing.assert_allclose(fitted["rgb"].sum(axis=0), fitted["total_rgb"], rtol=1e-12)
    ours = error(fitted["directions"], fitted["rgb"], fitted["spread"])
    baseline = error(*median_cut_suns(image, 16))
    assert ours <= 0.5 * baseline, (ours, baseline)


def test_exact_irradiance_binding_agrees_with_numpy():
    image = videos.sun_disc(64, 128, (0.3, 0.2, 0.9), 0.2, 50.0, sky_radiance=0.5)
    normals = _penumbra.sh.fibonacci_directions(40)
    ours = _penumbra.lights.exact_irradiance(image, normals)
    np.testing.assert_allclose(ours, numpy_irradiance(image, normals), rtol=1e-6, atol=1e-9)


def test_uniform_sky_gives_pi_times_radiance():
    lights = _penumbra.lights.frame_lights(videos.sky(64, 128, 2.0), count=128)
    np.testing.assert_allclose(lights["rgb"].sum(axis=0), 4 * math.pi * 2.0, rtol=1e-6)
    e = _penumbra.lights.irradiance(lights["directions"], lights["rgb"], _penumbra.sh.fibonacci_directions(100))
    assert abs(e[:, 0].mean() / (2 * math.pi) - 1) < 0.02


def test_sun_angle_and_strength_per_flux_work_on_arrays_of_any_shape():
    """The bindings the add-on writes its suns with (rig_objects.py), against
    the rule in closed form (docs/lights.md "Suns in Cycles")."""
    L = _penumbra.lights
    spread = np.array([[0.0, 1.6e-16, -1.0], [0.1, 0.5, 4.0]])
    angle = L.sun_angle(spread)
    assert angle.shape == spread.shape
    np.testing.assert_array_equal(angle[0], 0.0)
    np.testing.assert_allclose(angle[1], [0.2 * math.sqrt(2.0), math.sqrt(2.0), math.pi], rtol=1e-15)
    assert float(L.sun_angle(0.1)) == pytest.approx(0.2 * math.sqrt(2.0))
    assert 0.0 < L.MIN_SUN_ANGLE < 1e-4  # far below a pixel of any map, far above where Cycles drops a sun
    np.testing.assert_allclose(L.sun_strength_per_flux(angle, "BLENDER4_CONE"), 0.5 * (1.0 + np.cos(angle / 2)))
    for model in (L.SunModel.BLENDER3_DISC, "POINT"):
        np.testing.assert_array_equal(L.sun_strength_per_flux(angle, model), np.ones_like(angle))
    assert [L.sun_model_for_blender(*v).name for v in ((3, 4), (3, 6), (4, 0), (4, 5), (5, 2))] == \
        ["BLENDER3_DISC"] * 2 + ["BLENDER4_CONE"] * 3


def test_bad_input_is_a_clear_error():
    good = videos.sky(8, 16)
    with pytest.raises(ValueError, match="at least 1"):
        _penumbra.lights.frame_lights(good, count=0)
    with pytest.raises(ValueError, match="exceeds"):
        _penumbra.lights.frame_lights(good, count=8 * 16 + 1)
    with pytest.raises(ValueError, match="empty"):
        _penumbra.lights.frame_lights(np.zeros((0, 16, 3), np.float32))
    with pytest.raises(ValueError, match="mapping"):
        _penumbra.lights.frame_lights(good, mapping="cube")
    with pytest.raises(ValueError, match="sampler"):
        _penumbra.lights.frame_lights(good, sampler="median_cut")
    for channels in (1, 2, 4):
        lights = _penumbra.lights.frame_lights(np.ones((8, 16, channels), np.float32), count=4)
        assert np.isfinite(lights["rgb"]).all() and lights["total_power"] > 0
    bad = good.copy()
    bad[0, 0, 0] = np.nan
    bad[1, 1, 1] = np.inf
    bad[2, 2, 2] = -1
    lights = _penumbra.lights.frame_lights(bad, count=4)
    assert lights["defects"] == {"nan": 1, "inf": 1, "negative": 1}
    assert np.isfinite(lights["rgb"]).all()
    black = _penumbra.lights.frame_lights(np.zeros((8, 16, 3), np.float32), count=4)
    assert black["total_power"] == 0 and np.isfinite(black["directions"]).all()


def test_sequence_rig_conserves_energy_and_tracks_lights(tmp_path):
    frames = videos.rotation_frames(videos.sun_disc(64, 128, (1, 0, 0.5), 0.1, 100.0, 0.2), 12, 3.0)
    first = videos.write_sequence(str(tmp_path / "seq"), frames)
    source = _penumbra.lights.open_source(first)
    assert source.frame_count == 12
    builder = _penumbra.lights.RigBuilder(count=16, frames_per_second=21)
    for i in range(source.frame_count):
        builder.add_frame_from(source, i)
    rig = builder.finish()
    assert rig["directions"].shape == (12, 16, 3)
    # Energy: every frame's lights sum to the (constant) map integral.
    total = (frames[0] * videos.solid_angles(64, 128)[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(rig["rgb"].sum(axis=1), np.tile(total, (12, 1)), rtol=1e-4)
    # The sun turns 3° per frame; the power-weighted direction of the lights
    # near it follows (the sun's energy may be split between a few lights).
    sun = np.array([1, 0, 0.5]) / np.linalg.norm([1, 0, 0.5])
    azimuth = []
    for t in range(12):
        a = math.radians(3.0 * t)
        s_t = np.array([sun[0] * math.cos(a), sun[0] * math.sin(a), sun[2]])
        near = rig["directions"][t] @ s_t > math.cos(0.4)
        m = (rig["power"][t][near, None] * rig["directions"][t][near]).sum(axis=0)
        azimuth.append(math.degrees(math.atan2(m[1], m[0])))
    steps = np.diff(np.unwrap(np.radians(azimuth)))
    assert np.all(np.abs(np.degrees(steps)[2:-2] - 3.0) < 0.6), np.degrees(steps)


def test_sequence_with_a_gap_or_a_size_change_is_an_io_error(tmp_path):
    frames = [videos.sky(8, 16)] * 3
    first = videos.write_sequence(str(tmp_path / "gap"), frames)
    os.remove(str(tmp_path / "gap" / "frame_0002.exr"))
    with pytest.raises(OSError, match="missing frames"):
        _penumbra.lights.open_source(first)
    first = videos.write_sequence(str(tmp_path / "size"), [videos.sky(8, 16), videos.sky(16, 32)])
    source = _penumbra.lights.open_source(first)
    builder = _penumbra.lights.RigBuilder(count=4)
    builder.add_frame_from(source, 0)
    with pytest.raises(OSError, match="same size"):
        builder.add_frame_from(source, 1)


def test_video_is_read_through_a_display_colour_space(tmp_path):
    frames = videos.rotation_frames(videos.sun_disc(32, 64, (1, 0, 0.3), 0.2, 3.0, 0.01), 6, 5.0)
    path = videos.write_video(str(tmp_path / "rot.mov"), frames, fps=24)
    source = _penumbra.lights.open_source(path)
    assert source.frame_count == 6 and abs(source.frames_per_second - 24) < 0.01
    config = _penumbra.color.Config(BLENDER_OCIO)
    builder = _penumbra.lights.RigBuilder(count=8)
    for i in range(6):
        builder.add_frame_from(source, i, config, "sRGB")
    rig = builder.finish(source.frames_per_second)
    # The video holds x/(1+x) in sRGB: the sun (3.0) comes back as 0.75, and
    # the lights' total is the integral of the compressed map.
    compressed = frames[0] / (1 + frames[0])
    total = (compressed * videos.solid_angles(32, 64)[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(rig["rgb"][0].sum(axis=0), total, rtol=0.03)
    sun = np.array([1, 0, 0.3]) / np.linalg.norm([1, 0, 0.3])
    near = rig["directions"][0] @ sun > math.cos(0.5)
    sun_energy = 0.75 * 2 * math.pi * (1 - math.cos(0.2))
    assert rig["rgb"][0][near, 0].sum() > 0.8 * sun_energy
    with pytest.raises(Exception, match="colour space|color space|Nonexistent|not found|unknown"):
        builder.add_frame_from(source, 0, config, "No Such Space")


def test_truncated_video_is_an_io_error(tmp_path):
    path = videos.write_video(str(tmp_path / "v.mov"), [videos.sky(16, 32)] * 4)
    data = open(path, "rb").read()
    with open(tmp_path / "cut.mov", "wb") as f:
        f.write(data[: len(data) // 3])
    with pytest.raises(OSError):
        source = _penumbra.lights.open_source(str(tmp_path / "cut.mov"))
        for i in range(source.frame_count):
            source.read(i)


def test_clustering_and_region_tables_through_the_bindings():
    lights = _penumbra.lights.frame_lights(videos.load_world("courtyard", 256), count=200, fit_irradiance=False)
    c = _penumbra.lights.cluster(lights["directions"], lights["rgb"], max_clusters=20)
    assert len(c["index"]) <= 20
    np.testing.assert_allclose(c["rgb"].sum(axis=0), lights["rgb"].sum(axis=0), rtol=1e-9)
    table = _penumbra.testing.light_region_table(lights["directions"], 6)
    assert len(table["offsets"]) == 217
    normals = _penumbra.sh.fibonacci_directions(50)
    regions = _penumbra.testing.light_region_of(normals, 6)
    for n, r in zip(normals, regions):
        members = set(table["lights"][table["offsets"][r]:table["offsets"][r + 1]])
        visible = set(np.nonzero(lights["directions"] @ n > 0)[0].tolist())
        assert visible <= members


def test_filter_taps_match_the_paper_at_21_hz():
    taps = np.array(_penumbra.lights.temporal_filter(21.0))
    paper = np.array([0.06216, 0.01296, -0.13816, 0.28315, 0.65223, 0.28315, -0.13816, 0.01296, 0.06216])
    np.testing.assert_allclose(taps, paper / paper.sum(), atol=1e-12)
    assert abs(np.sum(_penumbra.lights.temporal_filter(60.0)) - 1) < 1e-12


def _steps_after_the_turn(rig, degrees_per_frame):
    """Flux-weighted mean and largest step of the lights between frames once
    the map's own turn about +z is removed (degrees)."""
    a = math.radians(degrees_per_frame)
    turn = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    d, p = rig["directions"], rig["power"]
    angles, weights = [], []
    for t in range(1, len(d)):
        cos = np.clip(np.sum((d[t - 1] @ turn.T) * d[t], axis=1), -1, 1)
        angles.append(np.degrees(np.arccos(cos)))
        weights.append(p[t - 1] / p[t - 1].sum() + p[t] / p[t].sum())
    angles, weights = np.concatenate(angles), np.concatenate(weights)
    return float((angles * weights).sum() / weights.sum()), float(angles.max())


def test_followed_lights_turn_with_the_map_and_resampled_ones_wander():
    """RigBuilder's tracking (core/lights/tracking.hpp) through the binding:
    courtyard.exr turning 2° per frame. Followed lights (the default) move
    with the map; resampled ones (the paper's, and this tool's before issue
    #14) wander. Measured: 0.06° / 0.3° (mean / largest), against 4.9° / 70°."""
    frames = videos.rotation_frames(np.maximum(videos.load_world("courtyard", 128), 0), 8, 2.0)
    rigs = {}
    for tracking in ("FOLLOW", "RESAMPLE"):
        builder = _penumbra.lights.RigBuilder(count=16, frames_per_second=24, tracking=tracking)
        for f in frames:
            builder.add_frame(f)
        rigs[tracking] = _steps_after_the_turn(builder.finish(), 2.0)
    assert rigs["FOLLOW"][0] < 0.2 and rigs["FOLLOW"][1] < 0.6, rigs
    assert rigs["RESAMPLE"][0] > 0.5 and rigs["RESAMPLE"][1] > 5.0, rigs


def test_each_frame_keeps_its_own_brightness_unless_asked_to_filter_it():
    """±10% exposure noise on a still map: by default every frame's lights sum
    to that frame's own ∫L dω; filter_brightness low-passes the totals (the
    paper's), so they come out smoother than the frames'."""
    base = videos.sun_disc(32, 64, (0.3, 0.2, 0.9), 0.2, 50.0, sky_radiance=0.5)
    rng = np.random.default_rng(3)
    factors = rng.uniform(0.9, 1.1, 12)
    frames = [(base * f).astype(np.float32) for f in factors]
    own = np.array([(f * videos.solid_angles(32, 64)[:, None, None]).sum(axis=(0, 1)) for f in frames])
    totals = {}
    for smooth in (False, True):
        builder = _penumbra.lights.RigBuilder(count=8, frames_per_second=24, filter_brightness=smooth)
        for f in frames:
            builder.add_frame(f)
        totals[smooth] = builder.finish()["rgb"].sum(axis=1)
    np.testing.assert_allclose(totals[False], own, rtol=1e-9)
    assert np.std(np.diff(totals[True][:, 1])) < 0.5 * np.std(np.diff(own[:, 1]))
