"""Runs pytest inside Blender's own Python:
    blender -b --factory-startup --python tests/blender/pytest_in_blender.py -- ARGS
ARGS go to pytest; Blender exits with pytest's status: in background mode a
SystemExit raised by a --python script ends Blender with that code.

Without -b (a window, under Xvfb: blender_window.py), pytest runs on a
worker thread while Blender's event loop turns, and the process exits with
pytest's status when it ends."""

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_window  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if blender_window.windowed():
    blender_window.run_pytest(args)
else:
    status = pytest.main(args)
    sys.stdout.flush()
    sys.exit(int(status))
