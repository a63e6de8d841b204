"""Light-rig settings stored in the .blend."""

import bpy


class LightRigSceneSettings(bpy.types.PropertyGroup):
    pass


classes = (LightRigSceneSettings,)
