"""The add-on's properties take their defaults and ranges from the core: every
property below, as Blender registered it, has the default and the hard
bounds that _penumbra.settings_spec() reads from the core's settings structs.
A property or operator that types its own value instead of taking
addon/penumbra/core_settings.py's fails here, and so do core_settings.py's
defaults for registering without the core once they differ from the core's."""

import math

import bpy
import pytest

INT_LIMIT = 2**31 - 1
FLOAT_LIMIT = 3.4028234663852886e38  # a FloatProperty without max

# (where the property lives, property) -> the core setting it mirrors.
MIRRORS = [
    ("scene.visibility", "threads", "threads"),
    ("object.visibility", "rays", "visibility.rays"),
    ("object.visibility", "lobes", "visibility.lobes"),
    ("object.visibility", "sh_order", "visibility.sh_order"),
    ("object.visibility", "phong_exponent", "visibility.phong_exponent"),
    ("object.visibility", "transmission", "visibility.transmission"),
    ("operator.bake_visibility", "rays", "visibility.rays"),
    ("operator.bake_visibility", "lobes", "visibility.lobes"),
    ("operator.bake_visibility", "sh_order", "visibility.sh_order"),
    ("scene.light_rig", "count", "lights.count"),
    ("scene.light_rig", "blue_noise", "lights.blue_noise"),
    ("scene.light_rig", "fit_irradiance", "lights.fit_irradiance"),
    ("scene.light_rig", "temporal_filter", "lights.temporal_filter"),
    ("scene.light_rig", "filter_brightness", "lights.filter_brightness"),
    ("scene.light_rig", "cluster_max", "lights.cluster_max"),
    ("scene.light_rig", "adaptive_tolerance", "lights.adaptive_tolerance"),
    ("operator.build_light_rig", "count", "lights.count"),
    ("operator.build_light_rig", "blue_noise", "lights.blue_noise"),
    ("operator.build_light_rig", "fit_irradiance", "lights.fit_irradiance"),
    ("operator.build_light_rig", "temporal_filter", "lights.temporal_filter"),
    ("operator.build_light_rig", "filter_brightness", "lights.filter_brightness"),
    ("operator.build_light_rig", "cluster_max", "lights.cluster_max"),
    ("operator.build_light_rig", "adaptive_tolerance", "lights.adaptive_tolerance"),
    ("scene.colormap", "lut_width", "colormap.lut_width"),
    ("scene.colormap", "lut_height", "colormap.lut_height"),
    ("scene.colormap", "sigma_max", "colormap.sigma_max"),
    ("scene.colormap", "mean_min", "colormap.mean_min"),
    ("scene.colormap", "mean_max", "colormap.mean_max"),
]


@pytest.fixture(scope="module")
def spec():
    import penumbra
    from penumbra import native
    penumbra.register()
    yield native.require().settings_spec()
    penumbra.unregister()


def rna_property(where, name):
    kind, owner = where.split(".")
    if kind == "operator":
        return getattr(bpy.ops.penumbra, owner).get_rna_type().properties[name]
    if kind == "scene":
        return bpy.types.Scene.bl_rna.properties["penumbra"].fixed_type.properties[owner].fixed_type.properties[name]
    return bpy.types.Object.bl_rna.properties["penumbra_visibility"].fixed_type.properties[name]


def same_bound(blender, core, limit):
    if core is None:
        return True
    if math.isinf(core) or core == INT_LIMIT:
        return abs(blender) >= limit * (1 - 1e-6)
    return blender == pytest.approx(core, rel=1e-6)


@pytest.mark.parametrize("where, name, setting", MIRRORS, ids=[f"{w}.{n}" for w, n, _ in MIRRORS])
def test_the_property_has_the_cores_default_and_range(spec, where, name, setting):
    core = spec[setting]
    prop = rna_property(where, name)
    default = list(prop.default_array) if getattr(prop, "is_array", False) else prop.default
    assert default == pytest.approx(core["default"]), f"{where}.{name}: default {default}, core {core['default']}"
    if prop.type in {"INT", "FLOAT"}:
        limit = INT_LIMIT if prop.type == "INT" else FLOAT_LIMIT
        assert same_bound(prop.hard_min, core.get("min"), limit), f"{where}.{name}: min {prop.hard_min}, core {core}"
        assert same_bound(prop.hard_max, core.get("max"), limit), f"{where}.{name}: max {prop.hard_max}, core {core}"


def test_every_core_setting_is_mirrored_somewhere(spec):
    assert {setting for _, _, setting in MIRRORS} == set(spec)


def test_the_defaults_without_the_core_are_the_cores(spec):
    from penumbra import core_settings
    assert set(core_settings.DEFAULTS_WITHOUT_CORE) == set(spec)
    for name, default in core_settings.DEFAULTS_WITHOUT_CORE.items():
        assert default == pytest.approx(spec[name]["default"]), name


def test_the_sh_order_stops_at_the_visibility_tools_limit_not_the_sh_engines(spec):
    from penumbra import native
    core = native.require()
    limit = core.visibility.MAX_ORDER
    assert limit < core.sh.MAX_ORDER  # two limits (core/visibility/order_limit.hpp says why)
    assert spec["visibility.sh_order"]["max"] == limit
    for where in ("object.visibility", "operator.bake_visibility"):
        assert rna_property(where, "sh_order").hard_max == limit


def _path_properties():
    """(owner, name, rna property) of every file or folder path among the
    add-on's settings and operator properties."""
    owners = [(cls.__name__, cls.bl_rna) for cls in bpy.types.PropertyGroup.__subclasses__()
              if cls.__module__.startswith("penumbra")]
    owners += [(f"penumbra.{name}", getattr(bpy.ops.penumbra, name).get_rna_type()) for name in dir(bpy.ops.penumbra)]
    return [(owner, p.identifier, p) for owner, rna in owners for p in rna.properties
            if p.type == "STRING" and p.subtype in {"FILE_PATH", "DIR_PATH"}]


def test_every_path_property_takes_a_path_relative_to_the_blend(spec):
    """Penumbra names files "//..." (its defaults, a saved .blend's
    settings); Blender 5.x warns on every such assignment to a path property
    without PATH_SUPPORTS_BLEND_RELATIVE. Blender 3.4's RNA does not expose
    the flag: there the list of path properties is checked alone."""
    found = _path_properties()
    names = {f"{owner}.{name}" for owner, name, _ in found}
    assert {"LightRigSceneSettings.filepath", "LightRigSceneSettings.json_path", "ColormapSceneSettings.output_folder",
            "VisibilityObjectSettings.model_path", "penumbra.build_light_rig.filepath",
            "penumbra.bake_visibility.filepath"} <= names, names
    if hasattr(found[0][2], "is_path_supports_blend_relative"):
        assert [f"{owner}.{n}" for owner, n, p in found if not p.is_path_supports_blend_relative] == []
