"""Light rigs from HDR images and video (see core/lights and docs/lights.md)."""

import bpy

from . import settings, operators

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.LightRigSceneSettings


def draw_panel(layout, context):
    s = context.scene.penumbra.light_rig
    col = layout.column(align=True)
    col.prop(s, "filepath")
    if not s.filepath:
        col.label(text="Empty: the World's environment texture", icon="WORLD")
    col.prop(s, "mapping")
    col.prop(s, "colorspace")
    col = layout.column(align=True)
    col.prop(s, "count")
    col.prop(s, "sampler")
    col.prop(s, "power")
    col.prop(s, "blue_noise")
    col.prop(s, "temporal_filter")
    col.prop(s, "cluster_max")
    col.prop(s, "adaptive_tolerance")
    row = layout.row(align=True)
    row.prop(s, "frame_start")
    row.prop(s, "frame_end")
    layout.prop(s, "json_path")
    layout.prop(s, "limit_shadows")
    if bpy.app.version < (4, 2, 0):
        box = layout.box()
        box.label(text="EEVEE Legacy draws at most 128 lights", icon="INFO")
        box.label(text="and 8 shadowed suns: enable the shadow")
        box.label(text="limit or keep Lights <= 128 for EEVEE.")
    layout.operator("penumbra.build_light_rig", icon="LIGHT_SUN")
    if s.last_report:
        layout.label(text=s.last_report)
    preview = bpy.data.images.get(operators.PREVIEW_NAME)
    if preview is not None and hasattr(preview, "preview_ensure"):
        preview.preview_ensure()
        layout.template_icon(icon_value=preview.preview.icon_id, scale=8.0)


def register():
    operators.register()


def unregister():
    operators.unregister()
