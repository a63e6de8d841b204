"""Colour-map lookup settings stored in the .blend."""

import bpy


class ColormapSceneSettings(bpy.types.PropertyGroup):
    pass


classes = (ColormapSceneSettings,)
