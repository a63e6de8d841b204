"""Tests that need Blender's window manager: modal operators, their timers
and events. `blender -b` and the bpy modules have no event loop (the bpy
4.5/5.2 modules even report one window, but nothing ever dispatches its
events), so these run in Debian's Blender 3.4 with a window under Xvfb:

    xvfb-run -a -s "-screen 0 1280x1024x24" blender -p 0 0 640 480 --factory-startup \\
        --enable-event-simulate --python tests/blender/pytest_in_blender.py -- ARGS

(run_blender_tests.py's fourth run). Blender's event loop only turns once
the --python script has returned, so pytest_in_blender.py runs pytest in a
worker thread, and every bpy call a test makes is handed to Blender's main
thread with on_main(), which a timer runs between two turns of the loop; the
loop goes on (modal handlers, timers, simulated events) while the test
waits. A small window keeps each turn fast: under Xvfb's software OpenGL a
full-size one is redrawn at about one turn a second, 640x480 at ~20.

Test files whose names end in `_window.py` hold such tests; conftest.py
collects them only in a windowed Blender and every other test file only in
a background one, so neither kind is skipped in the other."""

import queue
import sys
import threading
import time
import traceback

import bpy

_calls = queue.Queue()
_exit_status = []  # pytest's status once it has ended


def windowed():
    """Whether this Blender has a window manager that dispatches events."""
    return not bpy.app.background


def _pump():
    """Runs the calls the worker handed over (a bpy.app.timers callback)."""
    if _exit_status:
        # On the main thread Blender honours SystemExit from a timer: it
        # quits with this status (wm.quit_blender would exit with 0).
        raise SystemExit(_exit_status[0])
    while True:
        try:
            fn, box, done = _calls.get_nowait()
        except queue.Empty:
            return 0.01
        try:
            box.append((True, fn()))
        except BaseException as error:  # handed back to the caller's thread
            box.append((False, error))
        done.set()


def on_main(fn, timeout=60.0):
    """fn() on Blender's main thread, between two turns of the event loop;
    returns its value or raises its exception here."""
    box, done = [], threading.Event()
    _calls.put((fn, box, done))
    if not done.wait(timeout):
        raise TimeoutError(f"Blender's main thread did not run {fn!r} within {timeout} s")
    ok, value = box[0]
    if not ok:
        raise value
    return value


def wait_until(condition, timeout=60.0, interval=0.02):
    """Calls condition() on the main thread until it returns something true
    (returned), while the event loop turns; TimeoutError after `timeout` s."""
    end = time.monotonic() + timeout
    while True:
        value = on_main(condition)
        if value:
            return value
        if time.monotonic() > end:
            raise TimeoutError(f"{condition!r} still false after {timeout} s")
        time.sleep(interval)


def let_the_loop_turn(times):
    """Returns after Blender's event loop has turned at least `times` times
    (each call waits for the pump, which runs once per turn)."""
    for _ in range(times):
        on_main(lambda: None)


def run_pytest(args):
    """Starts pytest on a worker thread and returns; Blender's event loop
    then runs. When pytest ends, Blender exits with pytest's status."""
    import pytest

    def worker():
        status = 1
        try:
            # The splash screen takes the first Esc; close it before any test.
            on_main(_close_splash)
            time.sleep(0.5)
            status = int(pytest.main(args))
        except BaseException:
            traceback.print_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            _exit_status.append(status)

    # persistent: a test that loads a file must not stop the pump.
    bpy.app.timers.register(_pump, first_interval=0.0, persistent=True)
    threading.Thread(target=worker, name="pytest", daemon=True).start()


def _close_splash():
    window = bpy.context.window_manager.windows[0]
    for value in ("PRESS", "RELEASE"):
        window.event_simulate(type="ESC", value=value, x=window.width // 2, y=window.height // 2)
