"""Frame shading: on every frame change and pose edit, shade each enabled object
from its visibility model (paper §4.3) under the World's SH lighting, and
write the point-domain attributes `penumbra_shading` (colour, scene-linear
RGB) and `penumbra_visibility` (float, cosine-weighted visibility = AO).

Normalization (a contract): under a uniform World of radiance 1, the diffuse
`penumbra_shading` of a vertex is its ambient occlusion in [0, 1].
"""

import os
import stat
import time

import bpy
import numpy as np
from bpy.app.handlers import persistent

from .. import native
from . import armature_data, enabled_objects, mesh_data, world_lighting
from .input_error import VisibilityInputError

SHADING_ATTRIBUTE = "penumbra_shading"
VISIBILITY_ATTRIBUTE = "penumbra_visibility"

_models = {}        # object name -> _Loaded
_busy = False       # re-entry guard: writing attributes triggers depsgraph updates
last_timings = {}   # seconds of the last shade, split into steps (read by benchmarks)


def _mesh_counts(mesh):
    """(vertices, polygons, loops, mesh name): changes with almost any topology
    edit and costs nothing to read, so the handler can check it every frame."""
    return len(mesh.vertices), len(mesh.polygons), len(mesh.loops), mesh.name


def _topology_changed(path, obj):
    return VisibilityInputError(
        f"model '{path}' was made for another topology than '{obj.name}' has now (the mesh was edited "
        "since the bake, or it is another mesh): undo the edit, or bake again")


class _Loaded:
    def __init__(self, obj, path):
        core = native.require()
        self.path = path
        self.mtime = os.path.getmtime(path)
        try:
            model = core.visibility.PoseModel.load(path)
        except OSError as error:  # damaged, truncated, not a model: the core says which
            raise VisibilityInputError(f"{error} — bake '{obj.name}' again to rewrite it") from None
        mesh = obj.data
        if model.vertex_count != len(mesh.vertices):
            raise VisibilityInputError(
                f"model '{path}' was made for a mesh with {model.vertex_count} vertices; "
                f"'{obj.name}' has {len(mesh.vertices)} (the mesh was edited since the bake, or it is another "
                "mesh): undo the edit, or bake again")
        if model.topology_hash != mesh_data.topology_hash(mesh):
            raise _topology_changed(path, obj)
        self.counts = _mesh_counts(mesh)
        armature = armature_data.armature_of(obj)
        missing = [j for j in model.joints if j not in armature.pose.bones]
        if missing:
            raise VisibilityInputError(
                f"model '{path}' was made for another armature: '{armature.name}' lacks {', '.join(missing[:5])}")
        self.model = model
        sizes, loops = mesh_data.polygon_topology(mesh)
        # The polygons (Blender's vertex normals, computed in C++ each frame)
        # and the reference neighbours (the frames' tangents).
        self.mesh = core.visibility.ShadingMesh(len(mesh.vertices), sizes, loops)
        self.neighbours = core.visibility.reference_neighbours(len(mesh.vertices), sizes, loops)
        # The GPU preview's mesh reads (gpu_preview.object_inputs).
        self.buffers = mesh_data.MeshBuffers(mesh)
        # Arrays reused frame after frame: the evaluated mesh's positions
        # are read into `positions`, the C++ writes the attributes' values
        # into `rgba` and `ao`, which go to Blender as they are.
        self.positions = np.empty((model.vertex_count, 3), dtype=np.float32)
        self.rgba = np.ones((model.vertex_count, 4), dtype=np.float32)
        self.ao = np.empty(model.vertex_count, dtype=np.float32)


class paused:
    """Context manager: no shading while the bake poses the scene frame by frame."""

    def __enter__(self):
        global _busy
        self._was = _busy
        _busy = True

    def __exit__(self, *exc):
        global _busy
        _busy = self._was
        return False


def forget(obj=None):
    if obj is None:
        _models.clear()
    else:
        _models.pop(obj.name, None)


def loaded_model(obj, check_topology=False):
    """The object's model, loaded once and kept while its file and the mesh's
    counts stay the same (a mesh edit that changes them loads and checks it
    again). check_topology: also compare the full topology hash, which an
    edit keeping every count (an edge rotated) changes too; the operator
    does, the per-frame handler does not (it reads every polygon)."""
    s = obj.penumbra_visibility
    if not s.model_path:
        raise VisibilityInputError(f"'{obj.name}' has no visibility model: bake one first")
    path = bpy.path.abspath(s.model_path)
    try:
        status = os.stat(path)  # one call a frame: whether the file is there and when it changed
    except OSError:
        status = None
    if status is None or not stat.S_ISREG(status.st_mode):
        raise VisibilityInputError(f"the model file '{path}' of '{obj.name}' is missing — bake again")
    entry = _models.get(obj.name)
    if entry is None or entry.path != path or entry.mtime != status.st_mtime or \
            entry.counts != _mesh_counts(obj.data):
        _models.pop(obj.name, None)
        entry = _Loaded(obj, path)
        _models[obj.name] = entry
    elif check_topology and entry.model.topology_hash != mesh_data.topology_hash(obj.data):
        _models.pop(obj.name, None)
        raise _topology_changed(path, obj)
    return entry


def _ensure_attributes(mesh):
    """The two point attributes, made (or remade with the right type) when
    needed. Returns them, ready to write."""
    attrs = mesh.attributes
    found = []
    for name, data_type in ((SHADING_ATTRIBUTE, "FLOAT_COLOR"), (VISIBILITY_ATTRIBUTE, "FLOAT")):
        attribute = attrs.get(name)
        if attribute is not None and (attribute.domain != "POINT" or attribute.data_type != data_type):
            attrs.remove(attribute)
            attribute = None
        found.append(attribute)
        if attribute is None:
            attrs.new(name, data_type, "POINT")
    if None in found:  # adding or removing a layer may move the others: look them up afresh
        return attrs[SHADING_ATTRIBUTE], attrs[VISIBILITY_ATTRIBUTE]
    return found[0], found[1]


def _read_positions(obj, depsgraph, entry, out=None):
    """The evaluated mesh's object-space positions into `out` (V, 3) float32
    (default entry.positions), and the object's world matrix. Read from the
    evaluated object's own mesh (modifiers and shape keys applied), not a
    to_mesh() copy: the same values at ~1/20 of the time (0.5 against 12 ms
    at 100k vertices in 3.4).
    Blender's normals are not read: reading them makes Blender compute them
    for the pose, which costs more than the C++ computing the same normals
    (frame_shading.hpp)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.data
    count = len(mesh.vertices)
    if count != entry.model.vertex_count:
        # The mesh itself matches the model (loaded_model checked it): a modifier adds or removes vertices.
        changing = [m.name for m in obj.modifiers if m.show_viewport and m.type != "ARMATURE"]
        raise VisibilityInputError(
            f"'{obj.name}' has {count} vertices after its modifiers; the model has "
            f"{entry.model.vertex_count}: disable {', '.join(changing) or 'the modifiers that add or remove vertices'}, "
            "or apply them and bake again")
    mesh_data._vertex_positions(mesh, entry.positions if out is None else out)
    return np.array(evaluated.matrix_world, dtype=np.float64)


def posed_rotations(obj, model, depsgraph):
    """The model's joints' rotations as `depsgraph` posed the armature: a
    render's depsgraph does not copy its pose back to the scene's armature,
    which may stand at another frame."""
    armature = armature_data.armature_of(obj).evaluated_get(depsgraph)
    return armature_data.bone_rotations(armature, model.joints)


def shade_object(obj, scene, depsgraph=None, check_topology=False):
    """Shades `obj` at the scene's current state and writes its attributes.
    Returns (rgb, ao, info): rgb (V, 3) and ao (V,) are views of the object's
    reused buffers, overwritten by its next shade (copy them to keep them);
    info["world_warning"] says what was wrong with the World's pixels, if
    anything. Raises VisibilityInputError / OSError / ValueError, before
    anything is written."""
    global last_timings
    t0 = time.perf_counter()
    entry = loaded_model(obj, check_topology)
    model = entry.model
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    rotations = posed_rotations(obj, model, depsgraph)
    t_read = time.perf_counter()
    world = _read_positions(obj, depsgraph, entry)
    read_mesh = time.perf_counter() - t_read
    lighting, _, world_warning = world_lighting.world_lighting_checked(scene, model.order)
    s = obj.penumbra_visibility
    camera = np.array(scene.camera.matrix_world.translation) if scene.camera else np.zeros(3)
    t1 = time.perf_counter()
    # Normals, frames, lobes and shading in one fused C++ pass, written
    # straight into the attributes' layout (RGB clamped >= 0, AO to [0, 1]).
    rgba, ao, info = model.shade_frame(entry.mesh, rotations, entry.positions, world, lighting,
                                       model=s.brdf.lower(), phong_exponent=s.phong_exponent, camera=camera,
                                       transmission=np.array(s.transmission[:]),
                                       threads=scene.penumbra.visibility.threads,
                                       rgba_out=entry.rgba, visibility_out=entry.ao)
    t2 = time.perf_counter()
    mesh = obj.data
    shading, visibility = _ensure_attributes(mesh)
    shading.data.foreach_set("color", rgba.reshape(-1))
    visibility.data.foreach_set("value", ao)
    # Blender 4.x and 5.x tag the mesh for the writes above; 3.4 does not, and
    # without the tag the evaluated mesh (viewport, renders of this
    # depsgraph) keeps the old values. Either way the depsgraph evaluates
    # the mesh's modifiers once more after the handler (docs/visibility.md).
    mesh.update()
    t3 = time.perf_counter()
    last_timings = {
        "gather": t1 - t0,
        "read_mesh": read_mesh,
        "normals": info["seconds_normals"],
        "pose_to_lobes": info["seconds_pose_to_lobes"],
        "frames": info["seconds_frames"],
        "shading": info["seconds_shading"],
        "shade_call": t2 - t1,
        "write_attributes": t3 - t2,
        "total": t3 - t0,
    }
    info["world_warning"] = world_warning
    return rgba[:, :3], ao, info


def shade_enabled_objects(scene, depsgraph=None):
    global _busy
    if _busy or native.module is None:
        return
    _busy = True
    try:
        for obj in enabled_objects.in_scene(scene):
            settings = obj.penumbra_visibility
            try:
                shade_object(obj, scene, depsgraph)
                if settings.status:
                    settings.status = ""
            except (VisibilityInputError, ValueError, RuntimeError, OSError) as error:
                # A handler must never raise into Blender: say it on the object.
                message = str(error)
                if settings.status != message:
                    settings.status = message
                    print(f"penumbra: {obj.name}: {message}")
    finally:
        _busy = False


def _drives_enabled_object(scene, update_ids):
    names = {getattr(u.id, "name", None) for u in update_ids}
    for obj in enabled_objects.in_scene(scene):
        for modifier in obj.modifiers:
            if modifier.type == "ARMATURE" and modifier.object is not None and modifier.object.name in names:
                return True
    return False


# True from a frame's render_pre to its render_post (or a cancel). Blender
# sets each rendered frame (a still too) between the two and calls
# frame_change_post with the render's depsgraph: shading there gives every
# rendered frame its own attributes, even with live_update off, where the
# viewport's attributes may be stale by design.
_rendering = False


@persistent
def on_render_pre(scene, *args):
    global _rendering
    _rendering = True


@persistent
def on_render_end(scene, *args):
    global _rendering
    _rendering = False


@persistent
def on_frame_change(scene, depsgraph=None):
    if not (scene.penumbra.visibility.live_update or _rendering):
        return
    shade_enabled_objects(scene, depsgraph)


@persistent
def on_depsgraph_update(scene, depsgraph):
    if _busy or not scene.penumbra.visibility.live_update:
        return
    # Only pose edits (the armature changed), the camera or the World: our own
    # attribute writes update the mesh and must not loop back here.
    relevant = any(isinstance(u.id, (bpy.types.World,)) or
                   (isinstance(u.id, bpy.types.Object) and u.id.type == "CAMERA") for u in depsgraph.updates)
    if relevant or _drives_enabled_object(scene, depsgraph.updates):
        shade_enabled_objects(scene, depsgraph)


def request_refresh():
    """Settings changed in the UI: re-shade at once (outside handlers)."""
    scene = bpy.context.scene if bpy.context else None
    if scene is not None and scene.penumbra.visibility.live_update:
        shade_enabled_objects(scene)




def _handlers():
    h = bpy.app.handlers
    return ((h.frame_change_post, on_frame_change), (h.depsgraph_update_post, on_depsgraph_update),
            (h.render_pre, on_render_pre), (h.render_post, on_render_end), (h.render_cancel, on_render_end))


def register_handlers():
    for handlers, fn in _handlers():
        if fn not in handlers:
            handlers.append(fn)


def unregister_handlers():
    global _rendering
    for handlers, fn in _handlers():
        while fn in handlers:
            handlers.remove(fn)
    _rendering = False
    forget()
