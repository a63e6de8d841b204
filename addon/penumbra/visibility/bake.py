"""Baking a visibility model from Blender: gather frames (main thread, bpy),
bake visibility and fit (C++ with the GIL released), write the model, store
the report on the object.

The seam for render farms: `bake_training_set` bakes a frame range of one
object into a _penumbra.visibility.TrainingSet, which can be saved (.pvis)
from a headless job (scripts/visibility_bake_farm.py); `fit_and_store`
merges any number of pieces and fits. The operator runs the same two steps.
"""

import json
import os
import tempfile
import threading
import time

import bpy

from .. import native
from . import armature_data, mesh_data
from .input_error import VisibilityInputError

DEFAULT_EXTENSION = ".pzh"


def default_model_path(obj):
    """Next to the .blend (`//<blend>_<object>.pzh`), or a temporary folder for an unsaved file."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in obj.name)
    if bpy.data.filepath:
        folder = os.path.dirname(bpy.data.filepath)
        stem = os.path.splitext(os.path.basename(bpy.data.filepath))[0]
        return os.path.join(folder, f"{stem}_{safe}{DEFAULT_EXTENSION}")
    return os.path.join(tempfile.gettempdir(), f"penumbra_{safe}{DEFAULT_EXTENSION}")


def resolve_path(path, obj):
    return bpy.path.abspath(path) if path else default_model_path(obj)


class BakeJob:
    """Everything one bake needs, checked up front so that a bad input fails
    before any frame is touched."""

    def __init__(self, context, obj, frame_start, frame_end, frame_step, rays, lobes, sh_order, occluders,
                 below_horizon="occluded", threads=0, actions=()):
        core = native.require()
        self.scene = context.scene
        self.obj = obj
        self.armature = armature_data.armature_of(obj)
        if len(obj.data.vertices) == 0:
            raise VisibilityInputError(f"'{obj.name}' has no vertices: nothing to bake")
        if len(obj.data.polygons) == 0:
            raise VisibilityInputError(f"'{obj.name}' has no faces: visibility needs a surface")
        self.actions = list(actions)
        if not self.actions and not armature_data.armature_has_animation(self.armature):
            raise VisibilityInputError(
                f"armature '{self.armature.name}' has no animation (no action, NLA strip or driver): "
                "the training poses are the frames of its actions")
        if frame_step < 1:
            raise VisibilityInputError("frame step must be at least 1")
        if frame_end < frame_start:
            raise VisibilityInputError(f"frame range is empty ({frame_start}..{frame_end})")
        frames = list(range(frame_start, frame_end + 1, frame_step))
        if not frames:
            raise VisibilityInputError("no frames to bake")
        # (action or None for what the armature plays now, frame); several
        # actions are played in turn over the same range.
        self.frames = [(action, f) for action in (self.actions or [None]) for f in frames]
        self.rays, self.lobes, self.order = rays, lobes, sh_order
        self.occluders = occluders
        self.threads = threads
        self.bone_names = [b.name for b in self.armature.pose.bones]
        self.vertex_count = len(obj.data.vertices)
        self.topology = mesh_data.topology_hash(obj.data)
        sizes, loops = mesh_data.polygon_topology(obj.data)
        self.neighbours = core.visibility.reference_neighbours(self.vertex_count, sizes, loops)
        self.influence = armature_data.bone_influence(obj, self.armature)
        self.training = core.visibility.TrainingSet(self.vertex_count, self.topology, self.bone_names, order=sh_order,
                                                    rays=rays, below_horizon=below_horizon)
        self.original_frame = self.scene.frame_current
        self.original_action = self.armature.animation_data.action if self.armature.animation_data else None
        self.diagnostics = None
        self.rays_cast = 0
        self.seconds_trace = 0.0  # inside the C++ bake (frames, BVH, rays, projection)
        self.seconds = {"pose": 0.0, "read": 0.0, "setup": 0.0, "build": 0.0, "cast": 0.0}  # breakdown
        self.repaired_normals = 0

    def gather(self, entry):
        """Main thread: pose the scene at `entry` ((action, frame) or a frame) and copy what the bake needs.
        Returns (training frame id, mesh, rotations, occluders); the id is the frame number, plus
        100000 × the action's index when several actions are baked."""
        action, frame = entry if isinstance(entry, tuple) else (None, entry)
        frame_id = frame
        if action is not None:
            if self.armature.animation_data is None:
                self.armature.animation_data_create()
            if self.armature.animation_data.action != action:
                self.armature.animation_data.action = action
            frame_id = self.actions.index(action) * 100000 + frame
        from . import frame_shading
        started = time.perf_counter()
        with frame_shading.paused():  # the bake's own frame changes need no shading
            self.scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        posed = time.perf_counter()
        self.seconds["pose"] += posed - started
        mesh = mesh_data.evaluated_mesh(self.obj, depsgraph)
        if len(mesh.positions) != self.vertex_count or mesh.topology != self.topology:
            changing = [m.name for m in self.obj.modifiers if m.type not in DEFORM_ONLY]
            raise VisibilityInputError(
                f"at frame {frame} the modifiers of '{self.obj.name}' change its topology "
                f"({len(mesh.positions)} vertices after modifiers, {self.vertex_count} in the mesh); "
                f"disable or apply {', '.join(changing) or 'the generating modifiers'} before baking")
        if self.diagnostics is None:
            d = native.require().visibility.mesh_diagnostics(mesh.positions, mesh.normals, mesh.triangles)
            if d["normals_point_inward"]:
                raise VisibilityInputError(
                    f"the normals of '{self.obj.name}' point inward (signed volume {d['signed_volume']:.3g}); "
                    "fix them with Mesh > Normals > Recalculate Outside, then bake again")
            self.diagnostics = d
        occluders = mesh_data.occluder_meshes(self.occluders, depsgraph, self.obj)
        rotations = armature_data.bone_rotations(self.armature)
        self.seconds["read"] += time.perf_counter() - posed
        return frame_id, mesh, rotations, occluders

    def bake(self, gathered, progress=None):
        """Any thread: trace one gathered frame (releases the GIL)."""
        frame, mesh, rotations, occluders = gathered
        started = time.perf_counter()
        stats = self.training.bake_frame(float(frame), mesh.positions, mesh.normals, mesh.triangles, self.neighbours,
                                         rotations, occluders, threads=self.threads, progress=progress)
        self.seconds_trace += time.perf_counter() - started
        for key in ("setup", "build", "cast"):
            self.seconds[key] += stats["seconds_" + key]
        self.rays_cast += stats["rays_cast"]
        self.repaired_normals = max(self.repaired_normals, stats["repaired_normals"])

    def restore_frame(self):
        native.require().visibility.release_bake_cache()  # the Embree scene kept between frames
        if self.actions and self.armature.animation_data is not None and \
                self.armature.animation_data.action != self.original_action:
            self.armature.animation_data.action = self.original_action
        self.scene.frame_set(self.original_frame)


# Modifiers that move vertices without changing the topology.
DEFORM_ONLY = {"ARMATURE", "CAST", "CURVE", "DISPLACE", "HOOK", "LAPLACIANDEFORM", "LATTICE", "MESH_DEFORM",
               "SHRINKWRAP", "SIMPLE_DEFORM", "SMOOTH", "CORRECTIVE_SMOOTH", "LAPLACIANSMOOTH", "SURFACE_DEFORM",
               "WARP", "WAVE", "VOLUME_DISPLACE", "WEIGHTED_NORMAL", "NORMAL_EDIT", "DATA_TRANSFER",
               "MESH_CACHE", "MESH_SEQUENCE_CACHE", "UV_PROJECT", "UV_WARP", "VERTEX_WEIGHT_EDIT",
               "VERTEX_WEIGHT_MIX", "VERTEX_WEIGHT_PROXIMITY"}


def bake_frames(job, progress=None, after_frame=None, overlap=False):
    """Bakes every frame of `job`. `progress(fraction)` returns False to
    cancel; `after_frame(k)` runs on the main thread once frame k is baked.

    overlap=False (default): read a frame (main thread, bpy), then trace it.
    overlap=True: the main thread poses and reads frame k + 1 while a worker
    thread traces frame k (the C++ bake releases the GIL). Measured on two
    cores (docs/visibility-benchmark.md) the overlap is *slower*: Blender's
    depsgraph threads, busy posing the next frame, take the cores from the
    casting threads, which costs more than the reading it hides. Errors of
    either side are raised here, after the worker has stopped.

    The overlap's worker is the one thread the add-on starts outside
    modal_job.py: it runs inside this synchronous call, which waits for it
    before returning or raising, so no operator or timer ever sees it. It
    is kept, unused by the operators, so that the measurement above can be
    repeated (test_visibility.py checks it bakes the same frames)."""
    if not overlap:
        n = len(job.frames)
        for k, entry in enumerate(job.frames):
            gathered = job.gather(entry)

            def frame_progress(fraction, k=k):
                return True if progress is None else progress((k + fraction) / n)
            job.bake(gathered, frame_progress if progress is not None else None)
            if after_frame:
                after_frame(k)
        return
    n = len(job.frames)
    state = {"error": None}

    def trace(gathered, k):
        def frame_progress(fraction):
            return True if progress is None else progress((k + fraction) / n)
        try:
            job.bake(gathered, frame_progress)
        except BaseException as error:  # noqa: BLE001 - re-raised on the main thread
            state["error"] = error

    worker = None
    finished = -1

    def join():
        nonlocal worker, finished
        if worker is None:
            return
        worker.join()
        worker = None
        if state["error"] is not None:
            raise state["error"]
        finished += 1
        if after_frame:
            after_frame(finished)

    try:
        for k, entry in enumerate(job.frames):
            gathered = job.gather(entry)
            join()
            worker = threading.Thread(target=trace, args=(gathered, k), daemon=True)
            worker.start()
        join()
    finally:
        if worker is not None:  # an error while gathering: let the running frame end first
            worker.join()


def bake_training_set(context, obj, frame_start, frame_end, frame_step, rays=256, sh_order=4, occluders=None,
                      below_horizon="occluded", threads=0, progress=None, log=None, actions=()):
    """Synchronous bake of one frame range (of each of `actions`, or of what the
    armature plays now) into a training set (the farm seam). Returns (job, training_set)."""
    job = BakeJob(context, obj, frame_start, frame_end, frame_step, rays, 1, sh_order, occluders, below_horizon,
                  threads, actions)

    def done(k):
        if log:
            log(f"visibility bake: frame {job.frames[k][1]} ({k + 1}/{len(job.frames)})")
    try:
        bake_frames(job, progress, done)
    finally:
        job.restore_frame()
    return job, job.training


def fit_model(training, influence, lobes, threads=0, progress=None):
    core = native.require()
    return core.visibility.fit_model(training, influence, lobes=lobes, threads=threads, progress=progress)


def summary_of(job_or_none, training, report, model_path, seconds_bake, seconds_fit, model):
    kept = [j for j in report["joints"] if j["active"]]
    dropped = [j for j in report["joints"] if not j["active"]]
    summary = {
        "model_path": model_path,
        "vertices": training.vertex_count,
        "frames": len(training),
        "rays": training.rays,
        "sh_order": training.order,
        "lobes": model.lobes,
        "below_horizon": training.below_horizon.name.lower(),  # the report keeps the names it always had
        "pose_features": model.features.name.lower(),
        "active_joints": [j["name"] for j in kept],
        "joints": report["joints"],
        "zh_fit": report["zh_fit"],
        "model_training": report["model_training"],
        "model_holdout": report["model_holdout"],  # the model as stored (pruned), fitted without those frames
        "model_holdout_unpruned": report["model_holdout_unpruned"],
        "holdout_frames": report["holdout_frames"],
        "ridge_relative": report["ridge_relative"],
        "constant_vertices": report["constant_vertices"],
        "model_bytes": report["model_bytes"],
        "dense_bytes": report["dense_bytes"],
        "seconds_bake": round(seconds_bake, 3),
        "seconds_fit": round(seconds_fit, 3),
        "dropped_joints": {j["name"]: j["reason"] for j in dropped},
    }
    if job_or_none is not None:
        summary["rays_cast"] = job_or_none.rays_cast
        summary["repaired_normals"] = job_or_none.repaired_normals
        summary["zero_area_triangles"] = job_or_none.diagnostics["zero_area_triangles"] if job_or_none.diagnostics else 0
    return summary


def store_result(obj, model, summary, path):
    """Writes the model (atomically) and records it on the object."""
    model.save(path)
    settings = obj.penumbra_visibility
    settings.model_path = path
    settings.report = json.dumps(summary)
    settings.status = ""
    from . import frame_shading
    frame_shading.forget(obj)


def fit_and_store(obj, pieces, lobes, path, threads=0, progress=None, job=None, seconds_bake=0.0):
    """Merges training-set pieces (one or many), fits, writes the model, stores the summary."""
    core = native.require()
    training = pieces[0] if len(pieces) == 1 else core.visibility.TrainingSet.merge(list(pieces))
    armature = armature_data.armature_of(obj)
    if training.vertex_count != len(obj.data.vertices) or training.topology_hash != mesh_data.topology_hash(obj.data):
        raise VisibilityInputError(f"the baked frames were made from another mesh than '{obj.name}'")
    if training.bone_names != [b.name for b in armature.pose.bones]:
        raise VisibilityInputError(f"the baked frames were made with another armature than '{armature.name}'")
    influence = job.influence if job is not None else armature_data.bone_influence(obj, armature)
    started = time.perf_counter()
    model, report = fit_model(training, influence, lobes, threads, progress)
    seconds_fit = time.perf_counter() - started
    summary = summary_of(job, training, report, path, seconds_bake, seconds_fit, model)
    store_result(obj, model, summary, path)
    return model, summary
