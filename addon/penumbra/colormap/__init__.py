"""Filtered colour-map lookups and their node groups (see core/colormap)."""

from . import settings

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.ColormapSceneSettings


def draw_panel(layout, context):
    layout.label(text="Colour-map lookups: not yet available")


def register():
    pass


def unregister():
    pass
