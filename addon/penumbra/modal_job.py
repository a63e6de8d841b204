"""How a long operator runs: modal from the UI, synchronously from a script,
with the same progress, cancel, undo step and exception policy in both.

The colour-map bake, the visibility bake and the light-rig build each hand
this module a Job; their operators take execute, invoke, modal and cancel
from JobOperator, which calls the functions of the same names here.

- Progress: the job's `fraction` (0..1), on Blender's progress cursor on one
  scale (PROGRESS_SCALE); from the UI also the job's status() in the header
  of the area the operator runs in, refreshed every TIMER_SECONDS; from a
  script printed to the console about once a second.
- Cancel: Esc or a right-click from the UI; a progress listener that returns
  False from a script; Blender's own cancel() of a modal operator (a file
  loaded, the window closed). A worker sees it as its progress callback
  returning False; the job ends at its next step, its own `finally` blocks
  run, and the job's cancelled_message is reported as a warning.
- Undo: the operator returns FINISHED once, after the job's last step wrote
  the result, and Blender pushes the undo step of an operator with 'UNDO' in
  bl_options then, from execute and from modal alike; one undo removes the
  result. A failed or cancelled job returns CANCELLED and pushes no step.
- Exceptions: an Exception from the job (a worker, a main-thread step, or
  making the job) is reported to the user as an error and ends the job; the
  job leaves the user's data as it was (it writes only in its last step, and
  puts back what it changed in `finally` blocks). One that is not a core
  error (errors.CORE_ERRORS, bad input the user can fix) is a bug, and its
  traceback also goes to the console. A BaseException that is not an
  Exception (KeyboardInterrupt, SystemExit) ends the job the same way and is
  raised again on Blender's main thread.

A job's steps() is a generator that runs on the main thread, where bpy is
allowed:
    yield fraction              a main-thread step is done (from the UI:
                                Blender's event loop turns until the next tick)
    value = yield Worker(...)   work(progress) runs without bpy on a worker
                                thread (from a script: right there); its value
                                comes back, or its exception is raised here
    return reports              [(kind, message)] for a finished job

Modal operators return RUNNING_MODAL for every other event while a job runs:
an edit or an undo meanwhile could free the data the job holds (colour
maps check what they were built from again before applying, for edits from
another window or a script).

This is the only module of the add-on that starts a thread for an operator
(visibility/bake.py's overlapped bake_frames says why it starts its own)."""

import threading
import time
import traceback

import bpy

from .errors import CORE_ERRORS, describe

TIMER_SECONDS = 0.01  # a light-rig frame is a main-thread step: one a tick
PROGRESS_SCALE = 1000
CANCEL_EVENTS = ("ESC", "RIGHTMOUSE")

_running = []  # jobs running modally, oldest first


class Worker:
    """A step that runs work(progress) on a worker thread, without bpy (the
    core releases the GIL). progress(fraction), 0..1, moves the job's fraction
    from `start` to `end` and returns False once the job is cancelled."""

    def __init__(self, work, start=0.0, end=1.0):
        self.work, self.start, self.end = work, start, end


class Job:
    """One run of a long operator. Subclasses give steps() and the messages."""

    cancelled_message = "Cancelled; nothing was changed"

    def __init__(self):
        self.fraction = 0.0
        self.cancelled = False

    def steps(self):
        raise NotImplementedError

    def status(self):
        """What the job is doing now, for the header and the console."""
        return ""

    def failure(self, error):
        """The error report for an Exception that ended the job."""
        return describe(error)

    def cancel(self):
        self.cancelled = True


class JobOperator:
    """A mix-in for an operator run by this module: the operator gives
    make_job(context), which checks its input and returns the Job (an
    exception there is reported and nothing runs)."""

    def execute(self, context):
        return execute(self, context, lambda: self.make_job(context))

    def invoke(self, context, event):
        return invoke(self, context, lambda: self.make_job(context))

    def modal(self, context, event):
        return modal(self, context, event)

    def cancel(self, context):
        cancel(self, context)


def running():
    """The jobs running modally from the UI (a script or a test can read their
    progress between two timer ticks)."""
    return list(_running)


class _Run:
    """Drives a job's steps() one yield at a time, in either mode."""

    def __init__(self, job):
        self.job = job
        self.steps = job.steps()
        self.outcome = (None, None)  # (value, error) of the last worker, handed to the job on resume
        self.thread = None  # the worker in flight (modal)
        self.timer = None

    def next(self):
        """Resumes the job; returns its next Worker or fraction, or
        ("done", reports) when it returned. Its exceptions propagate."""
        value, error = self.outcome
        self.outcome = (None, None)
        try:
            item = self.steps.throw(error) if error is not None else self.steps.send(value)
        except StopIteration as end:
            return "done", end.value or []
        if not isinstance(item, Worker):
            self.job.fraction = float(item)
        return item

    def progress_for(self, worker, listener=None):
        job = self.job

        def progress(fraction):
            job.fraction = worker.start + (worker.end - worker.start) * min(max(fraction, 0.0), 1.0)
            if listener is not None and listener(job.fraction) is False:
                job.cancel()
            return not job.cancelled
        return progress

    def call(self, worker, progress):
        try:
            self.outcome = (worker.work(progress), None)
            self.job.fraction = worker.end
        except BaseException as error:  # noqa: BLE001 - handed to the job on the main thread
            self.outcome = (None, error)

    def close(self):
        """Ends the job where it stands (its `finally` blocks run). A
        KeyboardInterrupt or SystemExit of the last worker is raised here."""
        error = self.outcome[1]
        if error is not None and not isinstance(error, Exception):
            self.next()  # raises it through the job
        self.steps.close()


def _cancelled(op, run):
    try:
        run.close()
    except Exception as error:  # noqa: BLE001 - the policy: reported
        return _finish(op, run.job, error)
    return _finish(op, run.job, "cancelled")


def _finish(op, job, end):
    """The operator's result for how the job ended: ("done", reports),
    "cancelled" or an Exception."""
    if isinstance(end, tuple):
        for kind, message in end[1]:
            op.report({kind}, message)
        return {"FINISHED"}
    if end == "cancelled":
        op.report({"WARNING"}, job.cancelled_message)
    else:
        _report_failure(op, job.failure(end), end)
    return {"CANCELLED"}


def _report_failure(op, message, error):
    if not isinstance(error, CORE_ERRORS):
        traceback.print_exception(type(error), error, error.__traceback__)
    op.report({"ERROR"}, message)


def _made(op, make_job):
    try:
        return make_job()
    except Exception as error:  # noqa: BLE001 - the policy: reported
        _report_failure(op, describe(error), error)
        return None


# Synchronous: scripts, background Blender -----------------------------------------

def execute(op, context, make_job, progress=None):
    """Runs the job made by make_job() to its end on this thread. `progress`
    (fraction) is called as the job advances and cancels it by returning
    False. Returns the operator's result."""
    job = _made(op, make_job)
    if job is None:
        return {"CANCELLED"}
    wm = context.window_manager
    printed = [time.perf_counter()]

    def listen(fraction):
        wm.progress_update(int(PROGRESS_SCALE * fraction))
        now = time.perf_counter()
        if now - printed[0] > 1.0:
            printed[0] = now
            print(f"penumbra: {job.status()} {100.0 * fraction:5.1f}%", flush=True)
        return progress is None or progress(fraction) is not False

    run = _Run(job)
    wm.progress_begin(0, PROGRESS_SCALE)
    try:
        while True:
            if job.cancelled:
                return _cancelled(op, run)
            try:
                item = run.next()
            except Exception as error:  # noqa: BLE001 - the policy: reported
                return _finish(op, job, error)
            if isinstance(item, tuple):
                return _finish(op, job, item)
            if isinstance(item, Worker):
                run.call(item, run.progress_for(item, listen))
            if not listen(job.fraction):
                job.cancel()
    except BaseException:
        run.steps.close()
        raise
    finally:
        wm.progress_end()


# Modal: from the UI -----------------------------------------------------------------

def invoke(op, context, make_job):
    """Starts the job made by make_job() as a modal operator: a timer advances
    it; RUNNING_MODAL. Without an event loop (background Blender, the bpy
    module: no TIMER would ever arrive) it runs as execute does. A stand-in
    window manager (a test driving modal() itself) counts as a loop."""
    if bpy.app.background and isinstance(context.window_manager, bpy.types.WindowManager):
        return execute(op, context, make_job)
    job = _made(op, make_job)
    if job is None:
        return {"CANCELLED"}
    run = _Run(job)
    wm = context.window_manager
    wm.progress_begin(0, PROGRESS_SCALE)
    run.timer = wm.event_timer_add(TIMER_SECONDS, window=context.window)
    op._modal_job = run
    _running.append(job)
    wm.modal_handler_add(op)
    return {"RUNNING_MODAL"}


def modal(op, context, event):
    run = op._modal_job
    job = run.job
    if job not in _running:  # ended by an exception raised from here; Blender may call once more
        return {"CANCELLED"}
    if event.type in CANCEL_EVENTS and event.value == "PRESS":
        job.cancel()
    elif event.type != "TIMER":
        return {"RUNNING_MODAL"}
    if run.thread is not None:
        if run.thread.is_alive():
            _show(context, job)
            return {"RUNNING_MODAL"}
        run.thread = None
    try:
        if job.cancelled:
            _end(context, run)
            return _cancelled(op, run)
        try:
            item = run.next()
        except Exception as error:  # noqa: BLE001 - the policy: reported
            _end(context, run)
            return _finish(op, job, error)
        if isinstance(item, tuple):
            _end(context, run)
            return _finish(op, job, item)
        if isinstance(item, Worker):
            run.thread = threading.Thread(target=run.call, args=(item, run.progress_for(item)), daemon=True)
            run.thread.start()
        _show(context, job)
        return {"RUNNING_MODAL"}
    except BaseException:
        _end(context, run)
        run.steps.close()
        raise


def cancel(op, context):
    """Blender ends a modal operator this way (a file loaded, the window
    closed): the worker is asked to stop and waited for (the core checks its
    progress callback at least every 50 ms), then the job ends as after Esc,
    without a report (the operator is gone)."""
    run = getattr(op, "_modal_job", None)
    if run is None or run.job not in _running:
        return
    run.job.cancel()
    if run.thread is not None:
        run.thread.join()
        run.thread = None
    _end(context, run)
    run.close()


def _show(context, job):
    context.window_manager.progress_update(int(PROGRESS_SCALE * job.fraction))
    if context.area and job.status():
        context.area.header_text_set(f"{job.status()} (Esc to cancel)")


def _end(context, run):
    """Takes the job's timer, progress and header away, once; the job stops
    counting as running."""
    if run.job not in _running:
        return
    _running.remove(run.job)
    wm = context.window_manager
    wm.event_timer_remove(run.timer)
    wm.progress_end()
    if context.area:
        context.area.header_text_set(None)
