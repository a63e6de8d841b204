"""Runs inside a real Blender: Debian's `blender` 3.4 (through
pytest_in_blender.py) or the bpy 4.5 module from .venv (plain pytest).
Puts build/addon on sys.path, as a batch script would."""

import os
import sys

import bpy
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD_ADDON = os.path.join(ROOT, "build", "addon")
if BUILD_ADDON not in sys.path:
    sys.path.insert(0, BUILD_ADDON)


def pytest_report_header(config):
    return f"Blender {bpy.app.version_string} ({'bpy module' if bpy.app.binary_path == '' else bpy.app.binary_path})"


@pytest.fixture
def factory_scene():
    """A clean, empty file for each test that needs one."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield bpy.context.scene


@pytest.fixture
def addon(factory_scene):
    """The add-on registered on a clean file: lookup images beside the test's
    files, no World lighting or visibility model cached from another test."""
    import penumbra
    from penumbra.visibility import runtime, scene_data
    penumbra.register()
    factory_scene.penumbra.colormap.output_folder = ""
    scene_data._lighting_cache.clear()
    try:
        yield factory_scene
    finally:
        runtime.forget()
        penumbra.unregister()
