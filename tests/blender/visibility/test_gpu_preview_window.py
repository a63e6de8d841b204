"""The GPU preview following what users do (issue 27 item 4), in Blender 3.4's
own viewport under Xvfb (blender_window.py): scrubbing and a modal bone
rotation update what the viewport draws; two characters with different
BRDFs draw in one redraw; a model change, an object's deletion, a new file
and an undo leave the preview holding no GPU texture for the object; a
topology edit stops its preview and says why. The characters carry
synthetic models (bench/helpers/gpu_preview_scene.py): this is about
following the scene, the shading's exactness is test_gpu_model_in_blender.py's."""

import importlib
import weakref

import bpy
import pytest

from blender_window import let_the_loop_turn, on_main, wait_until

VERTICES = 1500


@pytest.fixture(scope="module")
def addon():
    penumbra = on_main(lambda: importlib.import_module("penumbra"))
    on_main(penumbra.register)
    yield penumbra
    on_main(penumbra.unregister)


def _gpu():
    from penumbra.visibility import gpu_model, gpu_preview
    return gpu_model, gpu_preview


def _view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return {"window": window, "area": area, "region": region, "screen": window.screen}


def redraw():
    def draw():
        override = _view3d()
        if hasattr(bpy.context, "temp_override"):
            with bpy.context.temp_override(**override):
                bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)
        else:
            bpy.ops.wm.redraw_timer(override, type="DRAW", iterations=1)
    on_main(draw)


@pytest.fixture
def baseline(addon):
    """The preview's GPU textures before the test (none: a fresh scene)."""
    def reset():
        bpy.context.scene.penumbra.visibility.gpu_preview = False
        return _gpu()[0].live_texture_count()
    count = on_main(reset)
    yield count
    on_main(reset)


def make_character(tmp_path, name="PenumbraCharacter", empty=True, brdf="DIFFUSE", seed=27):
    def make():
        from bench.helpers.gpu_preview_scene import character
        scene, obj = character(VERTICES, str(tmp_path), name=name, empty=empty, seed=seed)
        obj.penumbra_visibility.brdf = brdf
        scene.penumbra.visibility.gpu_preview = True
        return obj.name
    return on_main(make)


def drawn_pose(name):
    """The pose block the viewport last uploaded for the object."""
    def read():
        preview = _gpu()[1]._previews.get(name)
        return None if preview is None or preview.batch is None else preview.batch.pose_bytes
    return on_main(read)


def scene_pose(name):
    """The pose block of the scene as it is now, computed apart from the viewport."""
    def compute():
        from penumbra.visibility import armature_data, frame_shading, model_shader
        obj = bpy.data.objects[name]
        model = frame_shading.loaded_model(obj).model
        features = model.pose_features(armature_data.bone_rotations(armature_data.armature_of(obj), model.joints))
        world = [list(row) for row in obj.matrix_world]
        return model_shader.pose_data(features, model_shader.feature_vec4_count(len(features)), world)
    return on_main(compute)


def test_scrubbing_updates_what_the_viewport_draws(baseline, tmp_path):
    name = make_character(tmp_path)
    seen = []
    for frame in (3, 9, 15):
        on_main(lambda: bpy.context.scene.frame_set(frame))
        redraw()
        assert on_main(lambda: list(_gpu()[1].last_drawn)) == [name]
        assert drawn_pose(name) == scene_pose(name)
        seen.append(drawn_pose(name))
    assert len(set(seen)) == 3  # every frame's pose, not one kept from before


def test_a_modal_bone_rotation_updates_the_preview_while_dragging(baseline, tmp_path):
    name = make_character(tmp_path)

    def pose_mode():
        armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
        for obj in bpy.context.view_layer.objects:
            obj.select_set(False)
        bpy.context.view_layer.objects.active = armature
        armature.select_set(True)
        bpy.ops.object.mode_set(mode="POSE")
        for bone in armature.data.bones:
            bone.select = bone.name == "forearm.L"
        armature.data.bones.active = armature.data.bones["forearm.L"]
    on_main(pose_mode)
    redraw()
    before = drawn_pose(name)

    def start_rotate():
        override = _view3d()
        window, region = override["window"], override["region"]
        x, y = region.x + region.width // 2, region.y + region.height // 2
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
        window.event_simulate(type="R", value="PRESS", x=x, y=y)
        window.event_simulate(type="R", value="RELEASE", x=x, y=y)
        return x, y
    x, y = on_main(start_rotate)
    let_the_loop_turn(5)
    for step in range(1, 6):
        on_main(lambda: _view3d()["window"].event_simulate(type="MOUSEMOVE", value="NOTHING",
                                                            x=x + 25 * step, y=y + 15 * step))
        let_the_loop_turn(3)
    redraw()
    during = drawn_pose(name)
    assert during != before  # the drag, not yet confirmed, already moved the preview
    assert during == scene_pose(name)

    def confirm():
        window = _view3d()["window"]
        window.event_simulate(type="RET", value="PRESS", x=x + 125, y=y + 75)
        window.event_simulate(type="RET", value="RELEASE", x=x + 125, y=y + 75)
    on_main(confirm)
    let_the_loop_turn(5)
    on_main(lambda: bpy.ops.object.mode_set(mode="OBJECT"))


def drawn_shading(name):
    """The shading block (lighting, BRDF operator, camera) the viewport last uploaded."""
    return on_main(lambda: _gpu()[1]._previews[name].batch.shading_bytes)


def scene_shading(name):
    """The shading block of the scene as it is now, its World read afresh."""
    def compute():
        import numpy as np
        from penumbra.visibility import frame_shading, preview_shader, world_lighting
        obj, scene = bpy.data.objects[name], bpy.context.scene
        order, settings = frame_shading.loaded_model(obj).model.order, obj.penumbra_visibility
        lighting, _ = world_lighting.world_lighting(scene, order)
        return preview_shader.uniform_data(order, lighting, settings.brdf.lower(), settings.phong_exponent,
                                           tuple(scene.camera.matrix_world.translation),
                                           np.array(settings.transmission[:]))
    return on_main(compute)


def _background():
    return bpy.context.scene.world.node_tree.nodes["Background"]


def test_the_preview_follows_world_edits_and_an_animated_world(baseline, tmp_path):
    """The preview keeps its read of the World between frames (issue 27's
    frame cost), so each way the World's light can change must reach it."""
    name = make_character(tmp_path)
    on_main(lambda: bpy.context.scene.frame_set(3))
    redraw()
    before = drawn_shading(name)
    assert before == scene_shading(name)

    # An edit in the UI: the depsgraph update handler, no frame change.
    on_main(lambda: _background().inputs["Color"].__setattr__("default_value", (0.2, 0.5, 1.0, 1.0)))
    let_the_loop_turn(3)
    redraw()
    edited = drawn_shading(name)
    assert edited != before and edited == scene_shading(name)

    # A script's edit followed at once by a frame change, no event in between.
    def edit_then_change_frame():
        _background().inputs["Strength"].default_value = 2.0
        bpy.context.scene.frame_set(4)
    on_main(edit_then_change_frame)
    redraw()
    scripted = drawn_shading(name)
    assert scripted != edited and scripted == scene_shading(name)

    # Keyframes: the light changes with the frame, with no edit at all.
    def keyframe_strength():
        strength = _background().inputs["Strength"]
        strength.default_value = 1.0
        strength.keyframe_insert("default_value", frame=1)
        strength.default_value = 4.0
        strength.keyframe_insert("default_value", frame=21)
    on_main(keyframe_strength)
    let_the_loop_turn(3)
    seen = []
    for frame in (6, 16):
        on_main(lambda: bpy.context.scene.frame_set(frame))
        redraw()
        seen.append(drawn_shading(name))
        assert seen[-1] == scene_shading(name)
    assert seen[0] != seen[1]


def test_the_preview_follows_a_new_world_and_the_render_engine(baseline, tmp_path):
    """A Scene update relights only when it changes what the World was read
    for: another World, or an engine with its own World Output."""
    name = make_character(tmp_path)

    def engine(name):
        bpy.context.scene.render.engine = name

    def other_world():
        from penumbra import compat
        world = bpy.data.worlds.new("Other")
        tree = compat.ensure_nodes(world)
        tree.nodes["Background"].inputs["Color"].default_value = (1.0, 0.3, 0.1, 1.0)
        for_cycles = tree.nodes.new("ShaderNodeBackground")
        for_cycles.inputs["Color"].default_value = (0.1, 1.0, 0.3, 1.0)
        output = tree.nodes.new("ShaderNodeOutputWorld")
        output.target = "CYCLES"
        tree.links.new(for_cycles.outputs["Background"], output.inputs["Surface"])
        bpy.context.scene.world = world
    on_main(lambda: engine("BLENDER_EEVEE_NEXT" if bpy.app.version >= (4, 2, 0) else "BLENDER_EEVEE"))
    redraw()
    first = drawn_shading(name)
    seen = [first]
    for change in (other_world, lambda: engine("CYCLES")):
        on_main(change)
        let_the_loop_turn(3)
        redraw()
        seen.append(drawn_shading(name))
        assert seen[-1] == scene_shading(name)
    assert len(set(seen)) == 3


def test_two_characters_with_different_brdfs_draw_in_one_redraw(baseline, tmp_path):
    first = make_character(tmp_path, "Diffuse", brdf="DIFFUSE")
    second = make_character(tmp_path, "Shiny", empty=False, brdf="PHONG", seed=28)
    on_main(lambda: bpy.data.objects[second].location.__setitem__(0, 3.0))
    on_main(lambda: bpy.context.scene.frame_set(5))
    redraw()
    assert sorted(on_main(lambda: list(_gpu()[1].last_drawn))) == sorted([first, second])
    brdfs = on_main(lambda: {n: p.batch.brdf for n, p in _gpu()[1]._previews.items()})
    assert brdfs == {first: "diffuse", second: "phong"}
    assert on_main(lambda: bpy.context.scene.penumbra.visibility.gpu_preview_status) == ""


def _textures():
    return on_main(lambda: _gpu()[0].live_texture_count())


def test_deleting_the_object_frees_its_textures(baseline, tmp_path):
    name = make_character(tmp_path)
    redraw()
    assert _textures() == baseline + 7  # six of the model, one of the frame
    on_main(lambda: bpy.data.objects.remove(bpy.data.objects[name]))
    wait_until(lambda: name not in _gpu()[1]._previews)
    assert _textures() == baseline


def test_a_model_change_frees_the_old_models_textures(baseline, tmp_path):
    name = make_character(tmp_path)
    redraw()
    # A weak reference, not id(): CPython may place the new model's copy at
    # the freed one's address.
    old = on_main(lambda: weakref.ref(_gpu()[1]._previews[name].batch))

    def other_model():
        from bench.helpers.gpu_preview_scene import synthetic_model
        obj = bpy.data.objects[name]
        armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
        path = str(tmp_path / "other.pzh")
        synthetic_model(obj, armature, path, seed=5)
        obj.penumbra_visibility.model_path = path
        bpy.context.scene.frame_set(bpy.context.scene.frame_current + 1)
    on_main(other_model)
    redraw()
    assert old() is None  # the old model's GPU copy is gone
    assert on_main(lambda: _gpu()[1]._previews[name].entry.path).endswith("other.pzh")
    assert on_main(lambda: _gpu()[1]._previews[name].batch) is not None
    assert _textures() == baseline + 7  # the new model's only


def test_a_new_file_frees_every_texture(baseline, tmp_path):
    make_character(tmp_path)
    redraw()
    assert _textures() == baseline + 7
    on_main(lambda: bpy.ops.wm.read_homefile())
    assert on_main(lambda: len(_gpu()[1]._previews)) == 0
    assert _textures() == baseline


def test_undoing_the_switch_to_shade_from_model_frees_its_textures(baseline, tmp_path):
    name = make_character(tmp_path)

    def disable_and_push():
        bpy.data.objects[name].penumbra_visibility.enabled = False
        bpy.ops.ed.undo_push(message="before shading")
        bpy.data.objects[name].penumbra_visibility.enabled = True
        bpy.ops.ed.undo_push(message="shading")
        bpy.context.scene.frame_set(4)
    on_main(disable_and_push)
    redraw()
    assert _textures() == baseline + 7

    def undo():
        override = _view3d()
        if hasattr(bpy.context, "temp_override"):
            with bpy.context.temp_override(**override):
                bpy.ops.ed.undo()
        else:
            bpy.ops.ed.undo(override)
    on_main(undo)
    redraw()
    assert not on_main(lambda: bpy.data.objects[name].penumbra_visibility.enabled)
    assert on_main(lambda: name in _gpu()[1]._previews) is False
    assert _textures() == baseline


def test_a_topology_edit_stops_the_preview_and_says_why(baseline, tmp_path):
    name = make_character(tmp_path)
    redraw()
    assert _textures() == baseline + 7

    def edit():
        bpy.data.objects[name].data.vertices.add(1)
        bpy.context.scene.frame_set(bpy.context.scene.frame_current + 1)
        return bpy.context.scene.penumbra.visibility.gpu_preview_status
    status = on_main(edit)
    redraw()
    assert name in status and "vertices" in status, status
    assert on_main(lambda: name in _gpu()[1]._previews) is False
    assert _textures() == baseline


def test_what_the_viewport_shades_matches_the_attributes_with_shape_keys_and_another_deform(baseline, tmp_path):
    """The preview reads the evaluated mesh, so a shape key and a deform
    modifier after the armature shade as the CPU's attributes do."""
    name = make_character(tmp_path, brdf="PHONG")

    def deform():
        obj = bpy.data.objects[name]
        obj.shape_key_add(name="Basis")
        key = obj.shape_key_add(name="Bulge")
        for k, point in enumerate(key.data):
            point.co.x += 0.03 * ((k % 7) - 3)
        key.value = 0.8
        twist = obj.modifiers.new("Twist", "SIMPLE_DEFORM")
        twist.deform_method = "TWIST"
        twist.angle = 0.4
        bpy.context.scene.frame_set(7)
    on_main(deform)
    redraw()

    def compare():
        import numpy as np
        from penumbra.visibility import frame_shading
        scene = bpy.context.scene
        gpu_rgb, gpu_ao = _gpu()[1]._previews[name].batch.shade_offscreen()
        obj = bpy.data.objects[name]
        cpu_rgb, cpu_ao, _ = frame_shading.shade_object(obj, scene)
        cpu_rgb, cpu_ao = cpu_rgb.copy(), cpu_ao.copy()  # views of buffers the next shade reuses
        obj.modifiers["Twist"].show_viewport = False  # what the shading would be without the extra deform
        untwisted, _, _ = frame_shading.shade_object(obj, scene, bpy.context.evaluated_depsgraph_get())
        return (float(np.max(np.abs(np.maximum(gpu_rgb, 0.0) - cpu_rgb))),
                float(np.max(np.abs(np.clip(gpu_ao, 0.0, 1.0) - cpu_ao))), float(np.ptp(cpu_rgb)),
                float(np.max(np.abs(untwisted - cpu_rgb))))
    rgb_difference, ao_difference, spread, twist_effect = on_main(compare)
    assert rgb_difference <= 1e-3 and ao_difference <= 1e-3, (rgb_difference, ao_difference)
    assert spread > 0.1  # a shading that varies over the character was compared
    assert twist_effect > 1e-2  # and the extra deform changed it
