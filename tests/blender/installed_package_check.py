"""Run inside a fresh Blender by test_installed_package.py, never on its own:
installs a Penumbra zip through Blender's own installer into the throwaway
user folders the test set up, runs each tool's main operator on a small
scene, then disables and removes the add-on. Prints one line
`RESULT {json}` with what happened; nothing here comes from the build tree.

    blender -b --factory-startup --python installed_package_check.py -- ZIP VIDEO OUT
    python installed_package_check.py ZIP VIDEO OUT        (the bpy module)
"""

import importlib
import json
import os
import sys
import traceback

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# Scene builders only: plain bpy scripts, no Penumbra code in them.
sys.path[:0] = [os.path.join(ROOT, "examples", "scenes")]

EXTENSION = bpy.app.version >= (4, 2, 0)
MODULE = "bl_ext.user_default.penumbra" if EXTENSION else "penumbra"


def install(zip_path):
    if EXTENSION:
        result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                          enable_on_install=True)
    else:
        result = bpy.ops.preferences.addon_install(filepath=zip_path)
        if result == {"FINISHED"}:
            result = bpy.ops.preferences.addon_enable(module=MODULE)
    return sorted(result)


def uninstall():
    if EXTENSION:
        repo_index = [r.module for r in bpy.context.preferences.extensions.repos].index("user_default")
        return sorted(bpy.ops.extensions.package_uninstall(repo_index=repo_index, pkg_id="penumbra"))
    import addon_utils
    folder = os.path.dirname(sys.modules[MODULE].__file__)
    bpy.ops.preferences.addon_disable(module=MODULE)
    try:
        return sorted(bpy.ops.preferences.addon_remove(module=MODULE))
    except RuntimeError as error:
        # Blender 3.x's operator removes the files, then redraws its area,
        # which background mode does not have: judge it by what it did.
        if "tag_redraw" not in str(error):
            raise
        addon_utils.modules_refresh()
        return ["FINISHED"] if not os.path.exists(folder) else ["FAILED"]


def empty_file():
    # Not read_factory_settings: it would reset the preferences, and with
    # them the add-on just installed.
    bpy.ops.wm.read_homefile(use_empty=True)


def visibility(out):
    import visibility_character
    empty_file()
    obj, _ = visibility_character.build(detail=1, frames=6)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    path = os.path.join(out, "character.pzh")
    baked = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=6, frame_step=2, rays=32, lobes=1,
                                             filepath=path)
    applied = bpy.ops.penumbra.apply_visibility()
    layer = obj.data.attributes.get("penumbra_visibility")
    return {"bake": sorted(baked), "apply": sorted(applied), "model_bytes": os.path.getsize(path),
            "has_visibility_attribute": layer is not None}


def lights(video, out):
    empty_file()
    result = bpy.ops.penumbra.build_light_rig(filepath=video, count=8, json_path=os.path.join(out, "rig.json"))
    collection = bpy.context.scene.penumbra.light_rig.collection
    suns = [o for o in collection.objects if o.type == "LIGHT"] if collection else []
    return {"build": sorted(result), "suns": len(suns), "rig_json": os.path.isfile(os.path.join(out, "rig.json"))}


def colormap(out):
    import colormap_scene
    empty_file()
    scene = bpy.context.scene
    plane, material, ramp, _, _ = colormap_scene.noise_ramp_plane()
    scene.penumbra.colormap.output_folder = out
    scene.penumbra.colormap.lut_width = 64
    scene.penumbra.colormap.lut_height = 32
    bpy.context.view_layer.objects.active = plane
    result = bpy.ops.penumbra.bake_colormap_lut()
    return {"bake": sorted(result), "ramp_muted": ramp.mute,
            "lookup_images": sorted(f for f in os.listdir(out) if f.endswith(".exr"))}


def mapped_libraries():
    """Shared libraries mapped in this process, by path (Linux)."""
    with open("/proc/self/maps") as f:
        return sorted({line.split()[-1] for line in f if ".so" in line.split()[-1]})


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    zip_path, video, out = args
    report = {"blender": bpy.app.version_string, "install": install(zip_path)}
    native = importlib.import_module(MODULE + ".native")
    report["load_error"] = native.load_error
    report["module_file"] = native.module.__file__ if native.module else None
    report["ffmpeg"] = native.module.image.ffmpeg_executable() if native.module else None
    for name, run in (("visibility", lambda: visibility(os.path.join(out, "visibility"))),
                      ("lights", lambda: lights(video, os.path.join(out, "lights"))),
                      ("colormap", lambda: colormap(os.path.join(out, "colormap")))):
        os.makedirs(os.path.join(out, name), exist_ok=True)
        try:
            report[name] = run()
        except Exception:
            report[name] = {"error": traceback.format_exc()}
    report["mapped"] = mapped_libraries()
    report["uninstall"] = uninstall()
    report["enabled_after_uninstall"] = MODULE in bpy.context.preferences.addons
    print("RESULT " + json.dumps(report), flush=True)


if __name__ == "__main__":  # extension_repo_steps.py imports the tool runs
    main()
