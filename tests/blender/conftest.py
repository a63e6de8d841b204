"""Runs inside a real Blender: Debian's `blender` 3.4 (through
pytest_in_blender.py, in the background or in a window under Xvfb) or the
bpy 4.5 / 5.2 modules (plain pytest). Puts build/addon on sys.path, as a
batch script would, and picks the test files for the mode (blender_window.py)."""

import os
import sys

import bpy
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD_ADDON = os.path.join(ROOT, "build", "addon")
if BUILD_ADDON not in sys.path:
    sys.path.insert(0, BUILD_ADDON)
if ROOT not in sys.path:
    sys.path.append(ROOT)  # bench.helpers: what the tests share with the benchmarks

import blender_window  # noqa: E402  (tests/blender is on sys.path: pytest's rootdir-relative imports)


def pytest_report_header(config):
    mode = "window: only *_window.py" if blender_window.windowed() else "background: *_window.py left out"
    return (f"Blender {bpy.app.version_string} ({'bpy module' if bpy.app.binary_path == '' else bpy.app.binary_path}; "
            f"{mode})")


# Test files that run in one Blender only and are not even collected in the
# others (a skip would count as a failure): docs/architecture.md's calls are
# bpy 4.5's; the benchmark criteria checks run in the Blender their
# benchmark runs in, as their answer does not depend on the version and their
# cost would triple.
ONLY_IN = {"test_architecture_calls.py": (4, 5),
           "test_colormap_criteria.py": (4, 5),
           "test_colormap_equal_time.py": (4, 5),
           "test_visibility_criteria.py": (4, 5),
           "test_lights_eevee.py": (5, 2)}  # EEVEE Next after gpu.init(); 3.4 runs test_lights_eevee_window.py


def pytest_ignore_collect(collection_path, config):
    """Tests of the window manager (`*_window.py`, see blender_window.py) run
    only in a windowed Blender, every other test only in a background one;
    the files of ONLY_IN only in their Blender."""
    name = collection_path.name
    if collection_path.is_file() and name.startswith("test_") and name.endswith(".py"):
        if name in ONLY_IN and tuple(bpy.app.version[:2]) != ONLY_IN[name]:
            return True
        return name.endswith("_window.py") != blender_window.windowed()
    return None


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
    from penumbra.visibility import frame_shading, world_lighting
    penumbra.register()
    factory_scene.penumbra.colormap.output_folder = ""
    world_lighting._lighting_cache.clear()
    try:
        yield factory_scene
    finally:
        frame_shading.forget()
        penumbra.unregister()
