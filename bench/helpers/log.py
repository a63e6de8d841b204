"""Progress lines of benchmarks and checks: flushed at once, since a parent
process reads them while the child runs (colormap_benchmark.py echoes its
sweeps' lines), each after the name of the script that prints it."""

import os
import sys


def log(*args, prefix=None):
    """print(`prefix`: *args), flushed; `prefix` defaults to script_name()."""
    print(f"{prefix or script_name()}:", *args, flush=True)


def script_name():
    """The running script's name without .py: argv[0], or, inside Blender
    (`blender ... --python FILE`, where argv[0] is Blender), FILE."""
    argv = sys.argv
    script = argv[argv.index("--python") + 1] if "--python" in argv[:-1] else (argv[0] if argv else "")
    return os.path.splitext(os.path.basename(script))[0] or "python"
