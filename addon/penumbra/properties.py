"""Settings stored in the .blend: one group per tool under `scene.penumbra`.

The tool issues add their settings to these groups; keeping them on the scene
means a batch script, the panel and a saved file all see the same values.
"""

import bpy


class PenumbraVisibilitySettings(bpy.types.PropertyGroup):
    pass


class PenumbraLightRigSettings(bpy.types.PropertyGroup):
    pass


class PenumbraColormapSettings(bpy.types.PropertyGroup):
    pass


class PenumbraSceneSettings(bpy.types.PropertyGroup):
    visibility: bpy.props.PointerProperty(type=PenumbraVisibilitySettings)
    light_rig: bpy.props.PointerProperty(type=PenumbraLightRigSettings)
    colormap: bpy.props.PointerProperty(type=PenumbraColormapSettings)


classes = (
    PenumbraVisibilitySettings,
    PenumbraLightRigSettings,
    PenumbraColormapSettings,
    PenumbraSceneSettings,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.penumbra = bpy.props.PointerProperty(type=PenumbraSceneSettings)


def unregister():
    del bpy.types.Scene.penumbra
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
