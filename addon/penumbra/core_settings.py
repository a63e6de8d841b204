"""Defaults and ranges of the settings the core owns, for the add-on's properties.

The values are the core's (common/setting.hpp and the settings structs beside
it). They are written out here, once for the add-on, because the add-on must
register and show its panel even when its compiled core cannot load;
tests/blender/test_settings.py checks every property that uses one against
_penumbra.settings_spec(), so the two cannot drift apart."""

# name: (default, min, max); None: no bound (the core's is infinite or the
# type's limit).
SPEC = {
    "threads": (0, 0, 1024),
    "visibility.rays": (256, 4, 65536),
    "visibility.sh_order": (4, 1, 8),
    "visibility.lobes": (2, 1, 4),
    "visibility.phong_exponent": (16.0, 0.0, None),
    "visibility.transmission": ((0.5, 0.5, 0.5), None, None),
    "lights.count": (64, 1, None),
    "lights.blue_noise": (False, None, None),
    "lights.fit_irradiance": (True, None, None),
    "lights.temporal_filter": (True, None, None),
    "lights.filter_brightness": (False, None, None),
    "lights.cluster_max": (0, 0, None),
    "lights.adaptive_tolerance": (0.0, 0.0, 1.0),
    "colormap.lut_width": (256, 2, 8192),
    "colormap.lut_height": (256, 2, 8192),
    "colormap.sigma_max": (0.25, 1e-6, None),
    "colormap.mean_min": (0.0, None, None),
    "colormap.mean_max": (1.0, None, None),
}


def limits(name):
    """The keyword arguments default=, min=, max= of a property for the core setting `name`."""
    default, low, high = SPEC[name]
    out = {"default": default}
    if low is not None:
        out["min"] = low
    if high is not None:
        out["max"] = high
    return out
