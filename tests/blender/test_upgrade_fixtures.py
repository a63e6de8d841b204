"""Nothing is lost across an upgrade: the .blend, model, lookup and rig that
the real 0.2.0 wrote (tests/data/upgrade/0.2.0/bpy-<version>/, made by
tests/data/upgrade/make_fixtures.py from commit dd137fb) still work with
this version of the add-on. Each bpy module opens the fixtures it wrote;
Blender 3.4 cannot open a 4.5 or 5.2 file, and its path (the legacy zip over
the old one, an old .blend) is test_extension_repo.py's."""

import json
import os
import shutil

import bpy
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
FIXTURES = os.path.join(os.path.dirname(HERE), "data", "upgrade", "0.2.0", "bpy-%d.%d" % bpy.app.version[:2])
SHADING_TOLERANCE = 1e-6
RENDER_RMSE = 1e-3


@pytest.fixture
def old_file(addon, tmp_path):
    """The 0.2.0 .blend opened from a copy of its folder (a re-bake or a
    rebuilt rig writes beside it), the add-on registered."""
    folder = tmp_path / "0.2.0"
    shutil.copytree(FIXTURES, folder)
    bpy.ops.wm.open_mainfile(filepath=str(folder / "upgrade.blend"))
    with open(folder / "fixture.json") as f:
        settings = json.load(f)
    yield folder, np.load(folder / "reference.npz"), settings


def use_scene(name):
    """The window shows the scene, as a user's click would. The window's
    redraw then evaluates the scene, which makes its depsgraph the active
    one (the one that writes the pose back to the armature that the shading
    reads); background mode has no redraw, so the update is asked for here
    (without it, bpy 4.5 shades every frame in the pose the file was saved
    with; 5.2 evaluates on the frame change itself)."""
    scene = bpy.data.scenes[name]
    bpy.context.window.scene = scene
    bpy.context.view_layer.update()
    return scene


if bpy.app.version >= (4, 2, 0):
    def test_the_model_shades_the_stored_frames_as_0_2_0_did(old_file):
        _, reference, _ = old_file
        scene = use_scene("Visibility")
        obj = next(o for o in scene.objects if o.penumbra_visibility.enabled)
        for frame, expected in zip(reference["visibility_frames"], reference["visibility_shading"]):
            scene.frame_set(int(frame))
            values = np.empty(len(obj.data.vertices), dtype=np.float32)
            obj.data.attributes["penumbra_visibility"].data.foreach_get("value", values)
            assert np.abs(values - expected).max() <= SHADING_TOLERANCE, f"frame {frame}"

    def test_the_colour_map_renders_as_0_2_0_did(old_file):
        folder, reference, settings = old_file
        scene = use_scene("Colour map")
        assert (scene.cycles.samples, scene.cycles.seed) == (settings["render"]["samples"], settings["render"]["seed"])
        scene.render.filepath = str(folder / "render.exr")
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = np.array(image.pixels[:], dtype=np.float32).reshape(image.size[1], image.size[0], 4)
        rmse = float(np.sqrt(np.mean((pixels - reference["colormap_render"]) ** 2)))
        assert rmse <= RENDER_RMSE, rmse
        # The filter changed since 0.2.0: the material kept its old groups
        # (above) and the panel asks for a re-bake.
        from penumbra.colormap import filter_quality, sample_count
        material = next(m for m in bpy.data.materials if sample_count.noise_filter_nodes(m))
        assert filter_quality.rebake_reason(sample_count.noise_filter_nodes(material),
                                            scene.penumbra.colormap.filter_quality) == "Baked at 16 Taps Mix"

    def test_the_rig_rebuilds_from_the_blend_s_settings(old_file):
        folder, _, _ = old_file
        scene = use_scene("Lights")
        with open(folder / "rig.json") as f:
            old_rig = json.load(f)
        assert scene.penumbra.light_rig.filepath.startswith("//")   # relative: the copied folder's video
        assert bpy.ops.penumbra.build_light_rig() == {"FINISHED"}
        suns = [o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
        with open(bpy.path.abspath(scene.penumbra.light_rig.json_path)) as f:
            new_rig = json.load(f)
        assert len(suns) == scene.penumbra.light_rig.count == 8
        assert len(new_rig["frames"]) == len(old_rig["frames"])
