"""Loads the compiled core `_penumbra` without ever breaking add-on registration.

Where the module is:
 - next to this file: the legacy zip for Blender 3.x and the build tree
   (build/addon/penumbra), with one _penumbra.cpython-3XY*.so per Python;
 - on sys.path as a top-level module: the Blender 4.2+ extension, whose
   wheel Blender installs into the extensions' site-packages.
It is imported once per process and also published as the top-level name
`_penumbra`, because the same shared object imported under two names would
register its Python types twice.

Video is decoded by an `ffmpeg` program in a child process (see
core/image/video.hpp); the add-on ships one and hands its path to the core.
"""

import glob
import importlib
import importlib.util
import os
import shutil
import stat
import sys
import tempfile

from . import installed_copies

module = None       # the loaded _penumbra, or None
load_error = None   # why it could not be loaded, for the panel


def _import_module():
    if "_penumbra" in sys.modules:
        return sys.modules["_penumbra"]
    here = os.path.dirname(os.path.abspath(__file__))
    if glob.glob(os.path.join(here, "_penumbra.*")):
        return importlib.import_module(__package__ + "._penumbra")
    return importlib.import_module("_penumbra")


def _load():
    global module, load_error
    loaded_before = "_penumbra" in sys.modules  # by an earlier copy or version of the add-on
    try:
        module = _import_module()
    except ImportError as error:  # missing build, wrong Python, missing library
        load_error = (
            f"{error}. Install the Penumbra package for this platform (dist/ in the source tree: "
            f"the extension zip for Blender 4.2+, the legacy zip for 3.x), or build it with `make build`; "
            f"this Blender runs Python {sys.version_info.major}.{sys.version_info.minor}."
        )
        return
    stale = installed_copies.stale_core_reason(module) if loaded_before else None
    if stale:  # an update replaced it while Blender ran: never call into it
        module, load_error = None, stale
        print(f"Penumbra: {stale}", file=sys.stderr)
        return
    installed_copies.remember_loaded_file(module)
    sys.modules["_penumbra"] = module
    ffmpeg = bundled_ffmpeg()
    if ffmpeg:
        module.image.set_ffmpeg_executable(ffmpeg)


def bundled_ffmpeg():
    """The ffmpeg the package ships, made executable, or None.

    Blender's installers unpack zips and wheels without file modes, so the
    program may arrive without its executable bit; it gets it back here, or,
    in a read-only install, runs from a copy in the temporary folder."""
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.path.join(here, "bin", "ffmpeg")]
    spec = importlib.util.find_spec("imageio_ffmpeg")  # the extension's bundled wheel
    if spec and spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            candidates += sorted(glob.glob(os.path.join(folder, "binaries", "ffmpeg-*")))
    for path in candidates:
        if os.path.isfile(path) and not path.endswith((".md", ".py")):
            return _executable(path)
    return None


def _executable(path):
    if os.access(path, os.X_OK):
        return path
    try:
        os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
        return path
    except OSError:
        copy = os.path.join(tempfile.gettempdir(), f"penumbra-{os.getuid()}", os.path.basename(path))
        if not os.path.exists(copy):
            os.makedirs(os.path.dirname(copy), exist_ok=True)
            shutil.copyfile(path, copy + ".part")
            os.chmod(copy + ".part", 0o755)
            os.replace(copy + ".part", copy)
        return copy


def require():
    """The loaded module, or a RuntimeError with the reason, for operators."""
    if module is None:
        raise RuntimeError(f"Penumbra's compiled core is not available: {load_error}")
    return module


_load()
