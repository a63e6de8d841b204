"""The light-rig operator's modal path, driven by Blender's own event loop:
invoke() from the 3D View, one frame per TIMER event, the progress it
reports, Esc, and the rig a full run leaves.

Only in Debian's Blender 3.4 with a window under Xvfb (blender_window.py,
run_blender_tests.py's fourth run). `blender -b` and the bpy 4.5 / 5.2
modules cannot run these: they have no event loop, so a modal operator
started there never receives a TIMER or an Esc (the bpy modules even show
one window, whose events nothing dispatches). There,
tests/blender/test_bad_input.py drives the same invoke() and modal() code
with stand-in events instead.

The test runs on pytest's worker thread; every bpy call goes through
on_main(), so Blender's loop turns (timers fire, the operator steps, the
simulated Esc arrives) while the test waits."""

import json
import math
import os

import bpy
import pytest

import lights_scenes
from blender_window import let_the_loop_turn, on_main, wait_until

FRAMES = 24
LIGHTS = 6


@pytest.fixture(scope="module")
def addon():
    yield from lights_scenes.window_addon()


@pytest.fixture
def scene(addon):
    """A new, empty scene shown in the window (the operator builds into the
    window's scene); the previous scene comes back afterwards (by name: a
    test may have loaded another file)."""
    def show_scene(name):
        window = bpy.context.window_manager.windows[0]
        previous = window.scene.name
        scene = bpy.data.scenes.get(name) or bpy.data.scenes.new(name)
        window.scene = scene
        return previous

    previous = on_main(lambda: show_scene("Modal Light Rig"))
    yield on_main(lambda: bpy.context.window_manager.windows[0].scene.name)
    # A test that failed half-way may leave its build running: stop it, so
    # that the next test starts alone.
    wait_until(lambda: _press_esc_once_running(0) is None and not _running(), timeout=30)
    on_main(lambda: show_scene(previous))


@pytest.fixture(scope="module")
def sequence(tmp_path_factory, addon):
    """FRAMES equirectangular EXRs of a sky and a sun that turns 5° a frame."""
    from lights_scenes import core_module, sky_and_sun

    folder = tmp_path_factory.mktemp("sky")
    core = on_main(core_module)
    sky = sky_and_sun(h=32, w=64, sky=0.05)
    for i in range(FRAMES):
        core.image.write_exr(str(folder / f"sky_{i + 1:04d}.exr"), core.lights.rotate_map_z(sky, math.radians(5 * i)),
                             half=False, colorspace="Linear")
    return str(folder / "sky_0001.exr")


def _invoke(filepath, json_path):
    """penumbra.build_light_rig as the Build button runs it: INVOKE_DEFAULT
    in the 3D View of the window."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region):
        return bpy.ops.penumbra.build_light_rig("INVOKE_DEFAULT", filepath=filepath, count=LIGHTS, frame_start=1,
                                                frame_end=FRAMES, json_path=json_path)


def _running():
    from penumbra.lights import operators
    return operators.running_builds()


def _data_state(json_path):
    """Every data-block's name by kind (a half-built rig or an orphan shows
    up here), the scene's rig settings, and the JSON."""
    state = {}
    for kind in dir(bpy.data):
        collection = getattr(bpy.data, kind, None)
        if isinstance(collection, bpy.types.bpy_prop_collection):
            state[kind] = sorted(block.name for block in collection)
    s = bpy.context.window_manager.windows[0].scene.penumbra.light_rig
    state["rig collection"] = s.collection.name if s.collection is not None else None
    state["last report"] = s.last_report
    state["json"] = os.path.exists(json_path)
    return state


def _press_esc_once_running(frames_done):
    """Once `frames_done` frames are in, queues Esc as a key press in the
    window (--enable-event-simulate); returns the progress it saw then."""
    running = _running()
    if not running or running[0][0] < frames_done:
        return None
    window = bpy.context.window_manager.windows[0]
    for value in ("PRESS", "RELEASE"):
        window.event_simulate(type="ESC", value=value, x=window.width // 2, y=window.height // 2)
    return running[0]


def test_esc_stops_the_modal_build_and_leaves_the_file_as_it_was(scene, sequence, tmp_path):
    json_path = str(tmp_path / "rig.json")
    before = on_main(lambda: _data_state(json_path))
    # invoke() returns before any frame: the frames come with the timer.
    assert on_main(lambda: (_invoke(sequence, json_path), _running())) == ({"RUNNING_MODAL"}, [(0, FRAMES)])
    done_at_esc, frames = wait_until(lambda: _press_esc_once_running(3))
    assert frames == FRAMES and 3 <= done_at_esc < FRAMES
    wait_until(lambda: _running() == [], timeout=30)
    # Cancelled part-way: nothing of the rig, no data-block added, no JSON.
    assert on_main(lambda: _data_state(json_path)) == before
    assert not os.path.exists(json_path + ".tmp")
    # The timer is gone with it: ten turns of the loop later (at least ten
    # frames' worth of ticks) still nothing has changed.
    let_the_loop_turn(10)
    assert on_main(_running) == []
    assert on_main(lambda: _data_state(json_path)) == before


def test_a_modal_build_reports_its_frames_and_builds_the_rig(scene, sequence, tmp_path):
    json_path = str(tmp_path / "rig.json")
    before = on_main(lambda: _data_state(json_path))
    assert on_main(lambda: (_invoke(sequence, json_path), _running())) == ({"RUNNING_MODAL"}, [(0, FRAMES)])
    seen = []

    def finished():
        running = _running()
        if running:
            seen.append(running[0])
        return not running

    wait_until(finished, timeout=120)
    # The progress advanced frame by frame, across turns of the event loop.
    done = [d for d, _ in seen]
    assert all(frames == FRAMES for _, frames in seen)
    assert done == sorted(done) and len({d for d in done if 0 < d < FRAMES}) >= 3, done

    def rig():
        from penumbra.lights.operators import PREVIEW_NAME
        from penumbra.lights.rig_objects import fcurve
        s = bpy.context.window_manager.windows[0].scene.penumbra.light_rig
        suns = [o for o in s.collection.objects if o.type == "LIGHT"] if s.collection else []
        keys = [len(fcurve(o.data, "energy").keyframe_points) for o in suns]
        return {"suns": len(suns), "keys": keys, "preview": PREVIEW_NAME in bpy.data.images,
                "report": s.last_report}

    built = on_main(rig)
    assert built["suns"] == LIGHTS and built["keys"] == [FRAMES] * LIGHTS, built
    assert built["preview"] and f"over {FRAMES} frame(s)" in built["report"]
    assert [f["frame"] for f in json.load(open(json_path))["frames"]] == list(range(1, FRAMES + 1))
    assert on_main(lambda: _data_state(json_path)) != before


def test_loading_a_file_during_a_modal_build_ends_it_through_cancel(scene, sequence, tmp_path):
    # Last in this file: it replaces the window's file with an empty one.
    json_path = str(tmp_path / "rig.json")
    assert on_main(lambda: (_invoke(sequence, json_path), _running())) == ({"RUNNING_MODAL"}, [(0, FRAMES)])
    wait_until(lambda: _running() and _running()[0][0] >= 2)

    def load_empty_file():
        # Blender ends every modal operator of the old file with cancel().
        bpy.ops.wm.read_homefile(use_empty=True)
        return _running()

    assert on_main(load_empty_file) == []
    let_the_loop_turn(10)
    assert on_main(_running) == []
    assert not os.path.exists(json_path) and not os.path.exists(json_path + ".tmp")
    assert on_main(lambda: [c.name for c in bpy.data.collections if c.name.startswith("Penumbra")]) == []
