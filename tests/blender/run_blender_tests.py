#!/usr/bin/env python3
"""Runs tests/blender in all three Blenders, every time:
  - Debian's `blender` 3.4, as `blender -b --factory-startup`;
  - the bpy 4.5 module from .venv (Python 3.11);
  - the bpy 5.2 module from .venv313 (Python 3.13);
  - Debian's `blender` 3.4 again, in a window under Xvfb, for the tests of
    modal operators, timers and events (`*_window.py`, blender_window.py),
    which the three above leave out (they have no event loop).
A Blender (or xvfb-run) that is missing is a failure, not a skip. Prints
each run's pytest summary and, last, the combined line
"blender: N passed, N failed"."""

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TESTS = os.path.join(ROOT, "tests", "blender")
BPY_MODULES = (("bpy 4.5 (.venv)", os.path.join(ROOT, ".venv", "bin", "python")),
               ("bpy 5.2 (.venv313)", os.path.join(ROOT, ".venv313", "bin", "python")))


def counts_from_junit(path):
    root = ET.parse(path).getroot()
    suites = [root] if root.tag == "testsuite" else root.findall("testsuite")
    total = sum(int(s.get("tests", 0)) for s in suites)
    failed = sum(int(s.get("failures", 0)) + int(s.get("errors", 0)) for s in suites)
    skipped = sum(int(s.get("skipped", 0)) for s in suites)
    return total - failed - skipped, failed, skipped


# The windowed run: a small window, because under Xvfb's software OpenGL
# Blender redraws a full-size one at about one event-loop turn a second
# (640x480: ~20); event simulation so a test can press Esc.
WINDOW_SCREEN = "-screen 0 1280x1024x24"
WINDOW_ARGS = ["-p", "0", "0", "640", "480", "--factory-startup", "--enable-event-simulate"]
# A window that hangs (a modal operator that never ends) must not hang `make test`.
WINDOW_TIMEOUT = 900


def run_command(command, timeout=None):
    """The exit status, or None after `timeout` s. With a timeout the command
    runs in its own session, so that stopping it also stops the Xvfb server
    xvfb-run started (and Ctrl-C here stops both)."""
    if timeout is None:
        return subprocess.run(command, cwd=ROOT).returncode
    process = subprocess.Popen(command, cwd=ROOT, start_new_session=True)
    try:
        return process.wait(timeout=timeout)
    except BaseException as error:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        if isinstance(error, subprocess.TimeoutExpired):
            return None
        raise


def run(name, command_prefix, extra_args, timeout=None, may_select_none=False):
    """(passed, failed, skipped) of one Blender's run. `may_select_none`: the
    extra arguments (-k ...) may leave this run nothing to run."""
    with tempfile.TemporaryDirectory() as tmp:
        junit = os.path.join(tmp, "junit.xml")
        pytest_args = [TESTS, "-q", "-p", "no:cacheprovider", "--durations=8", f"--junitxml={junit}", *extra_args]
        print(f"\n=== {name} ===", flush=True)
        returncode = run_command(command_prefix + pytest_args, timeout)
        if returncode is None:
            print(f"{name}: stopped after {timeout} s", flush=True)
            return 0, 1, 0
        if may_select_none and returncode == 5:  # pytest: no tests collected
            print(f"{name}: none of the tests selected", flush=True)
            return 0, 0, 0
        if not os.path.exists(junit):
            print(f"{name}: no test results (exit status {returncode})", flush=True)
            return 0, 1, 0
        passed, failed, skipped = counts_from_junit(junit)
        if returncode != 0 and failed == 0:
            failed = 1  # crashed after writing results, or no tests collected
        if passed + failed == 0:
            print(f"{name}: no tests ran", flush=True)
            failed = 1
        return passed, failed, skipped


def main():
    extra = sys.argv[1:]
    total_passed = total_failed = total_skipped = 0
    blender = shutil.which("blender")
    runs = []
    if blender:
        runs.append(("Blender 3.4 (Debian, blender -b --factory-startup)",
                     [blender, "-b", "--factory-startup",
                      "--python", os.path.join(TESTS, "pytest_in_blender.py"), "--"], {}))
    else:
        print("MISSING: Debian's `blender` is not installed; run scripts/install_deps.sh")
        total_failed += 1
    for name, python in BPY_MODULES:
        if os.path.exists(python):
            runs.append((name, [python, "-m", "pytest"], {}))
        else:
            print(f"MISSING: {name}; run scripts/install_deps.sh")
            total_failed += 1
    xvfb = shutil.which("xvfb-run")
    if blender and xvfb:
        runs.append(("Blender 3.4 (Debian, in a window under Xvfb)",
                     [xvfb, "-a", "-s", WINDOW_SCREEN, blender, *WINDOW_ARGS,
                      "--python", os.path.join(TESTS, "pytest_in_blender.py"), "--"],
                     # With -k and the like, the few window tests may all be left out.
                     {"timeout": WINDOW_TIMEOUT, "may_select_none": bool(extra)}))
    elif blender:
        print("MISSING: `xvfb-run` is not installed; run scripts/install_deps.sh")
        total_failed += 1
    for name, prefix, options in runs:
        p, f, s = run(name, prefix, extra, **options)
        print(f"{name}: {p} passed, {f} failed, {s} skipped", flush=True)
        total_passed += p
        total_failed += f
        total_skipped += s
    if total_skipped:
        # A skip inside Blender hides a missing piece; count it as a failure.
        print(f"{total_skipped} tests were skipped inside Blender: skips are not allowed here")
        total_failed += total_skipped
    print(f"blender: {total_passed} passed, {total_failed} failed", flush=True)
    return 0 if total_failed == 0 and total_passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
