"""The "Penumbra" tab of the 3D Viewport sidebar: the core's state, then one
section per tool, each drawn by its tool (visibility/panel.py,
lights/panel.py, colormap/panel.py) with sub-panels for its advanced
settings. Registered here, in order, because every section hangs under
PENUMBRA_PT_main."""

import bpy

from . import native, sidebar
from .colormap import panel as colormap_panel
from .lights import panel as lights_panel
from .visibility import panel as visibility_panel


class PENUMBRA_PT_main(sidebar.SidebarPanel, bpy.types.Panel):
    bl_label = "Penumbra"

    def draw(self, context):
        layout = self.layout
        if native.module is None:
            column = layout.column()
            column.alert = True
            column.label(text="Core not loaded", icon="ERROR")
            sidebar.draw_wrapped(column, context, str(native.load_error), max_lines=8)
        else:
            layout.label(text=f"Core {native.module.__version__}", icon="CHECKMARK")


def classes():
    """Every panel, parents before their sub-panels, in the order they are drawn."""
    return (PENUMBRA_PT_main, *visibility_panel.classes, *lights_panel.classes, *colormap_panel.classes)


def register():
    for cls in classes():
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes()):
        bpy.utils.unregister_class(cls)
