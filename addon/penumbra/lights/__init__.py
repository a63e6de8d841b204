"""Light rigs from HDR images and video (see core/lights)."""

from . import settings

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.LightRigSceneSettings


def draw_panel(layout, context):
    layout.label(text="HDR light rigs: not yet available")


def register():
    pass


def unregister():
    pass
