"""modal_job.py's modal path, driven by Blender's own event loop (3.4 in a
window under Xvfb, blender_window.py): the timer moves a job through its
main-thread steps and its worker, Esc or a right-click cancels it, an
exception from the worker is reported and a KeyboardInterrupt raised again
on the main thread, each leaving the data as it was; and a real operator,
the colour-map bake, with an injected worker failure and with the one undo
step that takes its result back. The light-rig build's modal path (frames,
Esc, a file loaded meanwhile) is tested in lights/test_light_rig_window.py;
the synchronous path of the same helper in test_modal_job.py."""

import os
import threading
import time

import bpy
import pytest

from blender_window import let_the_loop_turn, on_main, wait_until

import modal_job_probe as probe

WORKER_SECONDS = 1.0  # a worker that fails runs this long first: several timer ticks


@pytest.fixture(scope="module")
def addon():
    def register():
        import penumbra
        penumbra.register()
        probe.register()
        return penumbra

    penumbra = on_main(register)
    yield penumbra
    on_main(lambda: (probe.unregister(), penumbra.unregister()))


@pytest.fixture
def probe_op(addon):
    probe.PENUMBRA_OT_modal_job_probe.modal_raised.clear()
    yield
    # A test that failed half-way may leave its job running: end it, so the next starts alone.
    wait_until(lambda: _press_once("ESC") if _running() else True, timeout=30)
    wait_until(lambda: not _running(), timeout=30)

    def remove_result():
        for obj in [o for o in bpy.data.objects if o.name.startswith(probe.RESULT)]:
            bpy.data.objects.remove(obj)
    on_main(remove_result)


def _running():
    from penumbra import modal_job
    return modal_job.running()


def _in_3d_view(call):
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region):
        return call()


def _press_once(event_type):
    window = bpy.context.window_manager.windows[0]
    for value in ("PRESS", "RELEASE"):
        window.event_simulate(type=event_type, value=value, x=window.width // 2, y=window.height // 2)
    return True


def _slow(progress, until_cancelled=False):
    """A worker of about WORKER_SECONDS (or until cancelled), stopping as the core does."""
    end = time.monotonic() + (120.0 if until_cancelled else WORKER_SECONDS)
    while time.monotonic() < end:
        fraction = min(1.0, 1.0 - (end - time.monotonic()) / WORKER_SECONDS)
        if not progress(0.0 if until_cancelled else fraction):
            raise RuntimeError("Cancelled")
        time.sleep(0.01)
    return 7


def _start_probe(work, on_step=None):
    """Invokes the probe as a click does; returns the job, which no step has touched yet."""
    job = probe.ProbeJob(work, on_step)
    probe.SETUP["job"] = lambda: job
    before = probe.state()
    assert _in_3d_view(lambda: bpy.ops.penumbra_test.modal_job_probe("INVOKE_DEFAULT")) == {"RUNNING_MODAL"}
    assert _running() == [job] and job.fraction == 0.0 and probe.state() == before
    return job


def test_the_timer_moves_a_job_through_its_steps_and_its_worker(probe_op):
    gate = threading.Event()

    def gated(progress):
        """Reports 1/4, 2/4, 3/4, each held until the test has seen it."""
        for k in (1, 2, 3):
            progress(k / 4)
            assert gate.wait(30)
            gate.clear()
        return 7

    # Each main-thread step notes the fraction it starts from and how many
    # turns Blender's loop has made (an app timer run every turn counts them):
    # read on the main thread as the steps run, so no polling can miss a step.
    turns, steps = [0], []

    def count_turn():
        turns[0] += 1
        return 0.0 if _running() or not steps else None

    before = on_main(probe.state)
    on_main(lambda: bpy.app.timers.register(count_turn, first_interval=0.0))
    job = on_main(lambda: _start_probe(gated, on_step=lambda job, k: steps.append((job.fraction, turns[0]))))

    # The steps' half, one main-thread step a timer tick, then the worker's.
    wait_until(lambda: job.fraction >= 0.5 or not _running(), timeout=30)
    for fraction in (0.625, 0.75, 0.875):
        wait_until(lambda: job.fraction >= fraction, timeout=30)
        assert on_main(_running) == [job]  # Blender's loop turns while the worker runs
        gate.set()
    wait_until(lambda: not _running(), timeout=30)
    assert [f for f, _ in steps] == pytest.approx([0.0, 1 / 6, 2 / 6]), steps
    assert all(a < b for (_, a), (_, b) in zip(steps, steps[1:])), f"two steps in one turn of the loop: {steps}"
    assert job.worker_threads and job.worker_threads[0] != on_main(threading.get_ident)
    assert on_main(lambda: bpy.data.objects[probe.RESULT]["value"]) == 7
    assert on_main(probe.state)[0] == before[0] and job.failures == []
    let_the_loop_turn(2)  # the timer went with the job
    assert on_main(_running) == []


@pytest.mark.parametrize("key", ["ESC", "RIGHTMOUSE"])
def test_esc_or_a_right_click_cancels_a_job_and_leaves_the_data_as_it_was(probe_op, key):
    before = on_main(probe.state)
    job = on_main(lambda: _start_probe(lambda progress: _slow(progress, until_cancelled=True)))
    wait_until(lambda: job.worker_threads, timeout=30)  # the worker is running
    started = time.monotonic()
    on_main(lambda: _press_once(key))
    wait_until(lambda: not _running(), timeout=90)
    assert time.monotonic() - started < 60  # the worker stopped: it would run 120 s
    assert on_main(probe.state) == before and job.failures == []  # a cancel, not a failure


def test_an_exception_from_the_worker_is_reported_and_leaves_the_data_as_it_was(probe_op):
    def fails(progress):
        _slow(progress)
        raise ValueError("the probe's input is bad")

    before = on_main(probe.state)
    job = on_main(lambda: _start_probe(fails))
    wait_until(lambda: not _running(), timeout=60)
    assert on_main(probe.state) == before
    assert [str(error) for error in job.failures] == ["the probe's input is bad"]  # reported as an error


def test_a_keyboard_interrupt_ends_the_job_and_is_raised_on_the_main_thread(probe_op):
    def interrupted(progress):
        progress(0.5)
        raise KeyboardInterrupt

    before = on_main(probe.state)
    job = on_main(lambda: _start_probe(interrupted))
    wait_until(lambda: not _running(), timeout=60)
    raised = probe.PENUMBRA_OT_modal_job_probe.modal_raised
    assert [(type(e), thread) for e, thread in raised] == [(KeyboardInterrupt, on_main(threading.get_ident))]
    assert on_main(probe.state) == before and job.failures == []  # raised, not reported
    let_the_loop_turn(2)  # no timer left to tick into the ended job
    assert len(raised) == 1


# A real operator: the colour-map bake from the UI -------------------------------------

@pytest.fixture
def ramp_scene(addon, tmp_path):
    """A plane with a ramp, active in the window's view layer."""
    from colormap_scenes import make_ramp_material

    def build():
        settings = bpy.context.scene.penumbra.colormap
        settings.output_folder = str(tmp_path / "luts")
        settings.lut_width = settings.lut_height = 16
        material, ramp = make_ramp_material("Modal ramped", noise=False)
        mesh = bpy.data.meshes.new("Modal plane")
        mesh.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
        mesh.materials.append(material)
        obj = bpy.data.objects.new("Modal plane", mesh)
        bpy.context.scene.collection.objects.link(obj)
        bpy.context.window_manager.windows[0].view_layer.objects.active = obj
        return material.name, ramp.name

    names = on_main(build)
    yield names

    def remove():
        for kind, name in (("objects", "Modal plane"), ("meshes", "Modal plane"), ("materials", names[0])):
            block = getattr(bpy.data, kind).get(name)
            if block is not None:
                getattr(bpy.data, kind).remove(block)
    on_main(remove)


def _ramp_state(names):
    """The material's nodes and the ramp's mute, with the data-blocks a bake adds."""
    material = bpy.data.materials[names[0]]
    return (sorted(n.name for n in material.node_tree.nodes), material.node_tree.nodes[names[1]].mute,
            sorted(i.name for i in bpy.data.images), sorted(g.name for g in bpy.data.node_groups),
            sorted(o.name for o in bpy.data.objects))


def _bake_in_the_window():
    assert _in_3d_view(lambda: bpy.ops.penumbra.bake_colormap_lut("INVOKE_DEFAULT")) == {"RUNNING_MODAL"}
    return True


def test_a_colour_map_bake_whose_worker_fails_leaves_the_material_as_it_was(ramp_scene):
    from penumbra import native
    testing = native.require().testing
    before = on_main(lambda: _ramp_state(ramp_scene))
    testing.inject_worker_failure("colormap", "runtime_error")
    try:
        on_main(_bake_in_the_window)
        wait_until(lambda: not _running(), timeout=60)
    finally:
        testing.inject_worker_failure("colormap", "none")
    assert on_main(lambda: _ramp_state(ramp_scene)) == before


def test_one_undo_takes_a_modal_colour_map_bake_back(ramp_scene):
    def checkpoint():
        # A step for the scene as built, then the user's last edit before the bake.
        _in_3d_view(lambda: bpy.ops.ed.undo_push(message="ramp scene"))
        bpy.context.scene.collection.objects.link(bpy.data.objects.new("Modal undo marker", None))
        _in_3d_view(lambda: bpy.ops.ed.undo_push(message="marker"))
        return _ramp_state(ramp_scene)

    before = on_main(checkpoint)
    on_main(_bake_in_the_window)
    wait_until(lambda: not _running(), timeout=60)
    baked = on_main(lambda: _ramp_state(ramp_scene))
    assert baked[1] and baked != before  # the ramp is muted, the group and lookup added
    assert on_main(lambda: _in_3d_view(bpy.ops.ed.undo)) == {"FINISHED"}
    # Exactly the bake's step: the marker, pushed just before, is still there.
    assert on_main(lambda: _ramp_state(ramp_scene)) == before
    on_main(lambda: bpy.data.objects.remove(bpy.data.objects["Modal undo marker"]))


# A real operator with worker phases between main-thread steps: the visibility bake --------

VISIBILITY_FRAMES = 10


@pytest.fixture
def character_scene(addon, tmp_path):
    """The small character, active, and where its model goes."""
    from visibility_character_scenes import character

    def build():
        obj, rig = character(bpy.context.scene, frames=VISIBILITY_FRAMES)
        bpy.context.window_manager.windows[0].view_layer.objects.active = obj
        return obj.name, rig.name

    names = on_main(build)
    yield names, str(tmp_path / "model.pzh")

    def remove():
        for name in names:
            bpy.data.objects.remove(bpy.data.objects[name])
    on_main(remove)


def _bake_visibility(path):
    return _in_3d_view(lambda: bpy.ops.penumbra.bake_visibility(
        "INVOKE_DEFAULT", frame_start=1, frame_end=VISIBILITY_FRAMES, frame_step=1, rays=16, lobes=1,
        filepath=path))


def _visibility_state(name):
    obj = bpy.data.objects[name]
    return bpy.context.scene.frame_current, obj.penumbra_visibility.model_path, obj.penumbra_visibility.report


def test_a_modal_visibility_bake_traces_frame_by_frame_then_fits_and_stores_the_model(character_scene):
    (name, _), path = character_scene
    before = on_main(lambda: _visibility_state(name))
    assert on_main(lambda: _bake_visibility(path)) == {"RUNNING_MODAL"}
    job = on_main(_running)[0]
    traced = []

    def finished():
        if _running():
            traced.append(job.traced)
            return False
        return True

    wait_until(finished, timeout=120)
    assert traced == sorted(traced) and len(set(traced)) >= 3, traced  # a frame a step, across loop turns
    frame, model_path, report = on_main(lambda: _visibility_state(name))
    assert frame == before[0] and model_path == path and report != before[2]
    assert os.path.isfile(path)


def test_esc_during_a_modal_visibility_bake_leaves_the_frame_and_the_model_as_they_were(character_scene):
    (name, _), path = character_scene
    before = on_main(lambda: _visibility_state(name))
    assert on_main(lambda: _bake_visibility(path)) == {"RUNNING_MODAL"}
    job = on_main(_running)[0]
    wait_until(lambda: job.traced >= 2 and _press_once("ESC"), timeout=60)
    wait_until(lambda: not _running(), timeout=60)
    assert job.cancelled and job.traced < VISIBILITY_FRAMES and not job.fitting
    assert on_main(lambda: _visibility_state(name)) == before
    assert not os.path.exists(path)
