"""The add-on inside real Blender: registration, panel, preferences, and the
compiled core working next to Blender's own libraries."""

import os
import sys

import bpy
import numpy as np
import pytest

import penumbra
from penumbra import native

PANELS = ("PENUMBRA_PT_main", "PENUMBRA_PT_visibility", "PENUMBRA_PT_light_rig", "PENUMBRA_PT_colormap")


def registered_penumbra_classes():
    return sorted(name for name in dir(bpy.types) if name.startswith(("PENUMBRA_", "Penumbra")))


def test_native_core_loads_in_this_blender():
    assert native.load_error is None
    assert native.module is sys.modules["_penumbra"]
    info = native.module.build_info()
    # Built for the Python this Blender runs. Debian's Blender 3.4 (system
    # Python) and bpy 4.x and 5.0 run Python 3.11; Blender 5.1 moved to Python
    # 3.13 (PyPI's bpy 5.1+ wheels are cp313 only), where the cpython-313
    # build of the module is loaded.
    assert info["python"].startswith(f"{sys.version_info.major}.{sys.version_info.minor}.")
    assert info["python"].startswith("3.13." if bpy.app.version >= (5, 1, 0) else "3.11.")
    # Embree creates a real device here, on whichever TBB this process mapped.
    assert info["embree"].startswith("3.") and "failed" not in info["embree"]


def test_register_unregister_three_times_leaves_nothing_behind(factory_scene):
    before = registered_penumbra_classes()
    assert before == []
    for _ in range(3):
        penumbra.register()
        for panel in PANELS:
            assert hasattr(bpy.types, panel), panel
        assert hasattr(bpy.types.Scene, "penumbra")
        assert factory_scene.penumbra.visibility is not None
        penumbra.unregister()
        assert registered_penumbra_classes() == before
        assert not hasattr(bpy.types.Scene, "penumbra")


def test_panel_lives_in_the_3d_viewport_sidebar_tab(factory_scene):
    penumbra.register()
    try:
        main = bpy.types.PENUMBRA_PT_main
        assert (main.bl_space_type, main.bl_region_type, main.bl_category) == ("VIEW_3D", "UI", "Penumbra")
        for panel in PANELS[1:]:
            assert getattr(bpy.types, panel).bl_parent_id == "PENUMBRA_PT_main"
    finally:
        penumbra.unregister()


def test_preferences_class_is_registered_under_the_package_name(factory_scene):
    penumbra.register()
    try:
        prefs = penumbra.preferences.PENUMBRA_AP_preferences
        assert prefs.is_registered
        assert prefs.bl_idname == "penumbra"
        assert {"ocio_config", "threads"} <= set(prefs.__annotations__)
    finally:
        penumbra.unregister()


def test_addon_enables_through_blender_addon_utils(factory_scene):
    # The way a user enables it: preferences then really exist.
    import addon_utils
    addon_utils.enable("penumbra", default_set=True, handle_error=None)
    try:
        prefs = bpy.context.preferences.addons["penumbra"].preferences
        assert prefs.threads == 0
        prefs.threads = 2
        assert prefs.threads == 2
    finally:
        addon_utils.disable("penumbra", default_set=True)
    assert "penumbra" not in bpy.context.preferences.addons


def test_settings_are_saved_in_the_blend(factory_scene, tmp_path):
    penumbra.register()
    try:
        path = str(tmp_path / "saved.blend")
        bpy.ops.wm.save_as_mainfile(filepath=path)
        bpy.ops.wm.open_mainfile(filepath=path)
        assert bpy.context.scene.penumbra.light_rig is not None
    finally:
        penumbra.unregister()


def test_image_round_trip_through_core_with_blenders_own_ocio(tmp_path):
    from penumbra import color
    config = color.blender_config()
    assert os.path.dirname(config.path).endswith("colormanagement")
    assert config.has_colorspace("sRGB")
    srgb = np.linspace(0, 1, 5 * 4 * 3, dtype=np.float32).reshape(5, 4, 3)
    linear = config.to_scene_linear(srgb, "sRGB")
    path = str(tmp_path / "linear.exr")
    native.module.image.write_exr(path, linear, half=False, colorspace=config.scene_linear)
    back = native.module.image.read(path)
    np.testing.assert_array_equal(back, linear)
    # Blender reads the same file to the same numbers.
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = config.scene_linear
    blender_pixels = np.array(image.pixels[:], np.float32).reshape(5, 4, 4)[::-1, :, :3]
    np.testing.assert_allclose(blender_pixels, back, rtol=1e-6)
    bpy.data.images.remove(image)


def test_core_conversion_matches_blenders_own_colour_management():
    from mathutils import Color
    from penumbra import color
    config = color.blender_config()
    values = np.array([0.0, 0.01, 0.1, 0.3, 0.5, 0.8, 1.0], np.float32)
    ours = config.to_scene_linear(np.repeat(values[None, :, None], 3, axis=2), "sRGB")[0, :, 0]
    blenders = [Color((v, v, v)).from_srgb_to_scene_linear()[0] for v in values]
    np.testing.assert_allclose(ours, blenders, atol=1e-3)


def test_conversion_to_the_working_space_matches_blenders_own(factory_scene):
    """Scene linear is what Blender renders in. Blender 5.0 made it a setting
    of each file, the working space (Linear Rec.709, Linear Rec.2020 or
    ACEScg); before, it is the config's scene_linear role. In every working
    space the file can have, the core converts sRGB to it as Blender does."""
    from mathutils import Color
    from penumbra import color
    config = color.blender_config()
    srgb = np.array([[0.9, 0.1, 0.05], [0.05, 0.2, 0.9], [0.3, 0.8, 0.2], [0.5, 0.5, 0.5]], np.float32)
    spaces = ["Linear Rec.709", "Linear Rec.2020", "ACEScg"] if bpy.app.version >= (5, 0, 0) else [None]
    for space in spaces:
        if space is not None and space != bpy.data.colorspace.working_space:
            assert bpy.ops.wm.set_working_color_space(working_space=space) == {"FINISHED"}
        assert color.working_space(config) == (space or config.scene_linear)
        ours = color.to_working_space(config, srgb[None], "sRGB")[0]
        blenders = [tuple(Color(tuple(map(float, c))).from_srgb_to_scene_linear()) for c in srgb]
        np.testing.assert_allclose(ours, blenders, atol=1e-3, err_msg=str(space))


def mapped_libraries():
    maps = open("/proc/self/maps").read().splitlines()
    return sorted({line.split()[-1] for line in maps if ".so" in line and line.split()[-1].startswith("/")})


def soname(path):
    """The ELF DT_SONAME of a shared library (libtbb.so.12.8 -> libtbb.so.12)."""
    import subprocess
    out = subprocess.run(["readelf", "-d", path], capture_output=True, text=True).stdout
    for line in out.splitlines():
        if "(SONAME)" in line:
            return line.split("[", 1)[1].rstrip("]")
    return os.path.basename(path)


def test_each_shared_library_family_maps_distinct_versions_only():
    """Blender 4.5 (bpy) carries OpenImageIO 3.0, OpenColorIO 2.4 and TBB; the
    module links Debian's OpenImageIO 2.4 and OpenColorIO 2.1. Different
    versions live side by side (their C++ namespaces are versioned); the same
    SONAME is mapped once and shared (TBB's ABI is stable across 2021.x). The
    module exports only PyInit__penumbra, so it cannot interpose on Blender."""
    libs = mapped_libraries()
    assert any(os.path.basename(lib).startswith("_penumbra") for lib in libs)
    seen = {}
    for lib in libs:
        base = os.path.basename(lib)
        if ".so" not in base:
            continue
        seen.setdefault(soname(lib), []).append(lib)
    clashes = {k: v for k, v in seen.items() if len(v) > 1}
    assert clashes == {}, clashes
    for family in ("libOpenImageIO", "libOpenColorIO", "libtbb", "libembree"):
        print(family, [lib for lib in libs if os.path.basename(lib).startswith(family)])
