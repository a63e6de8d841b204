"""Run inside a fresh Blender by test_extension_repo.py, one step per process,
never on its own: each step is what a user does between two starts of
Blender, in the throwaway user folders the test set up, through Blender's
own operators. Prints one line `RESULT {json}`.

    python extension_repo_steps.py STEP ARGS...                 (bpy 4.5, 5.2)
    blender -b --python extension_repo_steps.py -- STEP ARGS... (3.4)

Blender 4.2+ (a repository):
  disk-then-repo ZIP URL  install ZIP from disk, set a preference, add the
                          repository at URL, sync it, install from it
  run-tools VIDEO OUT     a restarted Blender: what is enabled, each tool's
                          main operator on a small scene
  upgrade                 sync, install the available updates, try a tool
  check OUT               a restarted Blender: what is loaded, one tool
Blender 3.x (no repositories):
  legacy-install ZIP OUT  Install Add-on, bake a colour-map lookup, save the .blend
  legacy-upgrade ZIP      Install Add-on over it with the next version, try a tool
  legacy-open BLEND OUT   a restarted Blender opens the old .blend, bakes again
"""

import importlib
import importlib.metadata
import json
import os
import sys
import traceback

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import installed_package_check as tools  # noqa: E402  (the tool runs on small scenes)

REPO_NAME = "Studio Penumbra"   # Blender makes the module name "StudioPenumbra" from it
THREADS = 3                     # a preference the user set, that must survive


def penumbra_addons():
    return sorted(a.module for a in bpy.context.preferences.addons if a.module.rpartition(".")[2] == "penumbra")


def loaded_state():
    """What the enabled copy runs: its version, its core, its preference."""
    enabled = penumbra_addons()
    state = {"enabled": enabled}
    if len(enabled) == 1:
        package = sys.modules[enabled[0]]
        native = importlib.import_module(enabled[0] + ".native")
        state.update(load_error=native.load_error,
                     core_file=native.module.__file__ if native.module else None,
                     core_version=native.module.__version__ if native.module else None,
                     threads=bpy.context.preferences.addons[enabled[0]].preferences.threads)
        if bpy.app.version >= (4, 2, 0):  # an extension's bl_info is not kept: its manifest has the version
            state["version"] = installed_manifest_version(os.path.dirname(package.__file__))
            state["wheel_version"] = importlib.metadata.version("penumbra_core")
        else:
            state["version"] = ".".join(map(str, package.bl_info["version"]))
    return state


def installed_manifest_version(folder):
    import tomllib
    with open(os.path.join(folder, "blender_manifest.toml"), "rb") as f:
        return tomllib.load(f)["version"]


def allow_online_access():
    """Installing and updating from any repository, file:// included, needs
    online access; syncing a file:// one does not (README: Installing).
    extensions.blender.org stays off: the tests reach no network."""
    bpy.context.preferences.system.use_online_access = True
    for repo in bpy.context.preferences.extensions.repos:
        if repo.module == "blender_org":
            repo.enabled = False


def our_repo():
    return next(r for r in bpy.context.preferences.extensions.repos if r.name == REPO_NAME)


def try_a_tool(out):
    """The colour-map bake, the quickest main operator, or its error."""
    os.makedirs(out, exist_ok=True)
    try:
        return tools.colormap(out)
    except Exception as error:
        return {"error": str(error)}


def disk_then_repo(zip_path, url):
    allow_online_access()
    report = {"disk": tools.install(zip_path)}
    bpy.context.preferences.addons[tools.MODULE].preferences.threads = THREADS
    report["add"] = sorted(bpy.ops.preferences.extension_repo_add(name=REPO_NAME, remote_url=url, type="REMOTE"))
    report["sync"] = sorted(bpy.ops.extensions.repo_sync(repo_directory=our_repo().directory))
    report["install"] = sorted(bpy.ops.extensions.package_install(repo_directory=our_repo().directory,
                                                                  pkg_id="penumbra", enable_on_install=True))
    report.update(loaded_state())
    bpy.ops.wm.save_userpref()
    return report


def run_tools(video, out):
    report = loaded_state()
    for name, run in (("visibility", lambda: tools.visibility(os.path.join(out, "visibility"))),
                      ("lights", lambda: tools.lights(video, os.path.join(out, "lights"))),
                      ("colormap", lambda: tools.colormap(os.path.join(out, "colormap")))):
        os.makedirs(os.path.join(out, name), exist_ok=True)
        try:
            report[name] = run()
        except Exception:
            report[name] = {"error": traceback.format_exc()}
    return report


def upgrade(out):
    allow_online_access()
    report = {"sync": sorted(bpy.ops.extensions.repo_sync(repo_directory=our_repo().directory)),
              "upgrade": sorted(bpy.ops.extensions.package_upgrade_all())}
    report.update(loaded_state())
    report["tool"] = try_a_tool(out)
    bpy.ops.wm.save_userpref()
    return report


def check(out):
    report = loaded_state()
    report["tool"] = try_a_tool(out)
    return report


def legacy_install(zip_path, out):
    report = {"install": tools.install(zip_path)}
    bpy.context.preferences.addons[tools.MODULE].preferences.threads = THREADS
    report["tool"] = try_a_tool(out)
    bpy.ops.wm.save_userpref()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "old.blend"), relative_remap=True)
    report.update(loaded_state())
    return report


def legacy_upgrade(zip_path, out):
    result = bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    report = {"install": sorted(result), "enable": sorted(bpy.ops.preferences.addon_enable(module=tools.MODULE))}
    report.update(loaded_state())
    report["tool"] = try_a_tool(out)
    bpy.ops.wm.save_userpref()
    return report


def legacy_open(blend, out):
    bpy.ops.wm.open_mainfile(filepath=blend)
    report = loaded_state()
    material = bpy.data.materials.get("ColormapNoise") or next(iter(bpy.data.materials), None)
    report["lookup_images"] = sorted(i.name for i in bpy.data.images if i.filepath.endswith(".exr"))
    report["material"] = material.name if material else None
    report["tool"] = try_a_tool(out)
    return report


STEPS = {"disk-then-repo": disk_then_repo, "run-tools": run_tools, "upgrade": upgrade, "check": check,
         "legacy-install": legacy_install, "legacy-upgrade": legacy_upgrade, "legacy-open": legacy_open}


def start_as_the_user():
    """Blender reads the user's preferences at start, enabling their add-ons;
    the bpy module starts from factory settings, so it reads them here."""
    if not bpy.app.binary_path:
        bpy.ops.wm.read_userpref()


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    start_as_the_user()
    print("RESULT " + json.dumps(STEPS[args[0]](*args[1:])), flush=True)


main()
