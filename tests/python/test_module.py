"""The _penumbra module itself: metadata, errors as Python exceptions."""

import glob
import os
import subprocess
import sys

import pytest

import _penumbra
from conftest import ADDON_DIR


def test_version_is_a_dotted_string():
    parts = _penumbra.__version__.split(".")
    assert len(parts) == 3 and all(p.isdigit() for p in parts)


def test_build_info_names_every_library_with_a_version():
    info = _penumbra.build_info()
    for key in ("compiler", "simd", "openimageio", "opencolorio", "embree", "eigen", "python"):
        assert info[key], key
    assert info["opencolorio"].startswith("2.")
    assert info["embree"].startswith("3.")
    assert info["eigen"].startswith("3.")
    assert info["python"].startswith("3.11")


def test_only_the_module_init_symbol_is_exported():
    # Hidden symbols keep the module from interposing on Blender's own
    # OpenImageIO/OpenColorIO/TBB; `nm -D --defined-only` lists what is visible.
    # One module per supported Python (3.10, 3.11, 3.13), each checked.
    modules = glob.glob(os.path.join(ADDON_DIR, "_penumbra*.so"))
    assert len(modules) == 3, modules
    for so in modules:
        out = subprocess.run(["nm", "-D", "--defined-only", so], capture_output=True, text=True, check=True).stdout
        exported = [line.split()[-1] for line in out.splitlines() if line.split()[1] in "TDBRVW"]
        assert exported == ["PyInit__penumbra"], (so, exported)


def test_exception_types_are_python_exceptions_with_useful_bases():
    assert issubclass(_penumbra.PenumbraError, RuntimeError)
    assert issubclass(_penumbra.IoError, OSError)
    assert issubclass(_penumbra.Cancelled, _penumbra.PenumbraError)


def test_import_twice_under_both_names_gives_one_module():
    # The add-on imports penumbra._penumbra and publishes it as _penumbra; a
    # second PyInit would register the C++ types twice and fail.
    # penumbra/__init__ imports bpy, so load native.py as part of a bare
    # package object (the Blender tests cover the full add-on).
    code = (
        "import sys, types;"
        "pkg = types.ModuleType('penumbra'); pkg.__path__ = [%r]; sys.modules['penumbra'] = pkg;"
        "import penumbra.native as n; import _penumbra; assert n.module is _penumbra, n.load_error; print('ok')"
    ) % ADDON_DIR
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def _signatures(obj, seen=None):
    """Every (name, docstring signature line) of the module's functions and methods."""
    import types
    seen = set() if seen is None else seen
    for name in dir(obj):
        item = getattr(obj, name)
        if id(item) in seen or name.startswith("__"):
            continue
        seen.add(id(item))
        if isinstance(item, types.ModuleType) and item.__name__.startswith("_penumbra"):
            yield from _signatures(item, seen)
        elif isinstance(item, type):
            yield from _signatures(item, seen)
        elif callable(item) and item.__doc__:
            yield name, item.__doc__.splitlines()[0]


def test_no_binding_default_is_an_array_or_a_typed_out_number_the_core_owns():
    # An array default is built when the module loads: py::array_t<double>(3)
    # was uninitialised memory (help() showed 6.9e-310). The settings the
    # add-on mirrors must show the core's values (settings_spec).
    signatures = list(_signatures(_penumbra))
    assert len(signatures) > 50
    arrays = [(name, sig) for name, sig in signatures if "array(" in sig]
    assert arrays == []
    spec = _penumbra.settings_spec()
    shade = next(sig for name, sig in signatures if name == "shade_pose")
    assert f"exponent: float = {spec['visibility.phong_exponent']['default']}" in shade
    fit = next(sig for name, sig in signatures if name == "fit_visibility_model")
    assert f"lobes: int = {spec['visibility.lobes']['default']}" in fit
