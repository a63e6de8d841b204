"""The zip under build/ installs the way a user installs it: as a legacy
add-on in Blender 3.4 (Preferences > Add-ons > Install) and as an extension
in Blender 4.2+ (Install from Disk). Each install runs in a fresh Blender
process with its user folders redirected to a temporary directory."""

import glob
import os
import subprocess
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

INSTALL_3X = """
import bpy, addon_utils
bpy.ops.preferences.addon_install(filepath={zip!r})
addon_utils.enable("penumbra", default_set=True, handle_error=None)
import penumbra.native as n
print("INSTALLED", "penumbra" in bpy.context.preferences.addons, hasattr(bpy.types, "PENUMBRA_PT_main"), n.load_error)
"""

INSTALL_4X = """
import bpy
bpy.ops.extensions.package_install_files(filepath={zip!r}, repo="user_default", enable_on_install=True)
name = "bl_ext.user_default.penumbra"
import importlib; n = importlib.import_module(name + ".native")
print("INSTALLED", name in bpy.context.preferences.addons, hasattr(bpy.types, "PENUMBRA_PT_main"), n.load_error)
"""


def test_zip_installs_and_enables_in_this_blender(tmp_path):
    zips = glob.glob(os.path.join(ROOT, "build", "penumbra-*.zip"))
    assert len(zips) == 1, zips
    env = dict(os.environ)
    if bpy.app.version >= (4, 2, 0):
        env["BLENDER_USER_RESOURCES"] = str(tmp_path)
        script = INSTALL_4X.format(zip=zips[0])
    else:
        env["BLENDER_USER_SCRIPTS"] = str(tmp_path / "scripts")
        env["BLENDER_USER_CONFIG"] = str(tmp_path / "config")
        script = INSTALL_3X.format(zip=zips[0])
    if bpy.app.binary_path:
        command = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1", "--python-expr", script]
    else:  # the bpy module: a fresh Python process
        command = [sys.executable, "-c", script]
    out = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    lines = [line for line in out.stdout.splitlines() if line.startswith("INSTALLED")]
    assert lines == ["INSTALLED True True None"], out.stdout[-2000:] + out.stderr[-2000:]
