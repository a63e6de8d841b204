"""Runs pytest inside Blender's own Python:
    blender -b --factory-startup --python-exit-code 1 --python tests/blender/pytest_in_blender.py -- ARGS
ARGS go to pytest; Blender exits with pytest's status."""

import sys

import pytest

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
status = pytest.main(args)
sys.stdout.flush()
# os._exit: Blender would otherwise swallow SystemExit's code in background mode.
import os  # noqa: E402
os._exit(int(status))
