"""The zips in dist/ install the way a user installs them, in this Blender:
the legacy zip through Install Add-on in 3.x, the extension zip through
Install from Disk in 4.2+. A fresh Blender process with its user folders in
a temporary directory installs the zip, runs each tool's main operator on a
small scene, then disables and removes the add-on
(installed_package_check.py). Nothing comes from the build tree."""

import glob
import os
import subprocess
import sys

import bpy
import pytest

from bench.helpers.result_line import only_result

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def package():
    kind = "linux_x64" if bpy.app.version >= (4, 2, 0) else "legacy"
    found = glob.glob(os.path.join(ROOT, "dist", f"penumbra-*-{kind}.zip"))
    assert len(found) == 1, f"expected one {kind} zip in dist/ (make package): {found}"
    return found[0]


@pytest.fixture(scope="module")
def installed_run(tmp_path_factory):
    from bench.helpers import test_videos as videos  # fixture data only: made with the build tree's module
    tmp = tmp_path_factory.mktemp("install")
    video = videos.write_video(str(tmp / "sky.mov"), videos.rotation_frames(videos.sky(32, 64), 4, 5.0), fps=24)
    user = tmp / "user"
    env = dict(os.environ)
    env.pop("PENUMBRA_FFMPEG", None)  # the installed add-on must find its own ffmpeg
    env.pop("PYTHONPATH", None)
    if bpy.app.version >= (4, 2, 0):
        env["BLENDER_USER_RESOURCES"] = str(user)
    else:
        env["BLENDER_USER_SCRIPTS"] = str(user / "scripts")
        env["BLENDER_USER_CONFIG"] = str(user / "config")
    script = os.path.join(HERE, "installed_package_check.py")
    args = [package(), video, str(tmp / "out")]
    if bpy.app.binary_path:
        command = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1", "--python", script, "--",
                   *args]
    else:
        command = [sys.executable, script, *args]
    proc = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    report = only_result(proc, exit_zero=True, tail=3000)
    report["user_folder"] = str(user)
    return report


def test_the_package_installs_and_loads_its_own_core(installed_run):
    assert installed_run["install"] == ["FINISHED"]
    assert installed_run["load_error"] is None
    # The core and the video decoder come from the installed package, not from this checkout.
    assert installed_run["module_file"].startswith(installed_run["user_folder"])
    assert installed_run["ffmpeg"].startswith(installed_run["user_folder"])


def test_the_visibility_baker_runs_from_the_installed_package(installed_run):
    result = installed_run["visibility"]
    assert result.get("bake") == ["FINISHED"] and result.get("apply") == ["FINISHED"], result
    assert result["model_bytes"] > 0 and result["has_visibility_attribute"]


def test_a_light_rig_is_built_from_a_video_by_the_installed_package(installed_run):
    result = installed_run["lights"]
    assert result.get("build") == ["FINISHED"], result
    assert result["suns"] == 8 and result["rig_json"]


def test_the_colour_map_lookup_is_baked_by_the_installed_package(installed_run):
    result = installed_run["colormap"]
    assert result.get("bake") == ["FINISHED"], result
    assert result["ramp_muted"] and result["lookup_images"]


def test_the_package_brings_its_own_libraries_and_maps_each_once(installed_run):
    """The libraries come from the package (auditwheel gave them unique
    names), beside whatever copies Blender itself has mapped; TBB included:
    Blender's own, where it is in the global scope, serves both (docs/packaging.md)."""
    ours = [lib for lib in installed_run["mapped"] if lib.startswith(installed_run["user_folder"])]
    families = {os.path.basename(lib).split("-")[0] for lib in ours if ".libs/" in lib}
    assert {"libOpenImageIO", "libOpenImageIO_Util", "libOpenColorIO", "libembree3", "libtbb"} <= families, ours
    by_name = {}
    for lib in installed_run["mapped"]:
        by_name.setdefault(os.path.basename(lib), []).append(lib)
    assert not {k: v for k, v in by_name.items() if len(v) > 1}


def test_the_add_on_is_disabled_and_removed(installed_run):
    assert installed_run["uninstall"] == ["FINISHED"]
    assert not installed_run["enabled_after_uninstall"]
