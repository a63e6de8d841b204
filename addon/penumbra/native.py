"""Loads the compiled core `_penumbra` without ever breaking add-on registration.

The module lives next to this file. It is imported once per process and also
published as the top-level name `_penumbra`, because the same shared object
imported under two names would register its Python types twice.
"""

import importlib
import sys

module = None       # the loaded _penumbra, or None
load_error = None   # why it could not be loaded, for the panel


def _load():
    global module, load_error
    if "_penumbra" in sys.modules:
        module = sys.modules["_penumbra"]
        return
    try:
        module = importlib.import_module(__package__ + "._penumbra")
    except ImportError as error:  # missing build, wrong Python, missing library
        load_error = (
            f"{error}. Build it with `make build` in the Penumbra source tree "
            f"(Python {sys.version_info.major}.{sys.version_info.minor} is needed), "
            "or reinstall the add-on zip from build/."
        )
        return
    sys.modules["_penumbra"] = module


def require():
    """The loaded module, or a RuntimeError with the reason, for operators."""
    if module is None:
        raise RuntimeError(f"Penumbra's compiled core is not available: {load_error}")
    return module


_load()
