"""A batch script that registers the add-on and returns exits by itself, with
status 0, within 60 s, in this Blender. Before the fix the bpy 4.5 module
never exited: see the comment above register() in addon/penumbra/__init__.py."""

import os
import subprocess
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

SCRIPT = f"""
import sys
import bpy
sys.path.insert(0, {os.path.join(ROOT, "build", "addon")!r})
import penumbra
penumbra.register()
bpy.context.scene.penumbra.visibility  # the settings exist, so register() really ran
print("REGISTERED")
"""


def test_a_script_that_registers_the_add_on_exits_by_itself():
    if bpy.app.binary_path:
        command = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1", "--python-expr", SCRIPT]
    else:
        command = [sys.executable, "-c", SCRIPT]
    try:
        proc = subprocess.run(command, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired as timeout:
        raise AssertionError(f"the script did not exit within 60 s: {timeout.stdout}") from None
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "REGISTERED" in proc.stdout
