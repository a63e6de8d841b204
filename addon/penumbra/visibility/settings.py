"""Visibility-baker settings stored in the .blend."""

import bpy


class VisibilitySceneSettings(bpy.types.PropertyGroup):
    pass


classes = (VisibilitySceneSettings,)
