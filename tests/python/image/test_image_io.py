"""Image I/O through _penumbra: numpy in and out, Python exceptions out."""

import os

import numpy as np
import pytest

import _penumbra
from conftest import BLENDER_WORLDS


def test_exr_round_trip_float32_exact(tmp_path):
    rng = np.random.default_rng(1)
    pixels = rng.random((9, 13, 3), dtype=np.float32) * 1000
    path = str(tmp_path / "a.exr")
    _penumbra.image.write_exr(path, pixels, half=False, colorspace="Linear")
    back = _penumbra.image.read(path)
    assert back.dtype == np.float32 and back.shape == (9, 13, 3)
    np.testing.assert_array_equal(back, pixels)
    assert _penumbra.image.read_info(path)["colorspace"] == "Linear"


def test_row_zero_is_the_top_of_the_file(tmp_path):
    pixels = np.zeros((4, 2, 3), np.float32)
    pixels[0] = 1.0  # top row white
    path = str(tmp_path / "top.png")
    _penumbra.image.write_png16(path, pixels, colorspace="sRGB")
    back = _penumbra.image.read(path)
    assert back[0].min() == 1.0 and back[3].max() == 0.0


def test_eight_orders_of_magnitude_survive_a_float_exr(tmp_path):
    pixels = np.ones((2, 4, 3), np.float32)
    pixels[0, :, :] = np.array([1e-4, 1e-1, 1e2, 1e4], np.float32)[:, None]
    pixels[1, :, :] = 1e-4
    path = str(tmp_path / "hdr.exr")
    _penumbra.image.write_exr(path, pixels, half=False)
    np.testing.assert_array_equal(_penumbra.image.read(path), pixels)


def test_blender_bundled_hdri_reads_as_finite_rgb_with_its_few_negative_pixels():
    path = os.path.join(BLENDER_WORLDS, "forest.exr")
    image = _penumbra.image.read(path)
    assert image.ndim == 3 and image.shape[2] == 3
    assert image.shape[1] == 2 * image.shape[0]  # equirectangular
    assert np.isfinite(image).all() and image.max() > 1
    # Real captures hold slightly negative values (forest.exr: about -0.0016);
    # readers keep them, sanitize counts and clamps them.
    _, counts = _penumbra.image.sanitize(image)
    assert counts["negative"] == int((image < 0).sum()) > 0
    assert image.min() > -0.01


def test_grey_input_array_is_written_as_one_channel(tmp_path):
    path = str(tmp_path / "grey.exr")
    _penumbra.image.write_exr(path, np.full((3, 5), 0.25, np.float32))
    assert _penumbra.image.read_info(path)["channels"] == 1
    assert (_penumbra.image.read(path) == 0.25).all()


def test_missing_file_raises_oserror_naming_the_file(tmp_path):
    with pytest.raises(OSError, match="nope.exr"):
        _penumbra.image.read(str(tmp_path / "nope.exr"))


def test_truncated_file_raises_ioerror(tmp_path):
    path = tmp_path / "full.exr"
    noise = np.random.default_rng(2).random((64, 64, 3), dtype=np.float32)  # incompressible
    _penumbra.image.write_exr(str(path), noise, half=False)
    data = path.read_bytes()
    cut = tmp_path / "cut.exr"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(_penumbra.IoError):
        _penumbra.image.read(str(cut))


@pytest.mark.parametrize("shape", [(0, 4, 3), (4, 0, 3), (4, 4, 5), (4,), (2, 2, 2, 2)])
def test_bad_array_shapes_raise_valueerror_and_write_nothing(tmp_path, shape):
    with pytest.raises(ValueError):
        _penumbra.image.write_exr(str(tmp_path / "bad.exr"), np.zeros(shape, np.float32))
    assert os.listdir(tmp_path) == []


def test_sanitize_counts_and_replaces_nan_inf_negative():
    pixels = np.array([[[np.nan, np.inf, -1.0], [1.0, 2.0, -np.inf]]], np.float32)
    clean, counts = _penumbra.image.sanitize(pixels)
    assert counts == {"nan": 1, "inf": 2, "negative": 1}
    np.testing.assert_array_equal(clean, [[[0, 0, 0], [1, 2, 0]]])
    assert np.isnan(pixels[0, 0, 0])  # the caller's array is untouched


def test_sequence_with_a_gap_names_the_missing_frame(tmp_path):
    for n in (1, 2, 4):
        _penumbra.image.write_exr(str(tmp_path / f"frame_{n:04d}.exr"), np.full((2, 2, 3), n, np.float32))
    with pytest.raises(_penumbra.IoError, match="frame_0003.exr"):
        _penumbra.image.read_frames(str(tmp_path / "frame_0001.exr"), kind="sequence")


def test_sequence_frames_come_back_in_order(tmp_path):
    for n in (5, 6, 7):
        _penumbra.image.write_exr(str(tmp_path / f"frame_{n:04d}.exr"), np.full((2, 3, 3), n, np.float32), half=False)
    frames, fps = _penumbra.image.read_frames(str(tmp_path / "frame_0005.exr"))
    assert [f[0, 0, 0] for f in frames] == [5, 6, 7]
    assert fps == 0.0


def test_gil_is_released_while_reading(tmp_path):
    # Another Python thread keeps running while C++ reads a large file.
    import threading
    path = str(tmp_path / "big.exr")
    _penumbra.image.write_exr(path, np.random.default_rng(0).random((1500, 3000, 3), dtype=np.float32), half=False)
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(1)
            done.wait(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    for _ in range(3):
        _penumbra.image.read(path)
    done.set()
    t.join()
    assert len(ticks) > 5
