"""The visibility tool's operators (names are a contract):
penumbra.bake_visibility (bake.py's pipeline, modal with Esc, or
synchronous from scripts), penumbra.apply_visibility (runtime.py's
shading at the current frame) and penumbra.setup_material (material.py)."""

import os
import threading
import time

import bpy

from .. import native
from ..core_settings import limits
from ..errors import CORE_ERRORS, describe
from .bake import BakeJob, bake_frames, fit_model, resolve_path, store_result, summary_of
from .material import SHADING_ATTRIBUTE, setup_material
from .runtime import shade_object
from .scene_data import VisibilityInputError


class PENUMBRA_OT_bake_visibility(bpy.types.Operator):
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
    filepath: bpy.props.StringProperty(name="File", subtype="FILE_PATH", default="",
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

    def _start(self, context):
        r = self._resolved(context)
        folder = os.path.dirname(r["path"]) or "."
        if not os.path.isdir(folder):
            raise VisibilityInputError(f"the model's folder '{folder}' does not exist")
        if len(range(r["frame_start"], r["frame_end"] + 1, max(r["frame_step"], 1))) < 2:
            raise VisibilityInputError("a model needs at least two training frames: widen the frame range")
        self._settings = r
        self._job = BakeJob(context, r["obj"], r["frame_start"], r["frame_end"], r["frame_step"], r["rays"],
                            r["lobes"], r["sh_order"], r["occluders"], self.below_horizon,
                            context.scene.penumbra.visibility.threads, r["actions"])
        self._started = time.perf_counter()

    def _finish(self, context, model_and_report, seconds_bake):
        job, r = self._job, self._settings
        model, report = model_and_report
        summary = summary_of(job, job.training, report, r["path"], seconds_bake,
                             time.perf_counter() - self._fit_started, model)
        store_result(r["obj"], model, summary, r["path"])
        held_out = (f"held-out AO error {summary['model_holdout']['ao_mean_abs']:.4f} (saved model)"
                    if summary["holdout_frames"] else "no held-out frames (fewer than 8 frames)")
        self.report({"INFO"}, f"Baked {len(job.frames)} frames of '{r['obj'].name}': "
                              f"{len(summary['active_joints'])} active joints, {held_out}, "
                              f"model {summary['model_bytes'] / 1e6:.2f} MB → {r['path']}")

    # Synchronous (background mode, scripts) ------------------------------------
    def execute(self, context):
        try:
            self._start(context)
        except (VisibilityInputError, *CORE_ERRORS) as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        job = self._job
        last = [0.0]

        def printer(prefix):
            def report(fraction):
                now = time.perf_counter()
                if now - last[0] > 1.0 or fraction >= 1.0:
                    last[0] = now
                    print(f"penumbra: {prefix} {100.0 * fraction:5.1f}%", flush=True)
                return True
            return report

        try:
            bake_frames(job, None, lambda k: printer("bake visibility")((k + 1) / len(job.frames)))
            job.restore_frame()
            seconds_bake = time.perf_counter() - self._started
            self._fit_started = time.perf_counter()
            result = fit_model(job.training, job.influence, self._settings["lobes"], job.threads, printer("fit"))
            self._finish(context, result, seconds_bake)
        except (VisibilityInputError, *CORE_ERRORS) as error:
            job.restore_frame()
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        return {"FINISHED"}

    # Interactive: modal, worker thread, Esc cancels -------------------------------
    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        try:
            self._start(context)
        except (VisibilityInputError, *CORE_ERRORS) as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        self._cancel = False
        self._fraction = 0.0
        self._thread = None
        self._error = None
        self._result = None
        self._next = 0          # next frame index to gather
        self._traced = 0        # frames handed to the worker
        self._phase = "bake"
        self._seconds_bake = 0.0
        wm = context.window_manager
        wm.progress_begin(0, 1000)
        self._timer = wm.event_timer_add(0.02, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _worker(self, fn):
        def progress(fraction):
            self._fraction = fraction
            return not self._cancel

        def run():
            try:
                self._result = fn(progress)
            except BaseException as error:  # noqa: BLE001 - handed to the main thread
                self._error = error
        self._thread = threading.Thread(target=run, daemon=True)
        self._thread.start()

    def modal(self, context, event):
        if event.type == "ESC":
            self._cancel = True
        if event.type != "TIMER":
            return {"RUNNING_MODAL"}
        if self._thread is not None and self._thread.is_alive():
            self._show_progress(context)
            return {"RUNNING_MODAL"}
        self._thread = None
        if self._error is not None or self._cancel:
            return self._stop(context, self._error)
        job = self._job
        try:
            if self._phase == "bake":
                # Read, then trace (reading the next frame while tracing measured
                # slower on two cores: see bake_frames).
                if self._next < len(job.frames):
                    gathered = job.gather(job.frames[self._next])
                    self._next += 1
                    self._traced += 1
                    self._worker(lambda progress, g=gathered: job.bake(g, progress))
                else:
                    job.restore_frame()
                    self._seconds_bake = time.perf_counter() - self._started
                    self._phase = "fit"
                    self._fit_started = time.perf_counter()
                    self._worker(lambda progress: fit_model(job.training, job.influence, self._settings["lobes"],
                                                            job.threads, progress))
            elif self._phase == "fit":
                self._finish(context, self._result, self._seconds_bake)
                return self._stop(context, None, finished=True)
        except (VisibilityInputError, *CORE_ERRORS) as error:
            return self._stop(context, error)
        self._show_progress(context)
        return {"RUNNING_MODAL"}

    def _show_progress(self, context):
        job = self._job
        if self._phase == "bake":
            done = (max(self._traced - 1, 0) + (self._fraction if self._thread else 1.0)) / len(job.frames)
            overall, text = 0.9 * done, f"Baking visibility: frame {self._traced}/{len(job.frames)}"
        else:
            overall, text = 0.9 + 0.1 * self._fraction, "Fitting the pose model"
        context.window_manager.progress_update(int(1000 * overall))
        if context.workspace:
            context.workspace.status_text_set(f"{text} ({100 * overall:.0f}%) — Esc to cancel")

    def _stop(self, context, error, finished=False):
        if self._thread is not None and self._thread.is_alive():
            self._cancel = True  # the C++ side stops at its next progress report (<= 50 ms)
            self._thread.join()
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace:
            context.workspace.status_text_set(None)
        self._job.restore_frame()
        if finished:
            return {"FINISHED"}
        if error is None or isinstance(error, native.require().Cancelled):
            self.report({"WARNING"}, "Visibility bake cancelled; the earlier model is untouched")
        else:
            self.report({"ERROR"}, describe(error))
        return {"CANCELLED"}


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
