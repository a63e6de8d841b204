"""modal_job.py run synchronously, as an operator's execute() runs it from a
script, in Blender 3.4 -b and the bpy 4.5 / 5.2 modules: the exception
policy (an Exception is reported and the data is left as it was; a
KeyboardInterrupt ends the job and is raised again), cancel (a progress
listener returning False, the job's own cancel flag, a worker seeing its
progress callback return False), progress and the one undo step of a
finished job. The modal path of the same helper: test_modal_job_window.py."""

import threading
import types

import bpy
import pytest

from penumbra import modal_job

import modal_job_probe as probe


@pytest.fixture
def probe_op(addon):
    probe.register()
    probe.SETUP.update(job=None, progress=None)
    yield bpy.ops.penumbra_test.modal_job_probe
    probe.unregister()


def counting(progress, value=42):
    """A worker that reports ten fractions, stopping if told to (as the core does)."""
    for k in range(10):
        if not progress(k / 10):
            raise RuntimeError("Cancelled")  # what the core raises (_penumbra.Cancelled is a RuntimeError)
    return value


def reports(capfd):
    """The reports of the runs since the last call (background Blender prints them)."""
    out, err = capfd.readouterr()
    return [line for line in (out + err).splitlines() if line.startswith(("Info: ", "Warning: ", "Error: "))]


def test_a_job_runs_its_steps_then_its_worker_and_writes_its_result(probe_op, capfd):
    seen = []
    job = probe.ProbeJob(counting)
    probe.SETUP.update(job=lambda: job, progress=lambda f: seen.append(f))
    before = probe.state()
    capfd.readouterr()
    assert probe_op() == {"FINISHED"}
    assert bpy.data.objects[probe.RESULT]["value"] == 42
    assert probe.state()[0] == before[0]  # the frame the steps moved is back
    # Progress on one scale: the steps' half, then the worker's, ending at 1.
    assert seen == sorted(seen) and seen[:3] == pytest.approx([1 / 6, 2 / 6, 3 / 6]) and seen[-1] == 1.0
    # From a script the worker runs on the calling thread.
    assert job.worker_threads == [threading.get_ident()]
    assert reports(capfd) == ["Info: Probe finished with 42"]


def test_one_undo_takes_a_finished_job_back(probe_op):
    probe.SETUP["job"] = lambda: probe.ProbeJob(counting)
    bpy.ops.ed.undo_push(message="before the probe")
    before = probe.state()
    assert probe_op("EXEC_DEFAULT", True) == {"FINISHED"}
    assert probe.RESULT in bpy.data.objects
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert probe.state() == before


@pytest.mark.parametrize("error", [ValueError("the probe's input is bad"), ZeroDivisionError("a bug in the probe")])
def test_an_exception_from_the_worker_is_reported_and_changes_nothing(probe_op, capfd, error):
    def fails(progress):
        progress(0.5)
        raise error

    job = probe.ProbeJob(fails)
    probe.SETUP["job"] = lambda: job
    before = probe.state()
    capfd.readouterr()
    with pytest.raises(RuntimeError, match=str(error)):
        probe_op()
    assert probe.state() == before and job.failures == [error]
    # A core error is the user's to fix: a message only. Any other is a bug:
    # its traceback goes to the console too.
    out, err = capfd.readouterr()
    assert ("Traceback" in out + err) == (not isinstance(error, ValueError)), out + err


def test_an_exception_from_a_main_thread_step_is_reported_and_changes_nothing(probe_op):
    def on_step(job, k):
        if k == 1:
            raise OSError("the probe cannot read its file")

    probe.SETUP["job"] = lambda: probe.ProbeJob(counting, on_step)
    before = probe.state()
    with pytest.raises(RuntimeError, match="cannot read its file"):
        probe_op()
    assert probe.state() == before


def test_an_exception_while_making_the_job_is_reported(probe_op):
    def make():
        raise ValueError("no such thing to probe")

    probe.SETUP["job"] = make
    with pytest.raises(RuntimeError, match="no such thing to probe"):
        probe_op()


class _Op:
    """An operator's report() outside bpy.ops, which turns every exception
    into a RuntimeError and so would hide whether one was raised again."""

    def __init__(self):
        self.reports = []

    def report(self, kinds, message):
        self.reports.append((set(kinds), message))


def test_a_keyboard_interrupt_ends_the_job_and_is_raised_again(probe_op):
    def interrupted(progress):
        progress(0.3)
        raise KeyboardInterrupt

    job = probe.ProbeJob(interrupted)
    before = probe.state()
    op = _Op()
    context = types.SimpleNamespace(window_manager=bpy.context.window_manager)
    with pytest.raises(KeyboardInterrupt):
        modal_job.execute(op, context, lambda: job)
    assert probe.state() == before and op.reports == []


def test_a_progress_listener_returning_false_cancels_between_steps(probe_op, capfd):
    job = probe.ProbeJob(counting)
    probe.SETUP.update(job=lambda: job, progress=lambda fraction: fraction < 0.3)
    before = probe.state()
    capfd.readouterr()
    assert probe_op() == {"CANCELLED"}
    assert probe.state() == before
    assert job.worker_threads == []  # stopped before the worker
    assert reports(capfd) == ["Warning: Probe cancelled; nothing was changed"]


def test_a_progress_listener_returning_false_stops_the_worker(probe_op, capfd):
    calls = []

    def work(progress):
        calls.append(0)
        return counting(progress)

    probe.SETUP.update(job=lambda: probe.ProbeJob(work), progress=lambda fraction: fraction < 0.7)
    before = probe.state()
    capfd.readouterr()
    # The worker's Cancelled is the cancel, reported as such, not as a failure.
    assert probe_op() == {"CANCELLED"}
    assert calls == [0] and probe.state() == before
    assert reports(capfd) == ["Warning: Probe cancelled; nothing was changed"]


def test_the_jobs_cancel_flag_ends_it_at_its_next_step(probe_op, capfd):
    def on_step(job, k):
        if k == 0:
            job.cancel()

    job = probe.ProbeJob(counting, on_step)
    probe.SETUP["job"] = lambda: job
    before = probe.state()
    capfd.readouterr()
    assert probe_op() == {"CANCELLED"}
    assert probe.state() == before and job.worker_threads == []
    assert reports(capfd) == ["Warning: Probe cancelled; nothing was changed"]


def test_invoke_without_an_event_loop_runs_the_job_to_its_end(probe_op):
    # Background Blender and the bpy modules never send a TIMER: a modal run would never end.
    probe.SETUP["job"] = lambda: probe.ProbeJob(counting)
    assert probe_op("INVOKE_DEFAULT") == {"FINISHED"}
    assert modal_job.running() == [] and probe.RESULT in bpy.data.objects
