"""Filtered colour-map lookups and their node groups (see core/colormap and
docs/colormap.md): the active ColorRamp becomes a node group that samples a
pre-filtered lookup image, so one sample per pixel looks like many. Its
sidebar section is panel.py (registered by ../panels.py)."""

if "bpy" in locals():
    import importlib
    for _name in ("interface", "settings", "ramp", "node_groups", "noise_maths", "table_image", "node_builder",
                  "lookup_layout", "filter_quality", "noise_statistics", "noise_model", "noise_nodes",
                  "filtered_ramp", "footprint", "point_footprint", "point_filter", "noise_filter", "microsurface",
                  "height_ramp", "slope_ramp", "sample_count", "material", "surface_filter", "operators", "panel"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy  # noqa: E402

# In the order they import each other (a reload goes the same way).
from . import interface, settings, ramp, node_groups, noise_maths, table_image, node_builder  # noqa: E402,F401
from . import lookup_layout, filter_quality, noise_statistics, noise_model, noise_nodes  # noqa: E402,F401
from . import filtered_ramp, footprint, point_footprint, point_filter, noise_filter  # noqa: E402,F401
from . import microsurface, height_ramp, slope_ramp  # noqa: E402,F401
from . import sample_count, material, surface_filter, operators, panel  # noqa: E402,F401

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.ColormapSceneSettings


def register():
    for cls in operators.classes:
        bpy.utils.register_class(cls)
    for cls in surface_filter.classes:
        bpy.utils.register_class(cls)
    sample_count.register()


def unregister():
    for cls in reversed(surface_filter.classes):
        bpy.utils.unregister_class(cls)
    sample_count.unregister()
    for cls in reversed(operators.classes):
        bpy.utils.unregister_class(cls)
