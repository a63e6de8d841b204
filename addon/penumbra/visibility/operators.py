"""The visibility tool's operators (names are a contract):
penumbra.bake_visibility (bake.py's pipeline, run by modal_job.py: modal
with Esc from the UI, synchronous from scripts), penumbra.apply_visibility
(frame_shading.py's shading at the current frame) and penumbra.setup_material
(material.py)."""

import os
import time

import bpy

from .. import compat, modal_job
from ..core_settings import limits
from ..errors import CORE_ERRORS, describe
from .bake import BakeJob, fit_model, resolve_path, store_result, summary_of
from .material import SHADING_ATTRIBUTE, setup_material
from .frame_shading import shade_object
from .input_error import VisibilityInputError


class PENUMBRA_OT_bake_visibility(modal_job.JobOperator, bpy.types.Operator):
    """Bake a pose-space visibility model of the active skinned mesh (Esc cancels)"""

    bl_idname = "penumbra.bake_visibility"
    bl_label = "Bake Visibility"
    bl_options = {"REGISTER", "UNDO"}

    frame_start: bpy.props.IntProperty(name="Start", default=-1, description="First frame (-1: the object's setting)")
    frame_end: bpy.props.IntProperty(name="End", default=-1, description="Last frame (-1: the object's setting)")
    # Step, rays and lobes show their documented defaults; when a caller does
    # not set them, the object's own settings (same defaults) are used.
    frame_step: bpy.props.IntProperty(name="Step", default=1, min=1, description="Frame step (unset: the object's setting)")
    rays: bpy.props.IntProperty(name="Rays", **limits("visibility.rays"),
                                description="Rays per vertex (unset: the object's setting)")
    lobes: bpy.props.IntProperty(name="Lobes", **limits("visibility.lobes"),
                                 description="ZH lobes (unset: the object's setting)")
    sh_order: bpy.props.IntProperty(name="SH Order", **limits("visibility.sh_order"))
    occluders: bpy.props.StringProperty(name="Occluders", default="",
                                        description="Collection of other shadowing objects (empty: the object's setting)")
    filepath: bpy.props.StringProperty(name="File", subtype="FILE_PATH", default="", options=compat.BLEND_RELATIVE_PATH,
                                       description="Model file (empty: the object's setting, else next to the .blend)")
    actions: bpy.props.StringProperty(
        name="Actions", default="",
        description="Comma-separated actions played in turn over the frame range (empty: what the armature plays now)")
    below_horizon: bpy.props.EnumProperty(
        name="Below Horizon", default="OCCLUDED",
        items=(("OCCLUDED", "Occluded", "Rays below the tangent plane count as blocked (closed skins)"),
               ("CAST", "Cast", "Trace them too (open, thin surfaces)")))

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    # Settings ------------------------------------------------------------------
    def _given(self, name, settings):
        return getattr(self, name) if self.properties.is_property_set(name) else getattr(settings, name)

    def _resolved(self, context):
        obj = context.active_object
        s = obj.penumbra_visibility
        occluders = None
        name = self.occluders
        if name:
            occluders = bpy.data.collections.get(name)
            if occluders is None:
                raise VisibilityInputError(f"no collection named '{name}'")
        else:
            occluders = s.occluders
        actions = []
        for name in (n.strip() for n in self.actions.split(",")):
            if not name:
                continue
            action = bpy.data.actions.get(name)
            if action is None:
                raise VisibilityInputError(f"no action named '{name}'")
            actions.append(action)
        return dict(
            obj=obj,
            actions=actions,
            frame_start=self.frame_start if self.frame_start >= 0 else s.frame_start,
            frame_end=self.frame_end if self.frame_end >= 0 else s.frame_end,
            frame_step=self._given("frame_step", s),
            rays=self._given("rays", s),
            lobes=self._given("lobes", s),
            sh_order=self.sh_order,
            occluders=occluders,
            path=resolve_path(self.filepath or s.filepath, obj),
        )

    def make_job(self, context):
        r = self._resolved(context)
        folder = os.path.dirname(r["path"]) or "."
        if not os.path.isdir(folder):
            raise VisibilityInputError(f"the model's folder '{folder}' does not exist")
        if len(range(r["frame_start"], r["frame_end"] + 1, max(r["frame_step"], 1))) < 2:
            raise VisibilityInputError("a model needs at least two training frames: widen the frame range")
        bake = BakeJob(context, r["obj"], r["frame_start"], r["frame_end"], r["frame_step"], r["rays"], r["lobes"],
                       r["sh_order"], r["occluders"], self.below_horizon,
                       context.scene.penumbra.visibility.threads, r["actions"])
        return _VisibilityBake(bake, r)


class _VisibilityBake(modal_job.Job):
    """Frame by frame: pose and read (main thread, bpy), then trace (a
    worker); then fit (a worker) and store the model. Reading the next frame
    while one is traced measured slower on two cores (see bake_frames)."""

    cancelled_message = "Visibility bake cancelled; the earlier model is untouched"
    BAKE_SHARE = 0.9  # of the progress: tracing the frames; fitting is the rest

    def __init__(self, bake, settings):
        super().__init__()
        self.bake, self.settings = bake, settings
        self.traced = 0
        self.fitting = False

    def status(self):
        if self.fitting:
            return "Fitting the pose model"
        return f"Baking visibility: frame {self.traced}/{len(self.bake.frames)}"

    def steps(self):
        job, r = self.bake, self.settings
        started = time.perf_counter()
        frames = len(job.frames)
        try:
            for k, entry in enumerate(job.frames):
                gathered = job.gather(entry)
                self.traced = k + 1
                yield modal_job.Worker(lambda progress, g=gathered: job.bake(g, progress),
                                       self.BAKE_SHARE * k / frames, self.BAKE_SHARE * (k + 1) / frames)
        finally:
            job.restore_frame()
        seconds_bake = time.perf_counter() - started
        self.fitting = True
        fit_started = time.perf_counter()
        model, report = yield modal_job.Worker(
            lambda progress: fit_model(job.training, job.influence, r["lobes"], job.threads, progress),
            self.BAKE_SHARE, 1.0)
        summary = summary_of(job, job.training, report, r["path"], seconds_bake, time.perf_counter() - fit_started,
                             model)
        store_result(r["obj"], model, summary, r["path"])
        held_out = (f"held-out AO error {summary['model_holdout']['ao_mean_abs']:.4f} (saved model)"
                    if summary["holdout_frames"] else "no held-out frames (fewer than 8 frames)")
        return [("INFO", f"Baked {len(job.frames)} frames of '{r['obj'].name}': "
                         f"{len(summary['active_joints'])} active joints, {held_out}, "
                         f"model {summary['model_bytes'] / 1e6:.2f} MB → {r['path']}")]


class PENUMBRA_OT_apply_visibility(bpy.types.Operator):
    """Shade the active object (or every enabled object) at the current frame and write its attributes"""

    bl_idname = "penumbra.apply_visibility"
    bl_label = "Apply Visibility"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context):
        obj = context.active_object
        try:
            rgb, ao, info = shade_object(obj, context.scene, check_topology=True)
        except (VisibilityInputError, *CORE_ERRORS) as error:
            obj.penumbra_visibility.status = describe(error)  # the panel shows it
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        obj.penumbra_visibility.status = ""
        self.report({"INFO"}, f"Shaded {len(ao)} vertices of '{obj.name}' (mean visibility {float(ao.mean()):.3f})")
        if info["world_warning"]:
            self.report({"WARNING"}, info["world_warning"])
        return {"FINISHED"}


class PENUMBRA_OT_setup_material(bpy.types.Operator):
    """Wire the penumbra_shading attribute into the active object's material (shown as emission)"""

    bl_idname = "penumbra.setup_material"
    bl_label = "Set Up Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context):
        try:
            material = setup_material(context.active_object)
        except ValueError as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Material '{material.name}' now shows {SHADING_ATTRIBUTE}")
        return {"FINISHED"}


classes = (PENUMBRA_OT_bake_visibility, PENUMBRA_OT_apply_visibility, PENUMBRA_OT_setup_material)
