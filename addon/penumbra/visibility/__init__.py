"""Shadowed relighting of rigged meshes: bake a pose-space ZH visibility model
(core/visibility), then shade every pose from it (paper §3–4).

Operators (names are a contract): penumbra.bake_visibility,
penumbra.apply_visibility, penumbra.setup_material. Per-object settings:
`object.penumbra_visibility`; scene settings: `scene.penumbra.visibility`."""

import bpy

from . import settings, bake, runtime, material, report, gpu_preview

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.VisibilitySceneSettings

_operator_classes = (*bake.classes, *runtime.classes, *material.classes)


def draw_panel(layout, context):
    obj = context.active_object
    scene_settings = context.scene.penumbra.visibility
    if obj is None or obj.type != "MESH":
        layout.label(text="Select a skinned mesh", icon="INFO")
        return
    s = obj.penumbra_visibility
    box = layout.box()
    box.label(text="Bake", icon="RENDER_STILL")
    row = box.row(align=True)
    row.prop(s, "frame_start")
    row.prop(s, "frame_end")
    row.prop(s, "frame_step")
    row = box.row(align=True)
    row.prop(s, "rays")
    row.prop(s, "lobes")
    box.prop(s, "occluders")
    box.prop(s, "filepath")
    box.operator("penumbra.bake_visibility", icon="RENDER_STILL")

    box = layout.box()
    box.prop(s, "enabled", text="Shade from Model")
    box.prop(s, "brdf")
    if s.brdf == "PHONG":
        box.prop(s, "phong_exponent")
    elif s.brdf == "TRANSLUCENT":
        box.prop(s, "transmission")
    row = box.row(align=True)
    row.operator("penumbra.apply_visibility", icon="SHADING_RENDERED")
    row.operator("penumbra.setup_material", icon="MATERIAL")
    box.prop(scene_settings, "live_update")
    box.prop(scene_settings, "gpu_preview")
    if scene_settings.gpu_preview and scene_settings.gpu_preview_status:
        row = box.row()
        row.alert = True
        row.label(text=f"GPU preview: {scene_settings.gpu_preview_status}", icon="ERROR")
    box.prop(scene_settings, "threads")
    from .scene_data import read_world
    world = read_world(context.scene)
    row = box.row()
    row.alert = not world.supported
    row.label(text=f"Lighting: {world.note}", icon="WORLD" if world.supported else "ERROR")
    if s.status:
        alert = box.box()
        alert.alert = True
        alert.label(text=s.status, icon="ERROR")

    lines = report.summary_lines(s.report)
    if lines:
        box = layout.box()
        box.label(text="Last bake", icon="INFO")
        for line in lines:
            box.label(text=line)


def register():
    bpy.types.Object.penumbra_visibility = bpy.props.PointerProperty(type=settings.VisibilityObjectSettings)
    for cls in _operator_classes:
        bpy.utils.register_class(cls)
    runtime.register_handlers()
    gpu_preview.register()


def unregister():
    gpu_preview.unregister()
    runtime.unregister_handlers()
    for cls in reversed(_operator_classes):
        bpy.utils.unregister_class(cls)
    del bpy.types.Object.penumbra_visibility
