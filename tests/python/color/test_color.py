"""Colour management through _penumbra with Blender's own OCIO config."""

import numpy as np
import pytest

import _penumbra
from conftest import BLENDER_OCIO


@pytest.fixture(scope="module")
def config():
    return _penumbra.color.Config(BLENDER_OCIO)


def srgb_to_linear(v):
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def test_scene_linear_role_of_blender_config(config):
    assert config.scene_linear == "Linear"
    assert "Filmic Log" in config.colorspace_names()


def test_srgb_to_scene_linear_matches_formula(config):
    v = np.linspace(0, 1, 11, dtype=np.float32)
    pixels = np.repeat(v[None, :, None], 3, axis=2)
    linear = config.to_scene_linear(pixels, "sRGB")
    np.testing.assert_allclose(linear[0, :, 0], srgb_to_linear(v), atol=2e-3)


def test_unknown_colorspace_is_valueerror_listing_names(config):
    with pytest.raises(ValueError, match=r"unknown colour space 'Rec.2020-ish'.*'sRGB'"):
        config.to_scene_linear(np.zeros((1, 1, 3), np.float32), "Rec.2020-ish")


def test_progress_callback_can_cancel(config):
    calls = []

    def stop(fraction):
        calls.append(fraction)
        return False

    pixels = np.full((500, 4, 3), 0.5, np.float32)
    with pytest.raises(_penumbra.Cancelled):
        config.convert(pixels, "sRGB", "Linear", progress=stop)
    assert calls == [0.0]


def test_exception_in_progress_callback_propagates(config):
    def boom(fraction):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        config.convert(np.full((200, 4, 3), 0.5, np.float32), "sRGB", "Linear", progress=boom)


def test_missing_config_is_a_clear_error():
    with pytest.raises(_penumbra.PenumbraError, match="not found"):
        _penumbra.color.Config("/nowhere/config.ocio")
