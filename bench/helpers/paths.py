"""Where the benchmarks read and write, and the folders their imports need."""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DOCS = os.path.join(ROOT, "docs")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))


def use_addon():
    """Puts the built add-on (build/addon: `import penumbra`) and the example
    scenes (examples/scenes) on sys.path, as a batch script would."""
    for folder in (os.path.join(ROOT, "build", "addon"), os.path.join(ROOT, "examples", "scenes")):
        if folder not in sys.path:
            sys.path.insert(0, folder)


def compiled_core():
    """The compiled core `_penumbra`: the one already loaded (by the add-on,
    which publishes it under that name) or on sys.path (the tests' conftest),
    else the build tree's (build/addon/penumbra)."""
    try:
        import _penumbra
    except ImportError:
        sys.path.insert(0, os.path.join(ROOT, "build", "addon", "penumbra"))
        import _penumbra
    return _penumbra
