"""Issue #26 item 6 in bpy 5.2 (EEVEE Next, its GPU context made by
gpu.init() on Mesa's software OpenGL): the default rig, built for the
scene's engine, lights a plane as Cycles' World does within 4 % in mean
luminance, and the check refuses the same rig 10 % too dark or too bright.
Collected in bpy 5.2 only (conftest.ONLY_IN); 3.4's EEVEE Legacy runs it in
a window (test_lights_eevee_window.py).

gpu.init() cannot be undone, and the other tests of this process expect
the headless module's state (no GPU: test_gpu_preview.py), so the check
runs in a bpy 5.2 process of its own."""

import os
import subprocess
import sys
import textwrap

import bpy

from bench.helpers.result_line import only_result

HERE = os.path.dirname(os.path.abspath(__file__))
BLENDER_TESTS = os.path.dirname(HERE)
ROOT = os.path.dirname(os.path.dirname(BLENDER_TESTS))

CHECK = textwrap.dedent("""
    import json, sys
    sys.path[:0] = [{addon!r}, {tests!r}, {root!r}]
    import bpy, gpu
    gpu.init()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import penumbra
    penumbra.register()
    import lights_eevee_check as check
    rig, reference = check.rig_and_reference_means(bpy.context.scene, {folder!r})
    print("RESULT " + json.dumps({{"rig": float(rig), "reference": float(reference),
                                  "version": list(bpy.app.version)}}))
""")


def test_the_default_rig_drawn_by_eevee_next_matches_cycles_world(tmp_path):
    import lights_eevee_check as check
    code = CHECK.format(addon=os.path.join(ROOT, "build", "addon"), tests=BLENDER_TESTS, root=ROOT,
                        folder=str(tmp_path))
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, env=env)
    result = only_result(proc, tail=3000)
    assert result["version"][:2] == list(bpy.app.version[:2]) and bpy.app.version >= (5, 0, 0)
    rig, reference = result["rig"], result["reference"]
    assert check.within_tolerance(rig, reference), rig / reference
    # The render is linear in the suns' strengths (no World, a linear film),
    # so the rig scaled renders as its render scaled (the 3.4 test renders it).
    for factor in (0.9, 1.1):
        assert not check.within_tolerance(factor * rig, reference), (factor, rig / reference)
