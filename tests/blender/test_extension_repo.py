"""A user installs Penumbra and updates it, in this Blender, through its own
operators; one fresh process per start of Blender (extension_repo_steps.py),
with every user folder in a temporary directory.

4.2+: the user had installed the packaged version from disk, adds a copy of
dist/repo/ as a remote repository (file://), syncs it and installs from it;
restarts and runs each tool. The same build repacked as the next version
(`package.py --repack-as`) replaces the zip in that repository; the user
syncs and installs the update, restarts, and the new version runs.
3.x, which has no repositories: Install Add-on with the legacy zip, save a
.blend; Install Add-on again with the next version over it; restart and open
the old .blend."""

import os
import shutil
import subprocess
import sys

import bpy
import pytest

from bench.helpers.result_line import only_result

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
EXTENSION = bpy.app.version >= (4, 2, 0)
REPO_MODULE = "bl_ext.StudioPenumbra.penumbra"   # the repository extension_repo_steps.py adds
RESTART = "Restart Blender to load the new core"
THREADS = 3                                      # the preference the user set before updating


def packaged(kind):
    found = [n for n in os.listdir(os.path.join(ROOT, "dist")) if n.startswith("penumbra-") and n.endswith(f"-{kind}.zip")]
    assert len(found) == 1, f"expected one {kind} zip in dist/ (make package): {found}"
    return os.path.join(ROOT, "dist", found[0]), found[0].split("-")[1]


def next_version(version):
    major, minor, patch = map(int, version.split("."))
    return f"{major}.{minor}.{patch + 1}"


class User:
    """A user folder and the steps run in fresh Blenders against it."""

    def __init__(self, tmp):
        self.folder = tmp / "user"
        self.env = dict(os.environ)
        self.env.pop("PENUMBRA_FFMPEG", None)   # the installed add-on finds its own
        self.env.pop("PYTHONPATH", None)
        if EXTENSION:
            self.env["BLENDER_USER_RESOURCES"] = str(self.folder)
        else:
            self.env["BLENDER_USER_SCRIPTS"] = str(self.folder / "scripts")
            self.env["BLENDER_USER_CONFIG"] = str(self.folder / "config")

    def step(self, *args):
        script = os.path.join(HERE, "extension_repo_steps.py")
        if bpy.app.binary_path:   # not --factory-startup: a restart reads the preferences saved before
            command = [bpy.app.binary_path, "-b", "--python-exit-code", "1", "--python", script, "--", *args]
        else:
            command = [sys.executable, script, *args]
        proc = subprocess.run(command, env=self.env, capture_output=True, text=True, timeout=300)
        return only_result(proc, exit_zero=True, tail=3000)


def repack(version, dist, repo):
    """The packaged build as `version`, into `dist`, and `repo` serving it."""
    subprocess.run([os.path.join(ROOT, ".venv", "bin", "python"), os.path.join(ROOT, "scripts", "package.py"),
                    "--repack-as", version, "--dist", str(dist), "--repo", str(repo)],
                   check=True, capture_output=True, timeout=300)


@pytest.fixture(scope="module")
def journey(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("update")
    user = User(tmp)
    out = tmp / "out"
    if EXTENSION:
        zip_path, old = packaged("linux_x64")
        repo = tmp / "repo"   # a studio's copy of dist/repo/, which the update then changes
        shutil.copytree(os.path.join(ROOT, "dist", "repo"), repo)
        from bench.helpers import test_videos as videos   # fixture data only
        video = videos.write_video(str(tmp / "sky.mov"), videos.rotation_frames(videos.sky(32, 64), 4, 5.0), fps=24)
        steps = {"old": old, "new": next_version(old), "user": str(user.folder),
                 "disk_then_repo": user.step("disk-then-repo", zip_path, (repo / "index.json").as_uri()),
                 "restarted": user.step("run-tools", video, str(out / "tools"))}
        repack(steps["new"], tmp / "next", repo)
        steps["upgrade"] = user.step("upgrade", str(out / "upgrade"))
        steps["updated"] = user.step("check", str(out / "updated"))
    else:
        zip_path, old = packaged("legacy")
        steps = {"old": old, "new": next_version(old), "user": str(user.folder),
                 "install": user.step("legacy-install", zip_path, str(out / "old"))}
        repack(steps["new"], tmp / "next", tmp / "repo")
        steps["upgrade"] = user.step("legacy-upgrade", packaged_in(tmp / "next", "legacy"), str(out / "upgrade"))
        steps["updated"] = user.step("legacy-open", str(out / "old" / "old.blend"), str(out / "updated"))
    return steps


def packaged_in(folder, kind):
    return str(next(folder.glob(f"penumbra-*-{kind}.zip")))


def test_the_update_asks_for_a_restart_in_the_blender_that_installed_it(journey):
    upgrade = journey["upgrade"]
    assert upgrade["version"] == journey["new"], upgrade
    assert RESTART in (upgrade["load_error"] or ""), upgrade
    # The operators refuse, naming why, rather than drive the old core.
    assert RESTART in upgrade["tool"].get("error", ""), upgrade["tool"]


def test_a_restarted_blender_runs_the_new_version_with_the_user_s_preferences(journey):
    updated = journey["updated"]
    assert updated["enabled"] == [REPO_MODULE if EXTENSION else "penumbra"], updated
    assert updated["version"] == journey["new"] and updated["load_error"] is None, updated
    assert updated["core_file"].startswith(journey["user"]), updated
    # A repack keeps the compiled core, which names the version it was built as.
    assert updated["core_version"] == journey["old"], updated
    assert updated["threads"] == THREADS
    assert updated["tool"].get("bake") == ["FINISHED"], updated["tool"]


if EXTENSION:
    def test_a_file_repository_syncs_and_installs(journey):
        step = journey["disk_then_repo"]
        assert [step[k] for k in ("disk", "add", "sync", "install")] == [["FINISHED"]] * 4, step
        assert step["version"] == journey["old"] and step["load_error"] is None, step

    def test_a_copy_installed_from_disk_gives_way_to_the_repository_s_keeping_its_preferences(journey):
        for step in (journey["disk_then_repo"], journey["restarted"]):
            assert step["enabled"] == [REPO_MODULE], step
            assert step["threads"] == THREADS, step

    def test_each_tool_runs_from_the_repository_s_install(journey):
        restarted = journey["restarted"]
        assert restarted["core_file"].startswith(journey["user"]), restarted
        assert restarted["visibility"].get("apply") == ["FINISHED"], restarted["visibility"]
        assert restarted["lights"].get("suns") == 8, restarted["lights"]
        assert restarted["colormap"].get("bake") == ["FINISHED"], restarted["colormap"]

    def test_the_wheel_installed_is_the_new_version_s(journey):
        assert journey["updated"]["wheel_version"] == journey["new"]
else:
    def test_the_legacy_zip_installs_and_saves_a_blend(journey):
        install = journey["install"]
        assert install["install"] == ["FINISHED"] and install["tool"].get("bake") == ["FINISHED"], install

    def test_the_old_blend_opens_with_its_lookup_after_the_update(journey):
        updated = journey["updated"]
        assert updated["material"] and updated["lookup_images"], updated
