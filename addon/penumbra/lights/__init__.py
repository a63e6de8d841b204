"""Light rigs from HDR images and video (see core/lights and docs/lights.md).
Its sidebar section is panel.py (registered by ../panels.py)."""

from . import settings, operators, panel  # noqa: F401

# Registered before the scene's `penumbra` group, which points at SceneSettings.
settings_classes = settings.classes
SceneSettings = settings.LightRigSceneSettings


def register():
    operators.register()


def unregister():
    operators.unregister()
