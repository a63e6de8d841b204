"""A small operator and job for the tests of modal_job.py (test_modal_job.py
in the background, test_modal_job_window.py in a window): main-thread steps
that change the frame and put it back, as the visibility bake poses the
scene, then a worker, then the result written in the last step, as every
Penumbra job does."""

import threading

import bpy

from penumbra import modal_job

RESULT = "Modal Job Probe"  # the object a finished probe adds
STEPS = 3
SETUP = {"job": None, "progress": None}  # what the next run of the operator uses


class ProbeJob(modal_job.Job):
    """STEPS frames set on the main thread, then `work(progress)` on a worker;
    its value goes on the RESULT object it adds."""

    cancelled_message = "Probe cancelled; nothing was changed"

    def __init__(self, work, on_step=None):
        super().__init__()
        self.work = work
        self.on_step = on_step or (lambda job, k: None)
        self.worker_threads = []
        self.failures = []  # the exceptions the helper asked a report for

    def status(self):
        return f"Probe ({100 * self.fraction:.0f}%)"

    def failure(self, error):
        self.failures.append(error)
        return super().failure(error)

    def steps(self):
        scene = bpy.context.scene
        frame = scene.frame_current
        try:
            for k in range(STEPS):
                scene.frame_set(frame + k + 1)
                self.on_step(self, k)
                yield 0.5 * (k + 1) / STEPS
            value = yield modal_job.Worker(self._work, 0.5, 1.0)
        finally:
            scene.frame_set(frame)
        result = bpy.data.objects.new(RESULT, None)
        scene.collection.objects.link(result)
        result["value"] = value
        return [("INFO", f"Probe finished with {value}")]

    def _work(self, progress):
        self.worker_threads.append(threading.get_ident())
        return self.work(progress)


class PENUMBRA_OT_modal_job_probe(modal_job.JobOperator, bpy.types.Operator):
    """Runs SETUP['job']() through modal_job, as the add-on's operators do (tests only)"""
    bl_idname = "penumbra_test.modal_job_probe"
    bl_label = "Modal Job Probe"
    bl_options = {"REGISTER", "UNDO"}

    modal_raised = []   # (exception, thread id) that modal() raised

    def make_job(self, context):
        return SETUP["job"]()

    def execute(self, context):
        # As JobOperator's, with the test's progress listener.
        return modal_job.execute(self, context, lambda: self.make_job(context), progress=SETUP["progress"])

    def modal(self, context, event):
        try:
            return super().modal(context, event)
        except BaseException as error:
            type(self).modal_raised.append((error, threading.get_ident()))
            raise


def register():
    bpy.utils.register_class(PENUMBRA_OT_modal_job_probe)


def unregister():
    bpy.utils.unregister_class(PENUMBRA_OT_modal_job_probe)


def state():
    """What a job must leave as it was: the frame and the objects."""
    scene = bpy.context.window.scene if bpy.context.window else bpy.context.scene
    return scene.frame_current, sorted(o.name for o in bpy.data.objects)
