"""docs/architecture.md's data flow, run: each tool's main operator once on
a small scene, with every call into `_penumbra` recorded (sys.setprofile,
tests/architecture_doc.py), and every `_penumbra` name in the tool's `step`
table must have been called. Runs in bpy 4.5 only (conftest.py collects it
there and nowhere else), the Blender the doc describes."""

import math
import os
import sys

import bpy
import pytest

sys.path.append(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/: architecture_doc
import architecture_doc  # noqa: E402
from colormap_scenes import make_ramp_material, plane_with  # noqa: E402
from lights_scenes import sky_and_sun, world_with, write_map  # noqa: E402
from visibility_character_scenes import bake_op, character  # noqa: E402


def small_world(scene, folder):
    """A World lit by a small latlong file seen through a Mapping rotation."""
    path = write_map(os.path.join(str(folder), "sky.exr"), sky_and_sun(h=16, w=32))
    return world_with(scene, path, rotation_z=math.radians(30))


# Each tool: a scene is set up, then what it returns is run with every
# `_penumbra` call recorded.

def visibility(scene, folder):
    obj, _ = character(scene)
    small_world(scene, folder)

    def run():
        assert bake_op(folder, frame_end=22, frame_step=3, rays=16, lobes=1) == {"FINISHED"}
        obj.penumbra_visibility.enabled = True
        scene.frame_set(5)  # a pose the bake (frames 1, 4, ... 22) never saw, shaded by the frame-change handler
        assert obj.penumbra_visibility.status == ""
        assert "penumbra_shading" in obj.data.attributes
    return run


def lights(scene, folder):
    small_world(scene, folder)
    json_path = os.path.join(str(folder), "rig.json")

    def run():
        assert bpy.ops.penumbra.build_light_rig(count=4, frame_start=1, frame_end=1, json_path=json_path) == \
            {"FINISHED"}
    return run


def colormap(scene, folder):
    scene.penumbra.colormap.output_folder = str(folder)
    scene.penumbra.colormap.lut_width = scene.penumbra.colormap.lut_height = 16
    material, _ = make_ramp_material()  # driven by a Noise Texture
    obj = plane_with(material)
    bpy.ops.object.camera_add(location=(0, -6, 3), rotation=(1.1, 0, 0))
    scene.camera = bpy.context.active_object
    bpy.context.view_layer.objects.active = obj

    def run():
        assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    return run


SCENES = {"visibility": visibility, "lights": lights, "colormap": colormap}


@pytest.mark.parametrize("tool", sorted(SCENES))
def test_every_penumbra_function_in_the_tools_data_flow_is_called(addon, tmp_path, tool):
    from penumbra import native
    core = native.require()
    rows, problems = architecture_doc.load()
    rows = [r for r in rows if r.tool == tool]
    assert not problems, problems
    assert any(r.kind == "step" and r.penumbra for r in rows), f"no step row of {tool} cites a _penumbra name"
    run = SCENES[tool](addon, tmp_path)
    with architecture_doc.CallRecorder(core, architecture_doc.cited_classes(rows, core)) as recorder:
        run()
    missing = architecture_doc.uncalled(rows, core, recorder.called)
    assert not missing, "\n".join(missing + ["called:"] + architecture_doc.called_names(core, recorder.called))
