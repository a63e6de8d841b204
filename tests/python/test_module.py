"""The _penumbra module itself: metadata, errors as Python exceptions, its
layout (one submodule per part of the core) and its enums."""

import enum
import glob
import importlib
import os
import subprocess
import sys
import types

import numpy as np
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
    fit = next(sig for name, sig in signatures if name == "fit_model")
    assert f"lobes: int = {spec['visibility.lobes']['default']}" in fit


SUBMODULES = ("image", "color", "sh", "visibility", "lights", "colormap", "testing")
ALIASES = {"sh_eval": ("sh", "eval"), "phong_operator": ("sh", "phong_operator"),
           "project_environment": ("sh", "project_environment"), "colormap_lut": ("colormap", "lut")}


def test_the_top_level_holds_the_submodules_and_nothing_else_but_module_wide_names():
    public = {name for name in dir(_penumbra) if not name.startswith("_")}
    expected = {"build_info", "settings_spec", "PenumbraError", "IoError", "Cancelled", "write_file_durably",
                "replace_file_durably", *SUBMODULES, *ALIASES}
    assert public == expected
    assert isinstance(_penumbra.__version__, str)


@pytest.mark.parametrize("name", SUBMODULES)
def test_each_submodule_is_importable_by_its_dotted_name(name):
    module = importlib.import_module(f"_penumbra.{name}")
    assert module is getattr(_penumbra, name)
    assert isinstance(module, types.ModuleType) and module.__doc__
    assert sys.modules[f"_penumbra.{name}"] is module


def test_from_import_of_a_submodule_works():
    from _penumbra.lights import RigBuilder  # noqa: F401 (the import is the test)
    from _penumbra.visibility import TrainingSet
    assert TrainingSet is _penumbra.visibility.TrainingSet


@pytest.mark.parametrize("alias", sorted(ALIASES))
def test_top_level_aliases_are_the_submodule_functions_themselves(alias):
    module, name = ALIASES[alias]
    assert getattr(_penumbra, alias) is getattr(getattr(_penumbra, module), name)


# Names renamed in the core keep their old name in _penumbra, bound to the
# same object, so scripts written against the old name keep working.
RENAMED = {("visibility", "RuntimeMesh"): "ShadingMesh"}


@pytest.mark.parametrize("old", sorted(RENAMED))
def test_a_renamed_name_is_the_same_object_under_its_old_name(old):
    module = getattr(_penumbra, old[0])
    new = getattr(module, RENAMED[old])
    assert getattr(module, old[1]) is new
    assert old[1] in new.__doc__  # the docstring says so


def _enums():
    for module_name in SUBMODULES:
        module = getattr(_penumbra, module_name)
        for name in dir(module):
            item = getattr(module, name)
            if isinstance(item, type) and hasattr(item, "__members__") and not issubclass(item, enum.Enum):
                yield f"{module_name}.{name}", item


ENUMS = dict(_enums())


def test_every_tool_has_its_enums():
    assert {"image.FrameSourceKind", "sh.ShadingModel", "visibility.BelowHorizon", "visibility.Weighting",
            "visibility.PoseFeatures", "visibility.SceneBuild", "lights.Projection", "lights.Sampler",
            "lights.Power", "colormap.SigmaSpacing", "colormap.MapInterpolation", "colormap.RampInterpolation",
            "colormap.RampColorMode", "colormap.RampHueInterpolation", "colormap.RampSampling",
            "colormap.EffectiveHeightMethod", "colormap.SlopeFilteringMethod",
            "testing.WorkerFailure"} <= set(ENUMS)


@pytest.mark.parametrize("qualified", sorted(ENUMS))
def test_every_enum_converts_from_its_member_names_in_any_case(qualified):
    enum_type = ENUMS[qualified]
    assert enum_type.__members__
    for name, member in enum_type.__members__.items():
        assert name == name.upper()
        for spelling in (name, name.lower(), name.title()):
            assert enum_type(spelling) == member, spelling


@pytest.mark.parametrize("qualified", sorted(ENUMS))
def test_every_enum_rejects_other_names_with_a_value_error_naming_the_valid_ones(qualified):
    enum_type = ENUMS[qualified]
    with pytest.raises(ValueError) as raised:
        enum_type("no_such_member")
    message = str(raised.value)
    assert "'no_such_member'" in message and qualified in message
    for name in enum_type.__members__:
        assert name in message


def test_a_function_taking_an_enum_takes_its_name_and_names_the_argument_when_wrong():
    pixels = np.ones((8, 16, 3), np.float32)
    by_name = _penumbra.lights.frame_lights(pixels, count=4, mapping="mirror_ball", sampler="Standard")
    by_member = _penumbra.lights.frame_lights(pixels, count=4, mapping=_penumbra.lights.Projection.MIRROR_BALL,
                                              sampler=_penumbra.lights.Sampler.STANDARD)
    np.testing.assert_array_equal(by_name["directions"], by_member["directions"])
    with pytest.raises(ValueError, match=r"mapping must be EQUIRECTANGULAR, .* not 'cubemap'"):
        _penumbra.lights.frame_lights(pixels, mapping="cubemap")
    with pytest.raises(TypeError):  # neither a member nor a name
        _penumbra.lights.frame_lights(pixels, mapping=3)


def test_enum_defaults_are_the_cores():
    signatures = dict(_signatures(_penumbra))
    assert "mapping: _penumbra.lights.Projection = <Projection.EQUIRECTANGULAR" in signatures["frame_lights"]
    assert "brdf: _penumbra.sh.ShadingModel = <ShadingModel.DIFFUSE" in signatures["shade_pose"]
    assert "below_horizon: _penumbra.visibility.BelowHorizon = <BelowHorizon.OCCLUDED" in \
        _penumbra.visibility.TrainingSet.__init__.__doc__
