"""Filtered colour-map lookups and their node groups (see core/colormap and
docs/colormap.md): the active ColorRamp becomes a node group that samples a
pre-filtered lookup image, so one sample per pixel looks like many."""

if "bpy" in locals():
    import importlib
    for _name in ("interface", "settings", "ramp", "noise_statistics", "node_groups", "operators"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy  # noqa: E402

from . import interface, settings, ramp, noise_statistics, node_groups, operators  # noqa: E402,F401

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.ColormapSceneSettings


def draw_panel(layout, context):
    scene = context.scene
    s = scene.penumbra.colormap if hasattr(scene, "penumbra") else None
    if s is None:
        layout.label(text="Settings not registered")
        return
    col = layout.column(align=True)
    col.prop(s, "lut_width")
    col.prop(s, "lut_height")
    layout.prop(s, "sigma_spacing")
    layout.prop(s, "sampling")
    col = layout.column(align=True)
    col.prop(s, "sigma_max")
    col.prop(s, "mean_min")
    col.prop(s, "mean_max")
    layout.prop(s, "output_folder")
    layout.prop(s, "write_png")
    layout.operator(operators.PENUMBRA_OT_bake_colormap_lut.bl_idname, icon="NODE_TEXTURE")
    layout.operator(operators.PENUMBRA_OT_restore_color_ramp.bl_idname, icon="LOOP_BACK")


def register():
    for cls in operators.classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(operators.classes):
        bpy.utils.unregister_class(cls)
