"""penumbra.build_light_rig inside real Blender: the rig it creates, its
keyframes and JSON, the World's Mapping rotation, bad input, and that the
rig reproduces the map's lighting (analytically and in a Cycles render)."""

import json
import math
import os
import warnings

import bpy
import mathutils
import numpy as np
import pytest

from bench.helpers.metrics import rel_rmse
from lights_scenes import (core_module, directions, ensure_nodes, rig_state, sky_and_sun,
                           solid_angles, world_with, write_map)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def _map_irradiance(img, normals):
    """Independent numpy reference: Σ L Ω max(0, n·ω)."""
    h, w = img.shape[:2]
    d = directions(h, w).reshape(-1, 3)
    flux = (img * solid_angles(h, w)[:, None, None]).reshape(-1, 3)
    return np.clip(normals @ d.T, 0, None) @ flux


def _sun_rgb(ob):
    """∫L dω a sun carries. Blender 4.x Cycles: a uniform cone of half-angle
    h whose facing irradiance is the strength, so ∫L dω = strength·2/(1+cos h);
    3.x: a disc whose ∫L dω is the strength (checked by the render tests
    below against Cycles itself). For a rig built for Cycles (target_renderer)."""
    rgb = np.array(ob.data.color) * ob.data.energy
    if bpy.app.version >= (4, 0, 0):
        rgb = rgb * 2.0 / (1.0 + math.cos(ob.data.angle / 2))
    return rgb


def _rig_irradiance(scene, normals):
    """Irradiance from the suns as Blender holds them at the current frame."""
    e = np.zeros((len(normals), 3))
    for ob in scene.penumbra.light_rig.collection.objects:
        if ob.type != "LIGHT":
            continue
        d = (ob.matrix_world.to_3x3() @ mathutils.Vector((0, 0, 1))).normalized()
        rgb = _sun_rgb(ob)
        e += np.clip(normals @ np.array(d), 0, None)[:, None] * rgb[None, :]
    return e


def test_rig_reproduces_the_maps_irradiance_and_is_updated_not_duplicated(addon, tmp_path):
    scene = addon
    scene.render.engine = "CYCLES"  # the rig as Cycles draws it (target_renderer follows the engine)
    img = sky_and_sun()
    path = write_map(str(tmp_path / "map.exr"), img)
    json_path = str(tmp_path / "rig.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=64, json_path=json_path) == {"FINISHED"}
    coll = scene.penumbra.light_rig.collection
    suns = [o for o in coll.objects if o.type == "LIGHT"]
    assert len(suns) == 64 and all(o.data.type == "SUN" for o in suns)
    assert sum(1 for o in coll.objects if o.type == "EMPTY") == 1
    normals = core_module().sh.fibonacci_directions(200)
    ref = _map_irradiance(img, normals)
    got = _rig_irradiance(scene, normals)
    rel = rel_rmse(got, ref)
    assert rel < 0.03, rel
    # Colour: the summed RGB is the map's integral per channel.
    total = (img * solid_angles(*img.shape[:2])[:, None, None]).sum(axis=(0, 1))
    rgb = sum(_sun_rgb(o) for o in suns)
    np.testing.assert_allclose(rgb, total, rtol=1e-4)
    # JSON beside: one frame, 64 lights, unit directions, same totals.
    doc = json.load(open(json_path))
    assert len(doc["frames"]) == 1 and len(doc["frames"][0]["lights"]) == 64
    np.testing.assert_allclose(sum(np.array(l["rgb"]) for l in doc["frames"][0]["lights"]), total, rtol=1e-4)
    # A rebuild with fewer lights updates the same collection.
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=20, json_path=json_path) == {"FINISHED"}
    assert len([c for c in bpy.data.collections if c.name.startswith("Penumbra Light Rig")]) == 1
    assert len([o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]) == 20
    assert len([o for o in bpy.data.objects if o.type == "LIGHT"]) == 20


def test_world_mapping_rotation_is_honoured(addon, tmp_path):
    scene = addon
    img = sky_and_sun(sky=0.0)
    path = write_map(str(tmp_path / "map.exr"), img)
    world_with(scene, path, rotation_z=math.radians(90))
    assert bpy.ops.penumbra.build_light_rig(count=8, json_path=str(tmp_path / "a.json")) == {"FINISHED"}
    suns = [o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
    strongest = max(suns, key=lambda o: o.data.energy)
    d = strongest.matrix_world.to_3x3() @ mathutils.Vector((0, 0, 1))
    # Mapping (POINT) looks the texture up at Rz(90°)·d, so the sun seen at map
    # direction s appears at Rz(−90°)·s.
    s = np.array([0.4, -0.3, 0.8]) / np.linalg.norm([0.4, -0.3, 0.8])
    expected = np.array([s[1], -s[0], s[2]])
    assert np.dot(np.array(d), expected) > math.cos(0.1)


def test_the_rig_json_is_fsynced_renamed_then_its_folder_fsynced(addon, tmp_path):
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun())
    json_path = str(tmp_path / "rig.json")
    core_module().testing.record_durable_steps()
    try:
        assert bpy.ops.penumbra.build_light_rig(filepath=path, count=4, json_path=json_path) == {"FINISHED"}
    finally:
        steps = core_module().testing.recorded_durable_steps()
    temporary = steps[0][len("fsync file "):]
    assert steps == [f"fsync file {temporary}", f"rename {temporary} -> {json_path}", f"fsync folder {tmp_path}"]
    assert os.path.dirname(temporary) == str(tmp_path) and sorted(os.listdir(tmp_path)) == ["map.exr", "rig.json"]


def _clear_images():
    for image in list(bpy.data.images):
        bpy.data.images.remove(image)


def _suns_rgb(scene):
    """∫L dω of each sun, by light index."""
    suns = sorted((o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"),
                  key=lambda o: o["penumbra_light_index"])
    return np.array([_sun_rgb(o) for o in suns])


def test_rig_colours_are_in_the_files_working_space(addon, tmp_path):
    """Light colours are read by Blender in its scene-linear space. Before 5.0
    that is the config's scene_linear role; Blender 5.0 made it a setting of
    each file (the working space: Linear Rec.709, Linear Rec.2020 or ACEScg),
    so a rig built in an ACEScg file holds the same light in ACEScg."""
    from penumbra import color
    scene = addon
    scene.render.engine = "CYCLES"  # the rig as Cycles draws it (target_renderer follows the engine)
    config = color.blender_config()
    img = sky_and_sun()
    img[..., 0] *= 0.6  # a colour that differs between the spaces
    path = write_map(str(tmp_path / "map.exr"), img)
    json_path = str(tmp_path / "rig.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=path, colorspace=config.scene_linear, count=16,
                                            json_path=json_path) == {"FINISHED"}
    assert color.working_space(config) == config.scene_linear  # a new file: the default working space
    assert json.load(open(json_path))["colorspace"] == config.scene_linear
    default = _suns_rgb(scene)
    total = (img * solid_angles(*img.shape[:2])[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(default.sum(axis=0), total, rtol=1e-4)
    if bpy.app.version < (5, 0, 0):
        return  # one scene-linear space per config: nothing else to compare
    _clear_images()  # Blender refuses to change the working space while an image is unsaved
    assert bpy.ops.wm.set_working_color_space(working_space="ACEScg") == {"FINISHED"}
    assert color.working_space(config) == "ACEScg"
    assert bpy.ops.penumbra.build_light_rig(filepath=path, colorspace=config.scene_linear, count=16,
                                            json_path=json_path) == {"FINISHED"}
    assert json.load(open(json_path))["colorspace"] == "ACEScg"
    expected = config.convert(default[None].astype(np.float32), config.scene_linear, "ACEScg")[0]
    np.testing.assert_allclose(_suns_rgb(scene), expected, rtol=1e-4, atol=1e-6)


def test_a_packed_float_world_gives_the_rig_its_file_gives(addon, tmp_path):
    """Blender keeps a float image's pixels in the working space (5.x converts
    a float file to it on load, whatever the image's colour space says), so a
    packed World image must give the rig its file gives, in every working
    space."""
    scene = addon
    img = sky_and_sun()
    img[..., 0] *= 0.6
    path = write_map(str(tmp_path / "map.exr"), img)
    spaces = ["Linear Rec.709", "ACEScg"] if bpy.app.version >= (5, 0, 0) else [None]
    # Region lights, light by light: the irradiance fit (on by default) is
    # not continuous in the map (two maps equal to 1e-4 can end in two
    # equally good arrangements), and the pixels, not the fit, are tested here.
    plain = dict(count=16, fit_irradiance=False)
    for space in spaces:
        if space is not None and space != bpy.data.colorspace.working_space:
            _clear_images()  # Blender refuses to change the working space while an image is unsaved
            assert bpy.ops.wm.set_working_color_space(working_space=space) == {"FINISHED"}
        world = world_with(scene, path)
        image = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment").image
        assert bpy.ops.penumbra.build_light_rig(json_path=str(tmp_path / "f.json"), **plain) == {"FINISHED"}
        from_file = _suns_rgb(scene)
        image.pack()
        assert image.packed_file is not None
        assert bpy.ops.penumbra.build_light_rig(json_path=str(tmp_path / "p.json"), **plain) == {"FINISHED"}
        np.testing.assert_allclose(_suns_rgb(scene), from_file, rtol=1e-4, atol=1e-6, err_msg=str(space))


def test_sequence_gives_linear_keyframes_without_flips(addon, tmp_path):
    scene = addon
    core = core_module()
    folder = tmp_path / "seq"
    folder.mkdir()
    img = sky_and_sun(sky=0.05)
    for i in range(6):
        core.image.write_exr(str(folder / f"sky_{i + 1:04d}.exr"),
                             core.lights.rotate_map_z(img, math.radians(10 * i)), half=False, colorspace="Linear")
    assert bpy.ops.penumbra.build_light_rig(filepath=str(folder / "sky_0001.exr"), count=12, frame_start=10,
                                            frame_end=40, json_path=str(tmp_path / "s.json")) == {"FINISHED"}
    from penumbra.lights.rig_objects import fcurve
    sun = next(o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT")
    fc = fcurve(sun, "rotation_quaternion", 0)
    assert [k.co[0] for k in fc.keyframe_points] == [10, 11, 12, 13, 14, 15]
    assert all(k.interpolation == "LINEAR" for k in fc.keyframe_points)
    quats = [[fcurve(sun, "rotation_quaternion", i).evaluate(f) for i in range(4)] for f in range(10, 16)]
    for a, b in zip(quats, quats[1:]):
        assert np.dot(a, b) > 0.0
    energy = fcurve(sun.data, "energy")
    assert len(energy.keyframe_points) == 6
    # Blender evaluates the keys: the strength at a frame is the key's value.
    scene.frame_set(12)
    assert abs(sun.data.energy - energy.keyframe_points[2].co[1]) < 1e-5
    doc = json.load(open(tmp_path / "s.json"))
    assert [f["frame"] for f in doc["frames"]] == [10, 11, 12, 13, 14, 15]


def test_invoke_without_an_event_loop_builds_the_rig_at_once(addon, tmp_path):
    """`blender -b` and the bpy modules have no event loop: Blender runs
    INVOKE_DEFAULT as execute, so a script that asks for the Build button's
    path gets its rig at once instead of a modal build that would never get
    a timer tick (the modal path itself: test_light_rig_window.py)."""
    from penumbra.lights import operators
    scene = addon
    core = core_module()
    folder = tmp_path / "seq"
    folder.mkdir()
    for i in range(3):
        core.image.write_exr(str(folder / f"sky_{i + 1:04d}.exr"),
                             core.lights.rotate_map_z(sky_and_sun(h=16, w=32), math.radians(10 * i)),
                             half=False, colorspace="Linear")
    assert bpy.ops.penumbra.build_light_rig("INVOKE_DEFAULT", filepath=str(folder / "sky_0001.exr"), count=4,
                                            frame_end=3, json_path=str(tmp_path / "i.json")) == {"FINISHED"}
    assert operators.running_builds() == []
    suns = [o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
    assert len(suns) == 4
    assert len(json.load(open(tmp_path / "i.json"))["frames"]) == 3


def test_bad_input_reports_and_changes_nothing(addon, tmp_path):
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun())
    for kwargs, words in (({"filepath": path, "colorspace": "No Such Space"}, "colour space"),
                          ({"filepath": path, "count": 64 * 128 + 1}, "exceeds"),
                          ({"filepath": str(tmp_path / "missing.exr")}, "missing"),
                          ({}, "World")):
        with pytest.raises(RuntimeError, match=words):
            bpy.ops.penumbra.build_light_rig(json_path=str(tmp_path / "x.json"), **kwargs)
    assert not [c for c in bpy.data.collections if c.name.startswith("Penumbra Light Rig")]
    assert not os.path.exists(tmp_path / "x.json")
    # A count below the core's minimum (1) cannot reach the operator: the property clamps it.
    assert bpy.ops.penumbra.build_light_rig.get_rna_type().properties["count"].hard_min == 1


def test_a_blend_relative_source_gives_no_warning(addon, tmp_path):
    """Blender 5.x warns (RuntimeWarning, '... does not support blend
    relative "//" prefix') when a path property without
    PATH_SUPPORTS_BLEND_RELATIVE is given "//...", as users and scripts give
    the Source (compat.BLEND_RELATIVE_PATH). 3.4 and 4.5 never warn."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(RuntimeError, match="missing"):
            bpy.ops.penumbra.build_light_rig(filepath="//missing.exr", json_path="//x.json")
    assert [str(w.message) for w in caught if "//" in str(w.message)] == []


def _render_plane(scene, tmp_path, name):
    """Mean pixel of a white diffuse plane seen from above (32x32, 64 spp)."""
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 64
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(tmp_path / name)
    bpy.ops.render.render(write_still=True)
    pixels = core_module().image.read(str(tmp_path / name) + ".exr")
    return pixels.reshape(-1, 3).mean(axis=0)


def _plane_and_camera(scene):
    """A white diffuse plane facing up and an orthographic camera above it."""
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    mat = bpy.data.materials.new("White")
    nt = ensure_nodes(mat)
    for n in list(nt.nodes):
        if n.type != "OUTPUT_MATERIAL":
            nt.nodes.remove(n)
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    nt.links.new(diffuse.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
    plane.data.materials.append(mat)
    cam_data = bpy.data.cameras.new("Cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = 1.0
    cam = bpy.data.objects.new("Cam", cam_data)
    cam.location = (0, 0, 3)
    scene.collection.objects.link(cam)
    scene.camera = cam
    plane.visible_camera = True


def _black_world(scene):
    black = bpy.data.worlds.new("Black")
    ensure_nodes(black).nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = black


def test_cycles_render_lit_by_the_rig_matches_the_world(addon, tmp_path):
    scene = addon
    img = sky_and_sun(radius=0.2, sun_radiance=20.0)
    path = write_map(str(tmp_path / "map.exr"), img)
    world_with(scene, path)
    _plane_and_camera(scene)
    world_lit = _render_plane(scene, tmp_path, "world")
    assert bpy.ops.penumbra.build_light_rig(count=64, json_path=str(tmp_path / "r.json")) == {"FINISHED"}
    _black_world(scene)
    rig_lit = _render_plane(scene, tmp_path, "rig")
    # Lambertian plane facing up: pixel = albedo · E(up) / π. Both renders
    # must agree (Monte Carlo noise at 64 spp × 1024 pixels is well under 1%).
    expected = 0.8 * _map_irradiance(img, np.array([[0.0, 0.0, 1.0]]))[0] / math.pi
    np.testing.assert_allclose(world_lit, expected, rtol=0.04)
    np.testing.assert_allclose(rig_lit, world_lit, rtol=0.04)


def test_a_wide_sun_carries_its_regions_light_in_cycles(addon, tmp_path):
    """One light for a uniform cap of half-angle 40° at the zenith: a sun of
    about 80°. The plane lit by it must match the plane lit by the World
    (Cycles' own evaluation of the map). Before the strength was scaled by
    (1 + cos h)/2, Blender 4.x rendered it ~13% too bright."""
    scene = addon
    h, w = 64, 128
    img = np.zeros((h, w, 3), np.float32)
    img[directions(h, w)[..., 2] >= math.cos(math.radians(40))] = (2.0, 1.5, 1.0)
    path = write_map(str(tmp_path / "cap.exr"), img)
    world_with(scene, path)
    _plane_and_camera(scene)
    world_lit = _render_plane(scene, tmp_path, "world")
    assert bpy.ops.penumbra.build_light_rig(count=1, json_path=str(tmp_path / "r.json")) == {"FINISHED"}
    sun = next(o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT")
    assert 70 < math.degrees(sun.data.angle) < 85, math.degrees(sun.data.angle)
    _black_world(scene)
    rig_lit = _render_plane(scene, tmp_path, "rig")
    expected = 0.8 * _map_irradiance(img, np.array([[0.0, 0.0, 1.0]]))[0] / math.pi
    np.testing.assert_allclose(world_lit, expected, rtol=0.03)
    np.testing.assert_allclose(rig_lit, world_lit, rtol=0.04)


def test_a_one_pixel_region_gives_a_sun_that_lights(addon, tmp_path):
    """A region of one map cell has an RMS radius of rounding noise
    (~1e-16 rad). Written as the sun's angle, Cycles (3.4 and 4.5) renders
    such a sun black (its cone pdf overflows); it must be written as 0."""
    from penumbra.lights import rig_objects
    scene = addon
    _plane_and_camera(scene)
    _black_world(scene)
    d = np.array([0.3, 0.0, 1.0]) / math.hypot(0.3, 1.0)
    rig = {"slots": 1, "rgb": np.array([[[2.0, 2.0, 2.0]]]), "directions": d[None, None, :],
           "spread": np.array([[5.7e-17]]), "power": np.array([[2.0]])}
    write = rig_objects.write_rig(scene, scene.penumbra.light_rig, rig, 1, False)
    write.commit()
    lit = _render_plane(scene, tmp_path, "tiny")
    np.testing.assert_allclose(lit, 0.8 * 2.0 * d[2] / math.pi, rtol=0.01)
    sun = next(o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT")
    assert sun.data.angle == 0.0


def test_the_suns_written_have_the_cores_angle_and_carry_their_lights_flux(addon):
    """The add-on's suns against the core's rule (core/lights/sun_irradiance.hpp,
    what the irradiance fit assumes): angle from the spread, clipped to π and 0
    when tiny, and a strength that makes each sun carry its light's ∫L dω as
    this Blender's Cycles draws it (_sun_rgb, the conventions measured in
    docs/lights.md), with the cone from 4.0 on."""
    from penumbra.lights import rig_objects
    scene = addon
    lights = core_module().lights
    spread = np.array([[0.0, 5.7e-17, 0.02, 0.3, 0.9, 3.0]])
    slots = spread.shape[1]
    rgb = np.linspace(0.5, 3.0, 3 * slots).reshape(1, slots, 3)
    directions = np.tile([0.0, 0.6, 0.8], (1, slots, 1))
    rig = {"slots": slots, "rgb": rgb, "directions": directions, "spread": spread, "power": rgb.mean(axis=2)}
    rig_objects.write_rig(scene, scene.penumbra.light_rig, rig, 1, False).commit()
    suns = sorted((o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"),
                  key=lambda o: o[rig_objects.INDEX_KEY])
    expected_model = "BLENDER4_CONE" if bpy.app.version >= (4, 0, 0) else "BLENDER3_DISC"
    assert rig_objects.sun_model().name == expected_model
    angle = np.array([o.data.angle for o in suns])
    np.testing.assert_allclose(angle, lights.sun_angle(spread[0]), rtol=1e-6, atol=0)  # float32 in Blender
    assert angle[0] == angle[1] == 0.0 and angle[-1] == pytest.approx(math.pi)
    strength = rgb[0].max(axis=1) * lights.sun_strength_per_flux(angle, expected_model)
    np.testing.assert_allclose([o.data.energy for o in suns], strength, rtol=1e-6)
    np.testing.assert_allclose([_sun_rgb(o) for o in suns], rgb[0], rtol=1e-5)


def _fail_after(monkeypatch, n):
    """Makes the add-on's per-sun writer raise after `n` suns."""
    from penumbra.lights import rig_objects
    original = rig_objects._write_sun
    calls = []

    def failing(ob, k, values):
        if len(calls) >= n:
            raise RuntimeError("injected failure while writing the rig")
        calls.append(k)
        original(ob, k, values)

    monkeypatch.setattr(rig_objects, "_write_sun", failing)
    return calls


def test_a_failure_half_way_leaves_the_rig_and_json_as_they_were(addon, tmp_path, monkeypatch):
    scene = addon
    core = core_module()
    json_path = str(tmp_path / "rig.json")
    for name, sun in (("a", (0.4, -0.3, 0.8)), ("b", (-0.5, 0.2, 0.6))):
        folder = tmp_path / name
        folder.mkdir()
        img = sky_and_sun(h=32, w=64, sun=sun, sky=0.05)
        for i in range(3):
            core.image.write_exr(str(folder / f"sky_{i + 1:04d}.exr"),
                                 core.lights.rotate_map_z(img, math.radians(15 * i)), half=False, colorspace="Linear")
    # A keyframed rig of 6 suns is in the file.
    assert bpy.ops.penumbra.build_light_rig(filepath=str(tmp_path / "a" / "sky_0001.exr"), count=6,
                                            json_path=json_path) == {"FINISHED"}
    before = rig_state(scene, json_path)
    assert len([o for o in before["suns"].values() if "light" in o]) == 6 and before["json"]
    # A rebuild with another source and 10 suns dies after 4 suns: new suns,
    # new keys, the JSON and the preview must all stay as they were.
    calls = _fail_after(monkeypatch, 4)
    with pytest.raises(RuntimeError, match="injected failure"):
        bpy.ops.penumbra.build_light_rig(filepath=str(tmp_path / "b" / "sky_0001.exr"), count=10,
                                         json_path=json_path)
    assert len(calls) == 4
    assert rig_state(scene, json_path) == before
    assert not os.path.exists(json_path + ".tmp")
    # The same rebuild without the failure does change the rig (the state
    # comparison above can see a change).
    monkeypatch.undo()
    assert bpy.ops.penumbra.build_light_rig(filepath=str(tmp_path / "b" / "sky_0001.exr"), count=10,
                                            json_path=json_path) == {"FINISHED"}
    after = rig_state(scene, json_path)
    assert after != before and len([o for o in after["suns"].values() if "light" in o]) == 10


def test_a_failure_on_a_new_rig_leaves_nothing_behind(addon, tmp_path, monkeypatch):
    scene = addon
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(h=32, w=64))
    json_path = str(tmp_path / "rig.json")
    before = rig_state(scene, json_path)
    _fail_after(monkeypatch, 2)
    with pytest.raises(RuntimeError, match="injected failure"):
        bpy.ops.penumbra.build_light_rig(filepath=path, count=5, json_path=json_path)
    assert rig_state(scene, json_path) == before
    assert scene.penumbra.light_rig.collection is None
    assert not any(o.name.startswith("Penumbra") for o in bpy.data.objects)


def _strongest_direction(scene):
    suns = [o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
    dirs = np.array([tuple(o.matrix_world.to_3x3() @ mathutils.Vector((0, 0, 1))) for o in suns])
    energy = np.array([o.data.energy for o in suns])
    return dirs, energy, dirs[int(np.argmax(energy))]


def test_fisheye_input_gives_upper_hemisphere_lights_and_places_a_spot(addon, tmp_path):
    # Equidistant fisheye looking up, 128 px, image top = +Y, right = -X
    # (docs/lights.md), built here from that description, not from core code.
    n, R = 128, 64.0
    theta, phi = math.radians(40), math.radians(30)
    d = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    rho = theta / (math.pi / 2) * R
    col = n / 2 + rho * (-d[0]) / math.sin(theta)
    row = n / 2 - rho * d[1] / math.sin(theta)
    y, x = np.mgrid[0:n, 0:n] + 0.5
    img = np.zeros((n, n, 3), np.float32)
    img[np.hypot(x - n / 2, y - n / 2) < R] = 0.02
    img[(np.abs(x - col) < 1.6) & (np.abs(y - row) < 1.6)] = 2000.0
    path = write_map(str(tmp_path / "fisheye.exr"), img)
    assert bpy.ops.penumbra.build_light_rig(filepath=path, mapping="FISHEYE", count=24,
                                            json_path=str(tmp_path / "f.json")) == {"FINISHED"}
    dirs, energy, strongest = _strongest_direction(addon)
    assert len(dirs) == 24
    assert dirs[:, 2].min() > -1e-6, dirs[:, 2].min()  # nothing below the horizon
    angle = math.degrees(math.acos(min(1.0, float(np.dot(strongest, d)))))
    assert angle < 3.0, angle


def test_mirror_ball_input_places_a_spot(addon, tmp_path):
    # Mirror ball photographed looking along +Y: the ball's normal at image
    # point (u, v) (right, up, unit disc) is (u, -sqrt(1 - u² - v²), v); the
    # view ray (0, 1, 0) reflects to the direction seen there.
    n, R = 128, 64.0
    d = np.array([0.5, -0.6, 0.62])
    d /= np.linalg.norm(d)
    normal = d - np.array([0.0, 1.0, 0.0])
    normal /= np.linalg.norm(normal)
    col, row = n / 2 + normal[0] * R, n / 2 - normal[2] * R
    y, x = np.mgrid[0:n, 0:n] + 0.5
    img = np.zeros((n, n, 3), np.float32)
    img[np.hypot(x - n / 2, y - n / 2) < R] = 0.5  # a sky bright enough to draw some lights everywhere
    img[(np.abs(x - col) < 1.6) & (np.abs(y - row) < 1.6)] = 2000.0
    path = write_map(str(tmp_path / "ball.exr"), img)
    assert bpy.ops.penumbra.build_light_rig(filepath=path, mapping="MIRROR_BALL", count=24,
                                            json_path=str(tmp_path / "m.json")) == {"FINISHED"}
    dirs, energy, _ = _strongest_direction(addon)
    assert dirs[:, 2].min() < -0.2  # a full-sphere input lights from below too
    # The uniform sky's first moment ∫ L ω dω is zero, so the suns' summed
    # flux vector points at the spot.
    resultant = (energy[:, None] * dirs).sum(axis=0)
    resultant /= np.linalg.norm(resultant)
    angle = math.degrees(math.acos(min(1.0, float(np.dot(resultant, d)))))
    assert angle < 4.0, angle


def test_shadow_limit_gives_shadows_to_the_eight_strongest(addon, tmp_path):
    scene = addon
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(h=32, w=64, sky=0.2))
    json_path = str(tmp_path / "s.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=20, limit_shadows=True,
                                            json_path=json_path) == {"FINISHED"}
    suns, strongest, _ = _suns_by_strength(scene, json_path)
    assert sorted(k for k, o in suns.items() if o.data.use_shadow) == sorted(strongest[:8])
    # Without it every sun casts a shadow (Cycles: EEVEE Legacy's own choice is
    # test_a_rig_for_eevee_legacy_picks_the_eight_suns_it_shadows).
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=20, limit_shadows=False, target_renderer="CYCLES",
                                            json_path=json_path) == {"FINISHED"}
    assert all(o.data.use_shadow for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT")


def _suns_by_strength(scene, json_path):
    """The rig's suns by index, and their indices strongest first (mean
    luminance over the shot, from the JSON's own numbers) with their powers."""
    from penumbra.lights.rig_objects import INDEX_KEY
    suns = {int(o[INDEX_KEY]): o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"}
    doc = json.load(open(json_path))
    y = np.array([0.2126, 0.7152, 0.0722])
    power = np.mean([[np.dot(l["rgb"], y) for l in f["lights"]] for f in doc["frames"]], axis=0)
    return suns, [int(k) for k in np.argsort(-power, kind="stable")], power


def test_shadow_budget_gives_shadows_to_the_strongest_sharp_suns(addon, tmp_path):
    """shadow_budget N: the N strongest of the suns narrow enough to cast an
    umbra behind an occluder one occluder-width above the receiver (angle at
    most 2·atan(1/2)); a wider sun, however strong, keeps no shadow."""
    scene = addon
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(h=32, w=64, sky=0.2))
    json_path = str(tmp_path / "s.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=20, shadow_budget=3,
                                            json_path=json_path) == {"FINISHED"}
    suns, strongest, power = _suns_by_strength(scene, json_path)
    umbra = 2.0 * math.atan(0.5)
    sharp = [k for k in strongest if suns[k].data.angle <= umbra]
    shadowed = sorted(k for k, o in suns.items() if o.data.use_shadow)
    assert shadowed == sorted(sharp[:3])
    # The map makes the rule matter: a wide sun outranks a shadowed one.
    assert any(o.data.angle > umbra and power[k] > min(power[shadowed]) for k, o in suns.items())


def test_a_rig_for_eevee_legacy_picks_the_eight_suns_it_shadows(addon, tmp_path):
    """EEVEE Legacy draws the shadows of the first 8 suns it meets and no
    more: a rig for it gives them to the 8 strongest sharp suns (as a budget
    of 8) and says so, unless it has no more than 8 suns. EEVEE Next and
    Cycles draw every sun's shadow, so there every sun keeps one."""
    scene = addon
    path = write_map(str(tmp_path / "map.exr"), sky_and_sun(h=32, w=64, sky=0.2))
    json_path = str(tmp_path / "s.json")
    legacy = bpy.app.version < (4, 2, 0)
    for count in (20, 6):
        assert bpy.ops.penumbra.build_light_rig(filepath=path, count=count, target_renderer="EEVEE",
                                                json_path=json_path) == {"FINISHED"}
        suns, strongest, _ = _suns_by_strength(scene, json_path)
        shadowed = sorted(k for k, o in suns.items() if o.data.use_shadow)
        report = scene.penumbra.light_rig.last_report
        if legacy and count > 8:
            umbra = 2.0 * math.atan(0.5)
            picked = sorted([k for k in strongest if suns[k].data.angle <= umbra][:8])
            assert shadowed == picked and "EEVEE Legacy draws at most 8 sun shadows" in report, report
            # Legacy left alone would shadow the first 8 suns created (slots 0-7).
            assert picked != list(range(8))
        else:
            assert shadowed == sorted(suns) and "EEVEE Legacy" not in report, report
    assert bpy.ops.penumbra.build_light_rig(filepath=path, count=20, target_renderer="CYCLES",
                                            json_path=json_path) == {"FINISHED"}
    assert all(o.data.use_shadow for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT")


def test_fit_irradiance_makes_the_suns_as_drawn_closer_to_the_maps_irradiance(addon, tmp_path):
    """The operator's Fit Irradiance reaches the core: the suns it writes, drawn
    as this Blender draws a sun of their angle (disc in 3.x, cone in 4.x;
    core/lights/sun_irradiance.hpp), light a diffuse surface closer to the
    map's own irradiance (numpy) than the unfitted rig's suns."""
    scene = addon
    img = sky_and_sun(sun_radiance=400.0, radius=0.08)
    path = write_map(str(tmp_path / "map.exr"), img)
    normals = core_module().sh.fibonacci_directions(500)
    ref = _map_irradiance(img, normals)
    model = "BLENDER4_CONE" if bpy.app.version >= (4, 0, 0) else "BLENDER3_DISC"
    errors = {}
    for fit in (False, True):
        assert bpy.ops.penumbra.build_light_rig(filepath=path, count=16, fit_irradiance=fit, target_renderer="CYCLES",
                                                json_path=str(tmp_path / f"{fit}.json")) == {"FINISHED"}
        suns = [o for o in scene.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
        d = np.array([(o.matrix_world.to_3x3() @ mathutils.Vector((0, 0, 1))).normalized() for o in suns])
        rgb = np.array([_sun_rgb(o) for o in suns])
        spread = np.array([o.data.angle for o in suns]) / (2.0 * math.sqrt(2.0))  # the add-on's angle rule, inverted
        got = core_module().lights.irradiance(d, rgb, normals, spread=spread, sun_model=model)
        errors[fit] = rel_rmse(got, ref)
    assert errors[True] < 0.7 * errors[False], errors
