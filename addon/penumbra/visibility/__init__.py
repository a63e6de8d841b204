"""Shadowed relighting of rigged meshes: bake, fit, shade (see core/visibility)."""

from . import settings

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.VisibilitySceneSettings


def draw_panel(layout, context):
    layout.label(text="Visibility baker: not yet available")


def register():
    pass


def unregister():
    pass
