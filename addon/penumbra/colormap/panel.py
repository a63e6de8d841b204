"""The "Filtered Colour Maps" section of the sidebar: the two buttons that
filter the active ColorRamp and put it back, the surface filters (height,
slope, remove; greyed out until the active material has a baked filtered
ramp), then the lookup image's size, the range it covers and where it is
written, in sub-panels."""

import bpy

from .. import sidebar
from . import filter_quality, operators, sample_count, surface_filter
from .material import active_material


def _split(layout):
    """Labels left, values right, as Blender's own panels; nothing here is animatable."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _settings(context):
    return context.scene.penumbra.colormap


class PENUMBRA_PT_colormap(sidebar.ToolSection, bpy.types.Panel):
    bl_label = "Filtered Colour Maps"

    def draw(self, context):
        column = self.layout.column()
        column.operator(operators.PENUMBRA_OT_bake_colormap_lut.bl_idname, text="Bake Filtered Ramp",
                        icon="NODE_TEXTURE")
        has_ramp, has_filter, covered = surface_filter.panel_state(context)
        row = column.row()
        row.enabled = not covered  # a surface filter hides that ramp: remove the filter first
        row.operator(operators.PENUMBRA_OT_restore_color_ramp.bl_idname, text="Restore ColorRamp",
                     icon="LOOP_BACK")
        column = self.layout.column(align=True)
        column.label(text="Surface Filter")
        row = column.row(align=True)
        row.enabled = has_ramp
        add = surface_filter.PENUMBRA_OT_add_surface_filter.bl_idname
        row.operator(add, text="Height").kind = "HEIGHT"
        row.operator(add, text="Slope").kind = "SLOPE"
        row = column.row(align=True)
        row.enabled = has_filter
        row.operator(surface_filter.PENUMBRA_OT_remove_surface_filter.bl_idname, text="Remove Filter",
                     icon="X")


class _SubPanel(sidebar.SidebarPanel):
    bl_parent_id = "PENUMBRA_PT_colormap"


class PENUMBRA_PT_colormap_lookup(_SubPanel, bpy.types.Panel):
    bl_label = "Lookup Image"

    def draw(self, context):
        layout = _split(self.layout)
        s = _settings(context)
        column = layout.column(align=True)
        column.prop(s, "lut_width", text="Width")
        column.prop(s, "lut_height", text="Height")
        layout.prop(s, "sigma_spacing", text="Spacing")


class PENUMBRA_PT_colormap_quality(_SubPanel, bpy.types.Panel):
    bl_label = "Filter Quality"

    def draw(self, context):
        layout = self.layout
        s = _settings(context)
        layout.prop(s, "filter_quality", text="")
        measured = filter_quality.measured()
        column = layout.column(align=True)
        # Time: a filtered sample's over a plain one's; error: RMSE over the
        # plain ramp's at equal render time, 16 spp (both from the benchmark).
        split = column.split(factor=0.55)
        split.label(text="Preset")
        split.label(text="Time, Error")
        for key, quality in filter_quality.QUALITIES.items():
            numbers = measured.get(key)
            split = column.split(factor=0.55)
            split.label(text=("› " if key == s.filter_quality else "") + quality.label)
            split.label(text=f"{numbers['cost']:.2g}× {numbers['ratio']:.2f}" if numbers else "–")
        material = active_material(context)
        nodes = sample_count.noise_filter_nodes(material) \
            if material is not None and material.node_tree is not None else []
        reason = filter_quality.rebake_reason(nodes, s.filter_quality)
        if reason:
            box = layout.box()
            box.alert = True
            box.label(text=reason, icon="ERROR")
            box.label(text="Restore, bake again to apply")


class PENUMBRA_PT_colormap_range(_SubPanel, bpy.types.Panel):
    bl_label = "Range"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = _split(self.layout)
        s = _settings(context)
        layout.prop(s, "sigma_max")
        column = layout.column(align=True)
        column.prop(s, "mean_min")
        column.prop(s, "mean_max")
        # "As Rendered" is too long for the value column: label above, menu below.
        column = layout.column(align=True)
        column.label(text="Ramp Sampling")
        column.prop(s, "sampling", text="")


class PENUMBRA_PT_colormap_output(_SubPanel, bpy.types.Panel):
    bl_label = "Output"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = _split(self.layout)
        s = _settings(context)
        layout.prop(s, "output_folder")
        layout.column(heading="Also Write").prop(s, "write_png", text="16-bit PNG")


classes = (PENUMBRA_PT_colormap, PENUMBRA_PT_colormap_quality, PENUMBRA_PT_colormap_lookup,
           PENUMBRA_PT_colormap_range, PENUMBRA_PT_colormap_output)
