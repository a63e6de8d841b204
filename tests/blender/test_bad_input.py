"""Operators given bad input, inside Blender 3.4, 4.5 and 5.2.

Each test builds a small scene, provokes one bad input, runs the operator as
a click in the UI does (EXEC with an undo step; from a script `bpy.ops`
raises RuntimeError carrying the error report) or, where the bad input can
only arrive while a modal operator runs, drives the operator's own invoke()
and modal() code, and checks three things:

(a) the report: a refused input gives {'CANCELLED'} with an error naming the
    problem and what to do; an input the tool can use (a 1×1 map, pixels it
    zeroes) finishes and its report says what was done;
(b) the scene is as it was: data-blocks, objects, modifiers, collections,
    node trees and their links, mesh attributes (values included), the rig
    JSON and the lookup folder byte for byte;
(c) undo still works: undo takes back exactly the step before the operator
    (or the operator's own step when it finished) and redo brings it back.

A process that crashed would end the run, so every test that gets to its end
also shows Blender did not crash.

Bad input tested elsewhere and not repeated here: a mesh without armature,
another mesh's model, a renamed bone, inward normals, a topology-changing
modifier at bake time (test_visibility.py); a colour space, light count or
source file that is wrong, a failure half-way through writing the rig
(test_lights.py); a node that is not a ramp, NaN ramp colours, no material,
a linked material (test_colormap.py)."""

import hashlib
import json
import math
import os
import re
import types

import bmesh
import bpy
import numpy as np
import pytest

from penumbra import native
from penumbra.colormap import node_groups
from penumbra.colormap import operators as colormap_operators
from penumbra.lights import operators as light_operators
from penumbra.visibility import frame_shading

from colormap_scenes import make_ramp_material, plane_with
from lights_scenes import rig_state, sky_and_sun, solid_angles, world_with, write_map
from visibility_character_scenes import attribute, bake_op, character, uniform_world


# What a failed operator must leave as it was ---------------------------------------

_KINDS = ("objects", "meshes", "armatures", "collections", "materials", "node_groups", "images", "lights",
          "actions", "worlds", "cameras")
_VALUE_PROPERTY = {"FLOAT": "value", "FLOAT_COLOR": "color", "FLOAT_VECTOR": "vector", "INT": "value"}


def _digest(array):
    return hashlib.sha1(np.ascontiguousarray(array).tobytes()).hexdigest()


def _mesh_state(mesh):
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    attributes = []
    for a in mesh.attributes:
        if a.name.startswith("."):  # Blender's internal layers come and go with edits and undo
            continue
        entry = [a.name, a.domain, a.data_type]
        prop = _VALUE_PROPERTY.get(a.data_type)
        if prop is not None:
            width = {"color": 4, "vector": 3}.get(prop, 1)
            values = np.empty(len(a.data) * width, np.int32 if a.data_type == "INT" else np.float32)
            a.data.foreach_get(prop, values)
            entry.append(_digest(values))
        attributes.append(tuple(entry))
    return (len(mesh.vertices), len(mesh.edges), len(mesh.polygons), len(mesh.loops), _digest(co),
            sorted(attributes))


def _tree_state(tree):
    if tree is None:
        return None
    nodes = sorted((n.name, n.bl_idname, n.mute, n.label, tuple(round(v, 3) for v in n.location),
                    getattr(getattr(n, "image", None), "name", None),
                    getattr(getattr(n, "node_tree", None), "name", None)) for n in tree.nodes)
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    return nodes, links


def _action_name(id_block):
    anim = id_block.animation_data
    return anim.action.name if anim is not None and anim.action is not None else None


def scene_state():
    """The file's state, read by name (undo replaces every data-block, so
    nothing may be held across it). A mesh object's run-time `status` is left
    out on purpose: a failed apply_visibility writes its error there for the
    panel, which is the report, not a change of the scene."""
    state = {kind: sorted(b.name for b in getattr(bpy.data, kind)) for kind in _KINDS}
    for ob in bpy.data.objects:
        entry = (ob.type, ob.data.name if ob.data is not None else None, ob.parent.name if ob.parent else None,
                 [(m.name, m.type, getattr(getattr(m, "object", None), "name", None)) for m in ob.modifiers],
                 sorted(c.name for c in ob.users_collection), [s.material.name if s.material else None
                                                               for s in ob.material_slots],
                 tuple(round(v, 5) for v in ob.location), _action_name(ob))
        settings = getattr(ob, "penumbra_visibility", None)
        if settings is not None and ob.type == "MESH":
            entry += (settings.model_path, settings.report, settings.enabled)
        state["object " + ob.name] = entry
    for mesh in bpy.data.meshes:
        state["mesh " + mesh.name] = _mesh_state(mesh)
    for coll in bpy.data.collections:
        state["collection " + coll.name] = (sorted(o.name for o in coll.objects),
                                            sorted(c.name for c in coll.children))
    for light in bpy.data.lights:
        state["light " + light.name] = (light.type, round(light.energy, 6), tuple(round(v, 6) for v in light.color),
                                        round(getattr(light, "angle", 0.0), 6), light.use_shadow,
                                        _action_name(light))
    for kind in ("materials", "worlds", "node_groups"):
        for block in getattr(bpy.data, kind):
            state[f"{kind} {block.name}"] = _tree_state(block if kind == "node_groups" else block.node_tree)
    for image in bpy.data.images:
        state["image " + image.name] = (image.source, image.filepath)
    scene = bpy.context.scene
    state["scene"] = (sorted(c.name for c in scene.collection.children),
                      sorted(o.name for o in scene.collection.objects),
                      scene.world.name if scene.world else None, scene.camera.name if scene.camera else None,
                      scene.frame_current)
    if getattr(scene, "penumbra", None) is not None:
        coll = scene.penumbra.light_rig.collection
        state["light rig"] = (coll.name if coll is not None else None, scene.penumbra.light_rig.last_report)
    return state


def folder_files(folder):
    """{relative path: bytes} of every file under `folder`."""
    out = {}
    for root, _, names in os.walk(str(folder)):
        for name in names:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                out[os.path.relpath(path, str(folder))] = f.read()
    return out


# Undo -------------------------------------------------------------------------------

MARKER = "Penumbra undo marker"


def undo_checkpoint():
    """Pushes the scene as built, then one more step (an empty added, as a
    user's last edit before the operator). Returns (state one step back,
    state now)."""
    bpy.ops.ed.undo_push(message="scene built")
    previous = scene_state()
    bpy.context.scene.collection.objects.link(bpy.data.objects.new(MARKER, None))
    bpy.ops.ed.undo_push(message="marker added")
    return previous, scene_state()


def assert_undo_works(previous, current):
    """Undo gives `previous` (the state one step back), redo `current`. A failed
    operator pushes no step, so undo takes back the marker; a finished one
    pushed its own step, which undo takes back."""
    assert scene_state() == current
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert scene_state() == previous
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert scene_state() == current


def refused(operator, *words, **properties):
    """Runs `operator` as a click in the UI does and returns its error report;
    fails unless it is refused with an error containing every word (regular
    expressions, case-insensitive)."""
    with pytest.raises(RuntimeError) as error:
        operator("EXEC_DEFAULT", True, **properties)
    message = str(error.value)
    for word in words:
        assert re.search(word, message, re.IGNORECASE), (word, message)
    return message


def finished(operator, capfd, **properties):
    """Runs `operator` as a click in the UI does; returns what it reported
    (Blender prints reports in background mode)."""
    capfd.readouterr()
    assert operator("EXEC_DEFAULT", True, **properties) == {"FINISHED"}
    out, err = capfd.readouterr()
    return out + err


# Modal operators --------------------------------------------------------------------
# Background Blender runs 'INVOKE_DEFAULT' as execute (there is no event), so
# the window in which a modal operator waits for its worker (and a script, a
# timer or another window may change the scene) cannot be opened with
# bpy.ops. These stand-ins run the operator's own invoke() and modal() code
# with the parts of the UI they use.

class _WindowManager:
    def __init__(self):
        self.timers, self.handlers, self.progress = [], [], None

    def event_timer_add(self, time_step, window=None):
        timer = object()
        self.timers.append(timer)
        return timer

    def event_timer_remove(self, timer):
        self.timers.remove(timer)

    def modal_handler_add(self, operator):
        self.handlers.append(operator)
        return True

    def progress_begin(self, low, high):
        self.progress = low

    def progress_update(self, value):
        self.progress = value

    def progress_end(self):
        self.progress = None


class _UIContext:
    """bpy.context with a window manager that records timers and progress."""

    def __init__(self):
        self.window_manager = _WindowManager()
        self.window = self.area = self.workspace = None

    def __getattr__(self, name):
        return getattr(bpy.context, name)


class _Properties:
    def __init__(self, given):
        self._given = given

    def is_property_set(self, name):
        return name in self._given


def stand_in(cls, **given):
    """An object running `cls`'s own methods, with its properties at their
    defaults or `given`, recording its reports."""
    mixed_in = [klass for klass in reversed(cls.__mro__) if not issubclass(bpy.types.Operator, klass)]
    methods = {k: v for klass in mixed_in for k, v in vars(klass).items()  # with modal_job.JobOperator's
               if isinstance(v, types.FunctionType)}

    def report(self, kinds, message):
        self.reports.append((set(kinds), message))
    op = type(f"StandIn_{cls.__name__}", (), dict(methods, report=report))()
    op.reports = []
    category, name = cls.bl_idname.split(".")
    for prop in getattr(getattr(bpy.ops, category), name).get_rna_type().properties:
        if prop.identifier != "rna_type":
            setattr(op, prop.identifier, given.get(prop.identifier, getattr(prop, "default", None)))
    op.properties = _Properties(given)
    return op


def run_modal(op, context, between=None):
    """invoke(), then `between()` (the change made while the operator runs),
    then TIMER events until modal() ends. Returns modal()'s result."""
    result = op.invoke(context, types.SimpleNamespace(type="NONE"))
    assert result == {"RUNNING_MODAL"}, op.reports
    if between is not None:
        between()
    for _ in range(10000):
        run = getattr(op, "_modal_job", None)  # modal_job.invoke's run: join its worker
        if run is not None and run.thread is not None:
            run.thread.join()
        result = op.modal(context, types.SimpleNamespace(type="TIMER"))
        if result != {"RUNNING_MODAL"}:
            break
    wm = context.window_manager
    assert wm.timers == [] and wm.progress is None  # the UI is left as it was
    return result


def errors_of(op):
    return " | ".join(message for kinds, message in op.reports if "ERROR" in kinds)


# Visibility: a model file that is damaged --------------------------------------------

def _flip(offset, bit):
    def corrupt(data):
        data = bytearray(data)
        data[offset if offset >= 0 else len(data) + offset] ^= 1 << bit
        return bytes(data)
    return corrupt


# Header: magic (0..7), format version (8..11), reserved (12..15), payload
# size (16..23), payload checksum (24..31) (core/visibility/model_file.cpp).
CORRUPTIONS = {
    "truncated": (lambda data: data[: len(data) // 2], "truncated"),
    "magic bit": (_flip(0, 1), "not a Penumbra visibility file"),
    "version bit": (_flip(8, 1), "format version"),
    "size bit": (_flip(17, 0), "truncated|extra bytes"),
    "checksum bit": (_flip(24, 5), "checksum mismatch"),
    "payload bit": (_flip(-1000, 3), "checksum mismatch"),
}


def baked_character(tmp_path, **bake_settings):
    """The test character with a fresh model, applied once (so the run time
    holds it, as after a user's first Apply); every vertex has attributes a
    failed apply must keep."""
    obj, rig = character(bpy.context.scene)
    uniform_world(bpy.context.scene, (0.5, 1.0, 2.0))
    settings = dict(frame_step=4, rays=32)
    settings.update(bake_settings)
    assert bake_op(tmp_path, **settings) == {"FINISHED"}
    assert bpy.ops.penumbra.apply_visibility() == {"FINISHED"}
    return obj, rig


def assert_handler_reports(obj, *words):
    """On a frame change the handler must not raise into Blender: it writes
    the problem on the object, where the panel shows it."""
    obj.penumbra_visibility.enabled = True
    bpy.context.scene.frame_set(bpy.context.scene.frame_current + 1)
    for word in words:
        assert re.search(word, obj.penumbra_visibility.status, re.IGNORECASE), \
            (word, obj.penumbra_visibility.status)


@pytest.mark.parametrize("corruption", sorted(CORRUPTIONS))
def test_damaged_model_file_is_refused_and_nothing_changes(addon, tmp_path, corruption):
    obj, rig = baked_character(tmp_path)
    corrupt, why = CORRUPTIONS[corruption]
    path = obj.penumbra_visibility.model_path
    with open(path, "rb") as f:
        data = f.read()
    with open(path, "wb") as f:
        f.write(corrupt(data))
    frame_shading.forget()  # as when the .blend is opened again
    previous, before = undo_checkpoint()
    message = refused(bpy.ops.penumbra.apply_visibility, why, "model.pzh", "bake .* again")
    assert scene_state() == before
    assert obj.penumbra_visibility.status and obj.penumbra_visibility.status in message  # shown in the panel
    name = obj.name
    assert_undo_works(previous, before)
    assert_handler_reports(bpy.data.objects[name], why)


# Visibility: the mesh or the armature changed after the bake ----------------------------

def _edit_mesh(obj, what):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    if what == "face":
        bmesh.ops.delete(bm, geom=[next(iter(bm.faces))], context="FACES_ONLY")
    elif what == "vertex":
        bmesh.ops.delete(bm, geom=[next(iter(bm.verts))], context="VERTS")
    else:  # the edge between two quads turned: every count stays, the faces change
        edge = next(e for e in bm.edges if len(e.link_faces) == 2 and all(len(f.verts) == 4 for f in e.link_faces))
        bmesh.ops.rotate_edges(bm, edges=[edge], use_ccw=False)
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


# edit -> (the words the error must contain, whether the model is still held
# from an Apply before the edit).
TOPOLOGY_EDITS = {
    "face deleted, model held": ("another topology.*undo the edit, or bake again", True),
    "face deleted, file reopened": ("another topology.*undo the edit, or bake again", False),
    "vertex deleted, model held": ("988 vertices.*987.*undo the edit, or bake again", True),
    "edge rotated, model held": ("another topology.*undo the edit, or bake again", True),
    "subdivision added": ("after its modifiers.*disable Subdivision", True),
}


@pytest.mark.parametrize("edit", sorted(TOPOLOGY_EDITS))
def test_mesh_whose_topology_changed_since_the_bake_is_refused(addon, tmp_path, edit):
    obj, rig = baked_character(tmp_path)
    assert len(obj.data.vertices) == 988  # the character at detail 1
    words, held = TOPOLOGY_EDITS[edit]
    counts = (len(obj.data.vertices), len(obj.data.polygons), len(obj.data.loops))
    if edit.startswith("face"):
        _edit_mesh(obj, "face")  # one face fewer, every vertex kept
        assert len(obj.data.vertices) == 988
    elif edit.startswith("vertex"):
        _edit_mesh(obj, "vertex")
    elif edit.startswith("edge"):
        _edit_mesh(obj, "edge")
        assert (len(obj.data.vertices), len(obj.data.polygons), len(obj.data.loops)) == counts
    else:
        obj.modifiers.new("Subdivision", "SUBSURF")
    if not held:
        frame_shading.forget()
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.apply_visibility, words)
    assert scene_state() == before
    name = obj.name
    assert_undo_works(previous, before)
    # The handler checks the counts only (the full topology hash reads every
    # polygon, too slow for every frame); an edge rotated keeps them, and the
    # handler still refuses because the refused Apply let the model go.
    assert_handler_reports(bpy.data.objects[name], words.split(".*")[0])


@pytest.mark.parametrize("how", ["data API", "delete operator"])
def test_armature_deleted_after_the_bake_is_refused(addon, tmp_path, how):
    obj, rig = baked_character(tmp_path)
    if how == "data API":
        bpy.data.objects.remove(rig)
    else:
        bpy.ops.object.select_all(action="DESELECT")
        rig.select_set(True)
        assert bpy.ops.object.delete() == {"FINISHED"}
    assert obj.modifiers["Armature"].object is None
    bpy.context.view_layer.objects.active = obj
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.apply_visibility, "Armature modifier .* points at no armature", "undo the deletion")
    assert scene_state() == before
    name = obj.name
    assert_undo_works(previous, before)
    assert_handler_reports(bpy.data.objects[name], "points at no armature")


# Maps: NaN / Inf / negative pixels, 0×N pixels, 1×1 ------------------------------------

def _map_with_bad_pixels(h=32, w=64):
    """A sky-and-sun map with one NaN, one +Inf and one negative channel."""
    img = sky_and_sun(h=h, w=w)
    img[3, 5, 0] = np.nan
    img[7, 9, 1] = np.inf
    img[11, 13, 2] = -4.0
    return img


def _radiance_file(path, width, height):
    """A Radiance .hdr header for a width × height image and no pixels
    (OpenImageIO refuses to write a 0-pixel image, so it is written by hand)."""
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {height} +X {width}\n".encode())
    return path


def test_light_rig_from_a_map_with_nan_inf_and_negative_pixels(addon, tmp_path, capfd):
    """The light tool zeroes such pixels and says how many (docs/lights.md):
    the rig is built from the rest of the map, with finite values."""
    img = _map_with_bad_pixels()
    path = write_map(str(tmp_path / "bad.exr"), img)
    json_path = str(tmp_path / "rig.json")
    previous, before = undo_checkpoint()
    report = finished(bpy.ops.penumbra.build_light_rig, capfd, filepath=path, count=8, json_path=json_path)
    assert "replaced 1 NaN, 1 Inf and 1 negative pixel values by 0" in report
    suns = [o for o in addon.penumbra.light_rig.collection.objects if o.type == "LIGHT"]
    assert len(suns) == 8 and all(math.isfinite(o.data.energy) and o.data.energy >= 0 for o in suns)
    # The rig carries the map's light with those pixels at 0.
    clean = np.where(np.isfinite(img) & (img > 0), img, 0.0)
    total = (clean * solid_angles(*img.shape[:2])[:, None, None]).sum(axis=(0, 1))
    rgb = sum(np.array(l["rgb"]) for l in json.load(open(json_path))["frames"][0]["lights"])
    np.testing.assert_allclose(rgb, total, rtol=1e-4)
    assert_undo_works(before, scene_state())


@pytest.mark.parametrize("size", [(0, 16), (16, 0)])
def test_light_rig_from_a_map_of_zero_pixels_is_refused(addon, tmp_path, size):
    width, height = size
    json_path = str(tmp_path / "rig.json")
    name = f"empty_{width}x{height}.hdr"
    path = _radiance_file(str(tmp_path / name), width, height)
    world_with(addon, path)  # the World's environment, as a user usually gives the map
    previous, before = undo_checkpoint()
    words = (name, f"{width}x{height}", "at least 1x1", "check that the file is complete")
    refused(bpy.ops.penumbra.build_light_rig, *words, filepath=path, count=4, json_path=json_path)
    assert scene_state() == before
    refused(bpy.ops.penumbra.build_light_rig, *words, count=4, json_path=json_path)  # from the World
    assert scene_state() == before
    assert not os.path.exists(json_path) and not os.path.exists(json_path + ".tmp")
    assert_undo_works(previous, before)


def test_light_rig_from_a_one_pixel_map(addon, tmp_path, capfd):
    """One pixel is one light carrying the whole sphere's light (4π L); more
    lights than pixels are refused, with the most that can be asked for."""
    core = native.require()
    path = str(tmp_path / "one.exr")
    core.image.write_exr(path, np.array([[[0.5, 1.0, 2.0]]], np.float32), half=False, colorspace="Linear")
    json_path = str(tmp_path / "rig.json")
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.build_light_rig, "64 exceeds the 1 pixels", "at most", filepath=path, count=64,
            json_path=json_path)
    assert scene_state() == before and not os.path.exists(json_path)
    assert_undo_works(previous, before)
    report = finished(bpy.ops.penumbra.build_light_rig, capfd, filepath=path, count=1, json_path=json_path)
    assert "1 lights over 1 frame(s)" in report
    lights = json.load(open(json_path))["frames"][0]["lights"]
    assert len(lights) == 1
    np.testing.assert_allclose(lights[0]["rgb"], 4 * math.pi * np.array([0.5, 1.0, 2.0]), rtol=1e-5)
    assert_undo_works(before, scene_state())


def _environment_world(scene, path):
    world = world_with(scene, path)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    return world


def test_visibility_under_a_map_with_nan_inf_and_negative_pixels(addon, tmp_path, capfd):
    """NaN and Inf count as black and negative values are kept (the SH
    projection's contract); the result is finite, and the report says so."""
    obj, rig = baked_character(tmp_path)
    img = _map_with_bad_pixels()
    clean = np.where(np.isfinite(img), img, 0.0)
    _environment_world(addon, write_map(str(tmp_path / "clean.exr"), clean))
    assert bpy.ops.penumbra.apply_visibility() == {"FINISHED"}
    expected = attribute(obj, "penumbra_shading", 4).copy()
    _environment_world(addon, write_map(str(tmp_path / "bad.exr"), img))
    previous, before = undo_checkpoint()
    report = finished(bpy.ops.penumbra.apply_visibility, capfd)
    assert "2 NaN or infinite pixel(s), lit as black" in report, report
    assert "1 pixel(s) with negative values" in report and "bad.exr" in report
    shading = attribute(obj, "penumbra_shading", 4)
    assert np.isfinite(shading).all()
    np.testing.assert_allclose(shading, expected, rtol=1e-5, atol=1e-6)
    assert_undo_works(before, scene_state())


@pytest.mark.parametrize("size", [(0, 16), (16, 0)])
def test_visibility_under_a_map_of_zero_pixels_is_refused(addon, tmp_path, size):
    obj, rig = baked_character(tmp_path)
    path = _radiance_file(str(tmp_path / "empty.hdr"), *size)
    _environment_world(addon, path)
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.apply_visibility, "environment image 'empty.hdr' has no pixels",
            "could not read its file", "replace it")
    assert scene_state() == before
    assert_undo_works(previous, before)


def test_visibility_under_a_one_pixel_map_is_uniform_light(addon, tmp_path, capfd):
    """A 1×1 map is a uniform World of that radiance: the diffuse shading is
    the visibility times it (the run time's normalization contract)."""
    obj, rig = baked_character(tmp_path)
    core = native.require()
    path = str(tmp_path / "one.exr")
    core.image.write_exr(path, np.array([[[0.5, 1.0, 2.0]]], np.float32), half=False, colorspace="Linear")
    _environment_world(addon, path)
    previous, before = undo_checkpoint()
    report = finished(bpy.ops.penumbra.apply_visibility, capfd)
    assert "Shaded 988 vertices" in report and "NaN" not in report and "negative" not in report
    ao = attribute(obj, "penumbra_visibility", 1)
    rgb = attribute(obj, "penumbra_shading", 4)[:, :3]
    inside = ao < 0.999
    np.testing.assert_allclose(rgb[inside], ao[inside, None] * np.array([0.5, 1.0, 2.0]), rtol=1e-4, atol=1e-5)
    assert_undo_works(before, scene_state())


def _image_from_pixels(name, pixels):
    h, w = pixels.shape[:2]
    image = bpy.data.images.new(name, w, h, float_buffer=True)
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = pixels
    image.pixels.foreach_set(rgba.ravel())
    return image


def test_colour_map_image_with_nan_or_inf_pixels_is_refused(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path / "luts")
    pixels = np.tile(np.linspace(0, 1, 16, dtype=np.float32)[None, :, None], (3, 1, 3))
    pixels[1, 2, 0] = np.nan  # the middle row is the colour map
    pixels[1, 5, 1] = np.inf
    _image_from_pixels("strip", pixels)
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.bake_colormap_lut, "'strip' has 2 NaN or infinite pixel", "fix or replace",
            image_name="strip")
    assert scene_state() == before and not os.path.exists(tmp_path / "luts")
    assert_undo_works(previous, before)


@pytest.mark.parametrize("size", [(0, 16), (16, 0)])
def test_colour_map_image_of_zero_pixels_is_refused(addon, tmp_path, size):
    addon.penumbra.colormap.output_folder = str(tmp_path / "luts")
    image = bpy.data.images.load(_radiance_file(str(tmp_path / "empty.hdr"), *size))
    assert tuple(image.size) == (0, 0)
    previous, before = undo_checkpoint()
    refused(bpy.ops.penumbra.bake_colormap_lut, "'empty.hdr' has no pixels", "could not read its file",
            "replace it", image_name=image.name)
    assert scene_state() == before and not os.path.exists(tmp_path / "luts")
    assert_undo_works(previous, before)


def test_colour_map_image_of_one_pixel_bakes_a_constant_lookup(addon, tmp_path, capfd):
    addon.penumbra.colormap.output_folder = str(tmp_path / "luts")
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 8
    _image_from_pixels("dot", np.array([[[0.25, 0.5, 0.75]]], np.float32))
    previous, before = undo_checkpoint()
    report = finished(bpy.ops.penumbra.bake_colormap_lut, capfd, image_name="dot")
    assert "Filtered image 'dot'" in report
    lookup = native.require().image.read(str(tmp_path / "luts" / "dot_lut.exr"))
    np.testing.assert_allclose(lookup[..., :3].reshape(-1, 3), np.tile([0.25, 0.5, 0.75], (64, 1)), atol=1e-6)
    assert_undo_works(before, scene_state())


# Light rig: a sequence with a truncated EXR in the middle --------------------------------

def _noisy_sequence(folder, frames, seed):
    """EXR frames of a moving sun over a noisy sky (noise: the files do not
    compress to a few hundred bytes, so a cut lands in the pixel data)."""
    core = native.require()
    folder.mkdir()
    rng = np.random.default_rng(seed)
    img = sky_and_sun(h=32, w=64, sky=0.05)
    for i in range(frames):
        frame = core.lights.rotate_map_z(img, math.radians(10 * i)) + rng.uniform(0, 0.01, img.shape)
        core.image.write_exr(str(folder / f"sky_{i + 1:04d}.exr"), frame.astype(np.float32), half=False,
                             colorspace="Linear")
    return str(folder / "sky_0001.exr")


@pytest.mark.parametrize("run", ["script", "modal"])
def test_truncated_exr_in_a_sequence_leaves_the_rig_and_json_as_they_were(addon, tmp_path, run):
    json_path = str(tmp_path / "rig.json")
    good = _noisy_sequence(tmp_path / "good", 3, 1)
    assert bpy.ops.penumbra.build_light_rig(filepath=good, count=6, json_path=json_path) == {"FINISHED"}
    bad = _noisy_sequence(tmp_path / "bad", 5, 2)
    cut = tmp_path / "bad" / "sky_0003.exr"
    data = cut.read_bytes()
    assert len(data) > 10000
    cut.write_bytes(data[: len(data) * 3 // 4])
    previous, before = undo_checkpoint()
    rig_before = rig_state(addon, json_path)
    json_before = open(json_path, "rb").read()
    words = ("sky_0003.exr", "truncated", "re-export")
    if run == "script":
        refused(bpy.ops.penumbra.build_light_rig, *words, filepath=bad, count=10, json_path=json_path)
    else:
        op = stand_in(light_operators.PENUMBRA_OT_build_light_rig, filepath=bad, count=10, json_path=json_path,
                      frame_end=5)
        assert run_modal(op, _UIContext()) == {"CANCELLED"}
        message = errors_of(op)
        for word in words:
            assert word in message, message
    assert rig_state(addon, json_path) == rig_before
    assert open(json_path, "rb").read() == json_before and not os.path.exists(json_path + ".tmp")
    assert scene_state() == before
    assert_undo_works(previous, before)


# Colour maps: the ColorRamp changed while its lookup is being built -----------------------

def _ramp_scene(tmp_path):
    settings = bpy.context.scene.penumbra.colormap
    settings.output_folder = str(tmp_path / "luts")
    settings.lut_width = settings.lut_height = 16
    material, ramp = make_ramp_material("ramped", noise=True)
    obj = plane_with(material)
    bpy.context.view_layer.objects.active = obj
    return material, ramp


def _relink_fac(material, ramp):
    value = material.node_tree.nodes.new("ShaderNodeValue")
    value.name = "Other Source"
    material.node_tree.links.new(value.outputs[0], ramp.inputs["Fac"])  # replaces the noise's link


def _change_stops(material, ramp):
    ramp.color_ramp.elements[0].color = (0.0, 1.0, 0.0, 1.0)


def _remove_ramp(material, ramp):
    material.node_tree.nodes.remove(ramp)


def _remove_material(material, ramp):
    bpy.data.materials.remove(material)


# change -> (what it does, words of the error)
RAMP_CHANGES = {
    "ramp removed": (_remove_ramp, "ColorRamp '{ramp}' was removed from 'ramped'"),
    "Fac relinked": (_relink_fac, "ColorRamp '{ramp}' in 'ramped' was changed .*what drives its Fac"),
    "stops changed": (_change_stops, "ColorRamp '{ramp}' in 'ramped' was changed .*its stops"),
    "material removed": (_remove_material, "Material 'ramped' was removed"),
}


@pytest.mark.parametrize("change", sorted(RAMP_CHANGES))
def test_ramp_changed_while_its_lookup_is_built_is_refused(addon, tmp_path, change):
    """From the UI the lookup is built in a thread while Blender keeps
    running; the ramp can be edited meanwhile (from another window, a script
    or a timer). Applying a lookup of the ramp as it was would wire the group
    to the wrong source or touch a removed node."""
    material, ramp = _ramp_scene(tmp_path)
    ramp_name = ramp.name
    mutate, words = RAMP_CHANGES[change]
    op = stand_in(colormap_operators.PENUMBRA_OT_bake_colormap_lut)
    context = _UIContext()
    checkpoint = {}

    def meanwhile():
        mutate(material, ramp)
        checkpoint["previous"], checkpoint["before"] = undo_checkpoint()
    assert run_modal(op, context, meanwhile) == {"CANCELLED"}
    message = errors_of(op)
    assert re.search(words.format(ramp=ramp_name), message), message
    assert "Nothing was changed" in message and "bake again" in message
    assert scene_state() == checkpoint["before"]
    assert not os.path.exists(tmp_path / "luts")
    assert_undo_works(checkpoint["previous"], checkpoint["before"])


def test_ramp_left_alone_while_its_lookup_is_built_is_replaced(addon, tmp_path):
    """The same modal run with nothing changed meanwhile finishes (the test
    above can only fail on the change)."""
    material, ramp = _ramp_scene(tmp_path)
    op = stand_in(colormap_operators.PENUMBRA_OT_bake_colormap_lut)
    assert run_modal(op, _UIContext()) == {"FINISHED"}, op.reports
    assert material.node_tree.nodes.active.name == node_groups.FILTERED_RAMP and ramp.mute


@pytest.mark.parametrize("change", ["deleted", "replaced by another node"])
def test_restore_when_the_original_ramp_is_gone_is_refused(addon, tmp_path, change):
    material, ramp = _ramp_scene(tmp_path)
    ramp_name = ramp.name
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    tree.nodes.remove(ramp)
    if change == "replaced by another node":
        tree.nodes.new("ShaderNodeMath").name = ramp_name
    tree.nodes.active = tree.nodes[node_groups.FILTERED_RAMP]
    previous, before = undo_checkpoint()
    why = "was deleted or renamed" if change == "deleted" else "is now a Math node"
    refused(bpy.ops.penumbra.restore_color_ramp, f"original ColorRamp '{ramp_name}' of '{node_groups.FILTERED_RAMP}' "
            f"{why}", "undo that change")
    assert scene_state() == before
    assert_undo_works(previous, before)
