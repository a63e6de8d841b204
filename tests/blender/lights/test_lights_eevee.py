"""Issue #26 item 6 in bpy 5.2 (EEVEE Next, its GPU context made by
gpu.init() on Mesa's software OpenGL): the default rig, built for the
scene's engine, lights a plane as Cycles' World does within 4 % in mean
luminance, and the check refuses the same rig 10 % too dark or too bright.
Collected in bpy 5.2 only (conftest.ONLY_IN); 3.4's EEVEE Legacy runs it in
a window (test_lights_eevee_window.py)."""

import bpy

import lights_eevee_check as check


def test_the_default_rig_drawn_by_eevee_next_matches_cycles_world(addon, tmp_path):
    import gpu
    gpu.init()
    assert bpy.app.version >= (5, 0, 0)
    scene = addon
    rig, reference = check.rig_and_reference_means(scene, str(tmp_path))
    assert check.within_tolerance(rig, reference), rig / reference
    # The render is linear in the suns' strengths (no World, a linear film),
    # so the rig scaled renders as its render scaled (the 3.4 test renders it).
    for factor in (0.9, 1.1):
        assert not check.within_tolerance(factor * rig, reference), (factor, rig / reference)
