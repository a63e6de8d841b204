"""Defaults and ranges of the settings the core owns, for the add-on's properties.

They are the core's own: limits() reads _penumbra.settings_spec(), which
lists the core's settings structs (common/setting.hpp and the structs beside
it), so a default or a bound such as the visibility SH order's
(core/visibility/order_limit.hpp) has one definition.
tests/blender/test_settings.py checks that every property that mirrors a
core setting was registered with it.

The add-on must still register and show its panel when its compiled core
cannot load. Then nothing can bake, build or shade, and the panel says why;
the properties get the defaults below and no bounds (the test checks these
defaults against the core's too)."""

import math

from . import native

# name: default, only for registering without the compiled core.
DEFAULTS_WITHOUT_CORE = {
    "threads": 0,
    "visibility.rays": 256,
    "visibility.sh_order": 4,
    "visibility.lobes": 2,
    "visibility.phong_exponent": 16.0,
    "visibility.transmission": (0.5, 0.5, 0.5),
    "lights.count": 64,
    "lights.blue_noise": False,
    "lights.fit_irradiance": True,
    "lights.temporal_filter": True,
    "lights.filter_brightness": False,
    "lights.cluster_max": 0,
    "lights.adaptive_tolerance": 0.0,
    "colormap.lut_width": 256,
    "colormap.lut_height": 256,
    "colormap.sigma_max": 0.25,
    "colormap.mean_min": 0.0,
    "colormap.mean_max": 1.0,
}

INT_LIMIT = 2**31 - 1  # the core's unbounded_int: what a property has without a bound


def _bound(value):
    """A property's bound from the core's, or None where the core has none
    (infinite, or the type's limit)."""
    if value is None or (isinstance(value, float) and math.isinf(value)) or abs(value) == INT_LIMIT:
        return None
    return value


def limits(name):
    """The keyword arguments default=, min=, max= of a property for the core setting `name`."""
    if native.module is None:
        return {"default": DEFAULTS_WITHOUT_CORE[name]}
    spec = native.module.settings_spec()[name]
    out = {"default": tuple(spec["default"]) if isinstance(spec["default"], list) else spec["default"]}
    for key in ("min", "max"):
        bound = _bound(spec.get(key))
        if bound is not None:
            out[key] = bound
    return out
