"""Settings stored in the .blend: `scene.penumbra.<tool>`, one group per tool,
each defined in its tool package (visibility/, lights/, colormap/), so a batch
script, the panel and a saved file all see the same values."""

import bpy

from . import colormap, lights, visibility


class PenumbraSceneSettings(bpy.types.PropertyGroup):
    visibility: bpy.props.PointerProperty(type=visibility.SceneSettings)
    light_rig: bpy.props.PointerProperty(type=lights.SceneSettings)
    colormap: bpy.props.PointerProperty(type=colormap.SceneSettings)


def _classes():
    return (*visibility.settings_classes, *lights.settings_classes, *colormap.settings_classes,
            PenumbraSceneSettings)


def register():
    for cls in _classes():
        bpy.utils.register_class(cls)
    bpy.types.Scene.penumbra = bpy.props.PointerProperty(type=PenumbraSceneSettings)


def unregister():
    del bpy.types.Scene.penumbra
    for cls in reversed(_classes()):
        bpy.utils.unregister_class(cls)
