"""Writes the upgrade fixtures with an old version of Penumbra: kept so that
the next release can make its own. Run from a checkout of that version,
built (`make build`), in each bpy module:

    git worktree add --detach ../penumbra-0.2.0 dd137fb && cd ../penumbra-0.2.0 && make build
    .venv/bin/python    <this file> <this repo>/tests/data/upgrade/0.2.0/bpy-4.5
    .venv313/bin/python <this file> <this repo>/tests/data/upgrade/0.2.0/bpy-5.2

It uses only the old checkout (its add-on, its example scenes, its test
video maker) and writes, beside `upgrade.blend` and with paths relative to
it: the visibility model, the colour-map lookup, the light rig's source
video and JSON, and what 0.2.0 computed from them (`reference.npz`: the
character's shading at the stored frames, the colour-map render), which
tests/blender/test_upgrade_fixtures.py compares the new version against.
The .blend has one scene per tool: "Visibility" (the character, run-time
shading on), "Colour map" (the plane, its filtered material, a camera) and
"Lights" (the animated rig built from the video).
"""

import json
import os
import sys

import bpy
import numpy as np

OLD = os.getcwd()   # the old version's checkout, built
sys.path[:0] = [os.path.join(OLD, "build", "addon"), os.path.join(OLD, "examples", "scenes"),
                os.path.join(OLD, "scripts")]
import penumbra  # noqa: E402  (the old add-on, from its build tree)

SHADED_FRAMES = (1, 4, 7)      # 1 and 7 trained, 4 between two trained poses
RENDER_SIZE = (48, 32)
RENDER_SAMPLES = 16
RENDER_SEED = 0


def scene_named(name):
    """A new scene, made the window's: the example scenes and the operators
    work in the context's scene."""
    scene = bpy.data.scenes.new(name)
    bpy.context.window.scene = scene
    return scene


def visibility(out):
    import visibility_character
    scene = scene_named("Visibility")
    obj, _ = visibility_character.build(detail=1, frames=8)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    model = os.path.join(out, "character.pzh")
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=7, frame_step=3, rays=32, lobes=1,
                                              filepath=model)
    assert result == {"FINISHED"}, result
    assert bpy.ops.penumbra.setup_material() == {"FINISHED"}
    obj.penumbra_visibility.enabled = True
    shading = []
    for frame in SHADED_FRAMES:
        scene.frame_set(frame)
        values = np.empty(len(obj.data.vertices), dtype=np.float32)
        obj.data.attributes["penumbra_visibility"].data.foreach_get("value", values)
        shading.append(values)
    relative_paths(obj.penumbra_visibility, ("filepath", "model_path"))
    return {"visibility_shading": np.stack(shading), "visibility_frames": np.array(SHADED_FRAMES)}


def colormap(out):
    import colormap_scene
    scene = scene_named("Colour map")
    plane, *_ = colormap_scene.noise_ramp_plane()
    bpy.context.view_layer.objects.active = plane
    scene.penumbra.colormap.output_folder = "//lookup/"
    scene.penumbra.colormap.lut_width, scene.penumbra.colormap.lut_height = 64, 32
    result = bpy.ops.penumbra.bake_colormap_lut()
    assert result == {"FINISHED"}, result
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples, scene.cycles.seed = RENDER_SAMPLES, RENDER_SEED
    scene.cycles.use_denoising = scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x, scene.render.resolution_y = RENDER_SIZE
    scene.render.resolution_percentage = 100
    return {"colormap_render": render(scene, os.path.join(out, "render.exr"))}


def render(scene, path):
    """The scene's camera rendered to `path`, as RGBA pixels."""
    scene.render.filepath = path
    scene.render.image_settings.file_format = "OPEN_EXR"
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(image.size[1], image.size[0], 4)
    bpy.data.images.remove(image)
    os.remove(path)
    return pixels


def lights(out):
    import lights_make_test_videos as videos   # the old checkout's own test-video maker
    video = videos.write_video(os.path.join(out, "sky.mov"), videos.rotation_frames(videos.sky(32, 64), 4, 5.0),
                               fps=24)
    scene = scene_named("Lights")
    rig = scene.penumbra.light_rig   # set as in the panel, so that the .blend keeps them
    rig.filepath, rig.count, rig.json_path = bpy.path.relpath(video), 8, "//rig.json"
    result = bpy.ops.penumbra.build_light_rig()
    assert result == {"FINISHED"}, result
    return {}


def relative_paths(owner, names):
    """Paths in add-on settings are plain strings: Blender's relative remap
    on save does not reach them."""
    for name in names:
        value = getattr(owner, name)
        if value and not value.startswith("//"):
            setattr(owner, name, bpy.path.relpath(value))


def main():
    out = os.path.abspath(sys.argv[-1])
    os.makedirs(out, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.filepaths.save_version = 0   # no upgrade.blend1
    penumbra.register()
    blend = os.path.join(out, "upgrade.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)   # first, so that "//" means this folder
    reference = {**visibility(out), **colormap(out), **lights(out)}
    default = bpy.data.scenes.get("Scene")
    if default is not None and len(bpy.data.scenes) > 1:
        bpy.data.scenes.remove(default)
    # 0.2.0 loads its lookups by absolute path: made relative here, or the
    # fixture would only open where it was written.
    bpy.ops.file.make_paths_relative()
    bpy.ops.wm.save_as_mainfile(filepath=blend, relative_remap=True, compress=True)
    np.savez_compressed(os.path.join(out, "reference.npz"), **reference)
    with open(os.path.join(out, "fixture.json"), "w") as f:
        json.dump({"penumbra": ".".join(map(str, penumbra.bl_info["version"])), "blender": bpy.app.version_string,
                   "render": {"size": RENDER_SIZE, "samples": RENDER_SAMPLES, "seed": RENDER_SEED}}, f, indent=1)
    print(f"fixtures: {sorted(os.listdir(out))}")
    penumbra.unregister()


main()
