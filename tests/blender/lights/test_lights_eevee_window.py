"""Issue #26 item 6 in Blender 3.4's EEVEE Legacy, in a window under Xvfb
(Mesa's software OpenGL; `blender -b` has no GL context for EEVEE here): the
default rig, built for the scene's engine, lights a plane as Cycles' World
does within 4 % in mean luminance, and the check refuses the same rig 10 %
too dark or too bright. The test runs on pytest's worker thread; the scene,
the build and the renders run on Blender's main thread through on_main()."""

import bpy
import pytest

import lights_eevee_check as check
import lights_scenes
from blender_window import on_main


@pytest.fixture
def addon():
    yield from lights_scenes.window_addon()


def test_the_default_rig_drawn_by_eevee_legacy_matches_cycles_world(addon, tmp_path):
    folder = str(tmp_path)

    def measure():
        window = bpy.context.window_manager.windows[0]
        previous = window.scene
        window.scene = bpy.data.scenes.new("EEVEE Check")
        try:
            scene = window.scene
            rig, reference = check.rig_and_reference_means(scene, folder)
            check.scale_rig(scene, 1.1)
            brighter = check.mean_luminance(scene, check.eevee_engine(), folder)
            return rig, reference, brighter
        finally:
            window.scene = previous

    rig, reference, brighter = on_main(measure, timeout=240.0)
    assert check.within_tolerance(rig, reference), rig / reference
    for factor in (0.9, 1.1):
        assert not check.within_tolerance(factor * rig, reference), (factor, rig / reference)
    assert not check.within_tolerance(brighter, reference), brighter / reference
