"""A failure on a worker thread of each tool's parallel stage, run from its
operator inside Blender: the operator reports an error (bpy.ops raises
RuntimeError with the report, not a traceback) instead of taking Blender
down, leaves no half-made result,
and the same operator then runs to the end. The failure (std::runtime_error
or std::bad_alloc) is injected through _penumbra.testing, one-shot; the
module-level tests of the same hook are tests/python/test_parallel_failures.py."""

import os

import bpy
import pytest

from penumbra import native

from colormap_scenes import make_ramp_material, plane_with
from lights_scenes import sky_and_sun, write_map
from visibility_character_scenes import bake_op, character, uniform_world

KINDS = ["runtime_error", "bad_alloc"]


def fails_then_runs(stage, kind, run, unchanged):
    """`run` (an operator call) is refused while `stage` fails and leaves
    `unchanged()` as it was; then it runs to the end."""
    testing = native.require().testing
    before = unchanged()
    testing.inject_worker_failure(stage, kind)
    try:
        with pytest.raises(RuntimeError) as error:
            run()
    finally:
        testing.inject_worker_failure(stage, "none")
    # A report the operator made, not a Python traceback escaping it.
    assert "Traceback" not in str(error.value), str(error.value)
    assert unchanged() == before
    assert run() == {"FINISHED"}


@pytest.mark.parametrize("kind", KINDS)
def test_bake_visibility(addon, tmp_path, kind):
    obj, _ = character(addon, frames=8)
    model = os.path.join(str(tmp_path), "model.pzh")
    fails_then_runs("visibility.bake", kind,
                    lambda: bake_op(tmp_path, frame_end=8, rays=16, filepath=model),
                    lambda: (os.path.exists(model), obj.penumbra_visibility.report, addon.frame_current))
    assert os.path.isfile(model)


# The run time's parallel stages: Blender's face normals, then the fused pass
# (normals, frames, lobes, shading) over blocks of vertices.
@pytest.mark.parametrize("stage", ["visibility.face_normals", "visibility.shade_frame"])
def test_apply_visibility(addon, tmp_path, stage):
    obj, _ = character(addon, frames=8)
    uniform_world(addon)
    assert bake_op(tmp_path, frame_end=8, rays=16) == {"FINISHED"}
    fails_then_runs(stage, "bad_alloc", bpy.ops.penumbra.apply_visibility,
                    lambda: "penumbra_shading" in obj.data.attributes)
    assert "penumbra_shading" in obj.data.attributes


@pytest.mark.parametrize("kind", KINDS)
def test_build_light_rig(addon, tmp_path, kind):
    path = write_map(str(tmp_path / "sky.exr"), sky_and_sun(h=32, w=64))
    json_path = str(tmp_path / "rig.json")
    objects_before = len(bpy.data.objects)
    fails_then_runs("lights", kind,
                    lambda: bpy.ops.penumbra.build_light_rig(filepath=path, count=8, json_path=json_path),
                    lambda: (sorted(o.name for o in bpy.data.objects), os.path.exists(json_path)))
    assert len(bpy.data.objects) > objects_before and os.path.isfile(json_path)


@pytest.mark.parametrize("kind", KINDS)
def test_bake_colormap_lut(addon, tmp_path, kind):
    settings = addon.penumbra.colormap
    settings.output_folder = str(tmp_path / "luts")
    settings.lut_width = settings.lut_height = 16
    material, ramp = make_ramp_material("ramped", noise=True)
    bpy.context.view_layer.objects.active = plane_with(material)
    fails_then_runs("colormap", kind, bpy.ops.penumbra.bake_colormap_lut,
                    lambda: (sorted(n.name for n in material.node_tree.nodes), ramp.mute))
    assert ramp.mute  # replaced by the filtered group
