"""Add-on preferences (Edit > Preferences > Add-ons > Penumbra)."""

import bpy

from . import native


def addon_package():
    """The name Blender registered this add-on under: "penumbra" for a legacy
    add-on, "bl_ext.<repo>.penumbra" for a 4.2+ extension."""
    return __package__


class PENUMBRA_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    ocio_config: bpy.props.StringProperty(
        name="OpenColorIO Config",
        description="Config used for colour conversion; empty uses Blender's own (recommended)",
        subtype="FILE_PATH",
    )
    threads: bpy.props.IntProperty(
        name="Threads",
        description="Threads for long work (0 = all cores)",
        default=0, min=0, max=1024,
    )

    def draw(self, context):
        layout = self.layout
        if native.module is None:
            box = layout.box()
            box.alert = True
            box.label(text="Compiled core not loaded:", icon="ERROR")
            box.label(text=str(native.load_error))
        else:
            info = native.module.build_info()
            layout.label(text=f"Core {info['version']} · {info['simd']} · OpenImageIO {info['openimageio']} "
                              f"· OpenColorIO {info['opencolorio']} · Embree {info['embree']}")
        layout.prop(self, "ocio_config")
        layout.prop(self, "threads")


def get(context=None):
    """This add-on's preferences, or None when not registered as an add-on
    (a batch script that called register() directly)."""
    context = context or bpy.context
    entry = context.preferences.addons.get(__package__)
    return entry.preferences if entry else None


def register():
    bpy.utils.register_class(PENUMBRA_AP_preferences)


def unregister():
    bpy.utils.unregister_class(PENUMBRA_AP_preferences)
