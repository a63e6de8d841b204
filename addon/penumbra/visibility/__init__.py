"""Shadowed relighting of rigged meshes: bake a pose-space ZH visibility model
(core/visibility), then shade every pose from it (paper §3–4).

Operators (names are a contract, in operators.py): penumbra.bake_visibility,
penumbra.apply_visibility, penumbra.setup_material. Per-object settings:
`object.penumbra_visibility`; scene settings: `scene.penumbra.visibility`.
Its sidebar section is panel.py (registered by ../panels.py)."""

import bpy

from . import settings, bake, frame_shading, material, report, gpu_preview, operators, panel  # noqa: F401

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.VisibilitySceneSettings

_operator_classes = operators.classes


def register():
    bpy.types.Object.penumbra_visibility = bpy.props.PointerProperty(type=settings.VisibilityObjectSettings)
    for cls in _operator_classes:
        bpy.utils.register_class(cls)
    frame_shading.register_handlers()
    gpu_preview.register()


def unregister():
    gpu_preview.unregister()
    frame_shading.unregister_handlers()
    for cls in reversed(_operator_classes):
        bpy.utils.unregister_class(cls)
    del bpy.types.Object.penumbra_visibility
