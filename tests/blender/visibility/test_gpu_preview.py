"""The GPU viewport preview (addon/penumbra/visibility/gpu_preview.py).

In every Blender (headless, so without a GPU): the scene setting, what
turning it on says when there is no GPU, that the attributes and renders do
not change, that unregister removes the draw callback, and the generated
shader and uniform block. The GPU shading itself, against the CPU's, is
compared once per `make test` in Blenders that have a GPU:
tests/python/test_gpu_preview_in_blender.py."""

import math
import os
import sys

import bpy
import numpy as np
import pytest

import penumbra
from penumbra import compat, native
from penumbra.visibility import frame_shading, gpu_preview, preview_shader

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
import visibility_character  # noqa: E402
from visibility_character_scenes import front_camera  # noqa: E402


def attributes(obj):
    mesh = obj.data
    rgba = np.empty(len(mesh.vertices) * 4, dtype=np.float32)
    mesh.attributes[frame_shading.SHADING_ATTRIBUTE].data.foreach_get("color", rgba)
    ao = np.empty(len(mesh.vertices), dtype=np.float32)
    mesh.attributes[frame_shading.VISIBILITY_ATTRIBUTE].data.foreach_get("value", ao)
    return rgba.reshape(-1, 4), ao


def baked_character(scene, tmp_path):
    obj, rig = visibility_character.build(frames=24)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    world = bpy.data.worlds.new("Uniform")
    compat.ensure_nodes(world).nodes["Background"].inputs["Color"].default_value = (0.8, 0.9, 1.0, 1.0)
    scene.world = world
    assert bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=24, frame_step=2, rays=32, lobes=2,
                                            filepath=os.path.join(str(tmp_path), "model.pzh")) == {"FINISHED"}
    obj.penumbra_visibility.enabled = True
    return obj


def render(scene, path):
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = 24, 24
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.array(image.pixels[:], dtype=np.float32)
    bpy.data.images.remove(image)
    return pixels


def test_gpu_preview_is_a_scene_setting_that_starts_off(addon):
    settings = addon.penumbra.visibility
    assert settings.gpu_preview is False
    assert settings.gpu_preview_status == ""
    assert gpu_preview._draw_handle is not None  # registered with the add-on, drawing nothing while off


def test_turning_the_preview_on_without_a_gpu_says_so_and_changes_no_attribute_or_render(addon, tmp_path):
    obj = baked_character(addon, tmp_path)
    assert bpy.ops.penumbra.setup_material() == {"FINISHED"}
    front_camera(addon)
    before = {}
    for frame in (4, 10):
        addon.frame_set(frame)
        before[frame] = attributes(obj)
    render_before = render(addon, os.path.join(str(tmp_path), "off.png"))

    settings = addon.penumbra.visibility
    settings.gpu_preview = True
    # These suites run headless: there is no GPU, and the setting says so.
    assert gpu_preview.gpu_unavailable_reason() is not None
    assert settings.gpu_preview_status.startswith("no GPU available"), settings.gpu_preview_status
    assert not gpu_preview._previews
    gpu_preview._draw()  # the draw callback draws nothing and does not raise
    for frame in (4, 10):
        addon.frame_set(frame)
        rgba, ao = attributes(obj)
        np.testing.assert_array_equal(rgba, before[frame][0])
        np.testing.assert_array_equal(ao, before[frame][1])
    assert not gpu_preview._previews
    np.testing.assert_array_equal(render(addon, os.path.join(str(tmp_path), "on.png")), render_before)
    # A pose edit goes through the depsgraph handler: still nothing, still no error.
    rig = obj.modifiers["Armature"].object
    rig.pose.bones["forearm.L"].rotation_euler[2] += 0.3
    bpy.context.view_layer.update()
    assert settings.gpu_preview_status.startswith("no GPU available")
    assert bpy.ops.penumbra.apply_visibility() == {"FINISHED"}

    settings.gpu_preview = False
    assert settings.gpu_preview_status == ""


def test_unregister_removes_the_draw_callback_and_the_handlers(factory_scene):
    penumbra.register()
    assert gpu_preview._draw_handle is not None
    assert gpu_preview.on_frame_change in bpy.app.handlers.frame_change_post
    penumbra.unregister()
    assert gpu_preview._draw_handle is None
    assert gpu_preview.on_frame_change not in bpy.app.handlers.frame_change_post
    assert gpu_preview.on_depsgraph_update not in bpy.app.handlers.depsgraph_update_post
    assert gpu_preview.on_load not in bpy.app.handlers.load_post


def test_the_shader_is_written_for_every_model_a_bake_can_make_and_others_are_refused(addon):
    # The preview's limits are the core's (core/visibility/order_limit.hpp).
    core = native.require()
    assert (preview_shader.MAX_ORDER, preview_shader.MAX_LOBES) == (core.visibility.MAX_ORDER,
                                                                    core.visibility.MAX_LOBES)
    assert core.settings_spec()["visibility.lobes"]["max"] == core.visibility.MAX_LOBES
    for order in range(1, preview_shader.MAX_ORDER + 1):
        for lobes in range(1, preview_shader.MAX_LOBES + 1):
            # Inputs within the 16 vertex attributes OpenGL guarantees.
            assert 3 + preview_shader.lobe_vec4_count(order, lobes) <= 16
            for model in preview_shader.MODELS:
                for readback in (False, True):
                    source = preview_shader.vertex_source(order, lobes, model, readback)
                    assert source.count("{") == source.count("}")
                    assert ("gl_VertexID" in source) == readback
    with pytest.raises(ValueError, match=f"orders 1 to {core.visibility.MAX_ORDER}"):
        preview_shader.check_configuration(core.visibility.MAX_ORDER + 1, 2, "diffuse")
    with pytest.raises(ValueError, match=f"1 to {core.visibility.MAX_LOBES} lobes"):
        preview_shader.check_configuration(4, core.visibility.MAX_LOBES + 1, "diffuse")
    with pytest.raises(ValueError, match="BRDFs"):
        preview_shader.check_configuration(4, 2, "ward")


def test_the_uniform_block_holds_the_lighting_the_operator_blocks_and_the_camera(addon):
    core = native.require()
    order = 4
    lighting = np.arange(48, dtype=np.float64).reshape(16, 3) / 10.0
    data = np.frombuffer(preview_shader.uniform_data(order, lighting, "phong", 7.0, (1.0, 2.0, 3.0), (0.5, 0.5, 0.5)),
                         dtype=np.float32).reshape(-1, 4)
    _, total = preview_shader.operator_block_layout(order)
    assert total == 30  # Σ (4 − |m|)² over m = 0..3
    assert data.shape == (2 * 16 + math.ceil(total / 4) + 1, 4)
    np.testing.assert_allclose(data[:16, :3], lighting, rtol=1e-7)
    np.testing.assert_allclose(data[-1, :3], (1.0, 2.0, 3.0))
    # The blocks put back together are the core's dense operator.
    flat = data[32:32 + math.ceil(total / 4)].reshape(-1)[:total]
    dense = np.zeros((16, 16))
    offsets, _ = preview_shader.operator_block_layout(order)
    for m in range(-(order - 1), order):
        a, size = abs(m), order - abs(m)
        block = flat[offsets[a]:offsets[a] + size * size].reshape(size, size)
        rows = [preview_shader.sh_index(l, m) for l in range(a, order)]
        dense[np.ix_(rows, rows)] = block
    np.testing.assert_allclose(dense, core.sh.phong_operator(order, 7.0), atol=1e-7)
