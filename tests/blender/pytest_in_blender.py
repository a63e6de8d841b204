"""Runs pytest inside Blender's own Python:
    blender -b --factory-startup --python tests/blender/pytest_in_blender.py -- ARGS
ARGS go to pytest; Blender exits with pytest's status: in background mode a
SystemExit raised by a --python script ends Blender with that code."""

import sys

import pytest

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
status = pytest.main(args)
sys.stdout.flush()
sys.exit(int(status))
