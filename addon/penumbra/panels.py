"""The "Penumbra" tab of the 3D Viewport sidebar: one section per tool."""

import bpy

from . import colormap, lights, native, visibility


class PENUMBRA_PT_main(bpy.types.Panel):
    bl_label = "Penumbra"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Penumbra"

    def draw(self, context):
        layout = self.layout
        if native.module is None:
            box = layout.box()
            box.alert = True
            box.label(text="Compiled core not loaded", icon="ERROR")
            for line in _wrap(str(native.load_error), 40):
                box.label(text=line)
        else:
            layout.label(text=f"Core {native.module.__version__}", icon="CHECKMARK")


class _ToolSection:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Penumbra"
    bl_parent_id = "PENUMBRA_PT_main"
    bl_options = {"DEFAULT_CLOSED"}


class PENUMBRA_PT_visibility(_ToolSection, bpy.types.Panel):
    bl_label = "Shadowed Relighting"

    def draw(self, context):
        visibility.draw_panel(self.layout, context)


class PENUMBRA_PT_light_rig(_ToolSection, bpy.types.Panel):
    bl_label = "Light Rig"

    def draw(self, context):
        lights.draw_panel(self.layout, context)


class PENUMBRA_PT_colormap(_ToolSection, bpy.types.Panel):
    bl_label = "Filtered Colour Maps"

    def draw(self, context):
        colormap.draw_panel(self.layout, context)


def _wrap(text, width):
    words, line, lines = text.split(), "", []
    for word in words:
        if len(line) + len(word) + 1 > width and line:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return lines + ([line] if line else [])


classes = (PENUMBRA_PT_main, PENUMBRA_PT_visibility, PENUMBRA_PT_light_rig, PENUMBRA_PT_colormap)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
