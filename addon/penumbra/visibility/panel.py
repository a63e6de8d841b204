"""The "Shadowed Relighting" section of the sidebar: the active mesh's bake
settings, how it is shaded from its model, the run-time options the scene
shares, and the report of its last bake, one sub-panel each."""

import bpy

from .. import sidebar
from . import report


def _mesh(context):
    obj = context.active_object
    return obj if obj is not None and obj.type == "MESH" else None


def _split(layout):
    """Labels left, values right, as Blender's own panels; nothing here is animatable."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


class PENUMBRA_PT_visibility(sidebar.ToolSection, bpy.types.Panel):
    bl_label = "Shadowed Relighting"

    def draw(self, context):
        layout = self.layout
        obj = _mesh(context)
        if obj is None:
            layout.label(text="Select a skinned mesh", icon="INFO")
            return
        status = obj.penumbra_visibility.status
        if status:
            column = layout.column()
            column.alert = True
            sidebar.draw_wrapped(column, context, status, icon="ERROR")


class _MeshSubPanel(sidebar.SidebarPanel):
    bl_parent_id = "PENUMBRA_PT_visibility"

    @classmethod
    def poll(cls, context):
        return _mesh(context) is not None


class PENUMBRA_PT_visibility_bake(_MeshSubPanel, bpy.types.Panel):
    bl_label = "Bake"

    def draw(self, context):
        layout = _split(self.layout)
        s = context.active_object.penumbra_visibility
        column = layout.column(align=True)
        column.prop(s, "frame_start")
        column.prop(s, "frame_end")
        column.prop(s, "frame_step")
        column = layout.column(align=True)
        column.prop(s, "rays")
        column.prop(s, "lobes")
        layout.prop(s, "occluders")
        layout.prop(s, "filepath")
        layout.operator("penumbra.bake_visibility", icon="RENDER_STILL")


class PENUMBRA_PT_visibility_shading(_MeshSubPanel, bpy.types.Panel):
    bl_label = "Shading"

    def draw_header(self, context):
        self.layout.prop(context.active_object.penumbra_visibility, "enabled", text="")

    def draw(self, context):
        layout = _split(self.layout)
        s = context.active_object.penumbra_visibility
        column = layout.column()
        column.active = s.enabled
        column.prop(s, "brdf")
        if s.brdf == "PHONG":
            column.prop(s, "phong_exponent")
        elif s.brdf == "TRANSLUCENT":
            column.prop(s, "transmission", text="Transmit")
        layout.operator("penumbra.apply_visibility", icon="SHADING_RENDERED")
        layout.operator("penumbra.setup_material", icon="MATERIAL")
        _draw_world(layout, context)


def _draw_world(layout, context):
    """What the shading reads from the World, in red when part of it cannot be read."""
    from .world_lighting import read_world
    column = layout.column()
    try:
        world = read_world(context.scene)
    except ValueError as error:  # a World it cannot read at all; a draw must not raise
        column.alert = True
        sidebar.draw_wrapped(column, context, f"World: {error}", icon="ERROR")
        return
    column.alert = not world.supported
    sidebar.draw_wrapped(column, context, f"World: {world.note}", icon="WORLD" if world.supported else "ERROR")


class PENUMBRA_PT_visibility_options(sidebar.SidebarPanel, bpy.types.Panel):
    """The scene's run-time options, shared by every shaded mesh."""
    bl_label = "Options"
    bl_parent_id = "PENUMBRA_PT_visibility"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = _split(self.layout)
        s = context.scene.penumbra.visibility
        column = layout.column()
        column.prop(s, "live_update")
        column.prop(s, "gpu_preview")
        if s.gpu_preview and s.gpu_preview_status:
            column = layout.column()
            column.alert = True
            sidebar.draw_wrapped(column, context, s.gpu_preview_status, icon="ERROR")
        layout.prop(s, "threads")


class PENUMBRA_PT_visibility_report(_MeshSubPanel, bpy.types.Panel):
    bl_label = "Last Bake"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        obj = _mesh(context)
        return obj is not None and bool(report.summary_lines(obj.penumbra_visibility.report))

    def draw(self, context):
        column = self.layout.column(align=True)
        for line in report.summary_lines(context.active_object.penumbra_visibility.report):
            sidebar.draw_wrapped(column, context, line)


classes = (PENUMBRA_PT_visibility, PENUMBRA_PT_visibility_bake, PENUMBRA_PT_visibility_shading,
           PENUMBRA_PT_visibility_options, PENUMBRA_PT_visibility_report)
