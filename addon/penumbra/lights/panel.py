"""The "Light Rig" section of the sidebar: the source, the light count and
frames, the Build button and what the last build made; how the source is
read, how lights are sampled, and what is written, in sub-panels."""

import bpy

from .. import sidebar
from . import operators, rig_objects, shadow_pool


def _split(layout):
    """Labels left, values right, as Blender's own panels; nothing here is animatable."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


class PENUMBRA_PT_light_rig(sidebar.ToolSection, bpy.types.Panel):
    bl_label = "Light Rig"

    def draw(self, context):
        layout = _split(self.layout)
        s = context.scene.penumbra.light_rig
        layout.prop(s, "filepath")
        if not s.filepath:
            sidebar.draw_wrapped(layout, context, "Empty: the World's environment texture", icon="WORLD")
        layout.prop(s, "count")
        column = layout.column(align=True)
        column.prop(s, "frame_start")
        column.prop(s, "frame_end")
        layout.operator("penumbra.build_light_rig", icon="LIGHT_SUN")
        if s.last_report:
            sidebar.draw_wrapped(layout, context, s.last_report, icon="INFO")
        preview = bpy.data.images.get(operators.PREVIEW_NAME)
        if preview is not None and hasattr(preview, "preview_ensure"):
            preview.preview_ensure()
            layout.template_icon(icon_value=preview.preview.icon_id, scale=8.0)


class _SubPanel(sidebar.SidebarPanel):
    bl_parent_id = "PENUMBRA_PT_light_rig"
    bl_options = {"DEFAULT_CLOSED"}


class PENUMBRA_PT_light_rig_source(_SubPanel, bpy.types.Panel):
    bl_label = "Source Format"

    def draw(self, context):
        layout = _split(self.layout)
        s = context.scene.penumbra.light_rig
        # Their values are too long for the value column: label above, field below.
        for name, label in (("mapping", "Mapping"), ("colorspace", "Colour Space")):
            column = layout.column(align=True)
            column.label(text=label)
            column.prop(s, name, text="")


class PENUMBRA_PT_light_rig_sampling(_SubPanel, bpy.types.Panel):
    bl_label = "Sampling"

    def draw(self, context):
        layout = _split(self.layout)
        s = context.scene.penumbra.light_rig
        layout.prop(s, "sampler")
        layout.prop(s, "power")
        layout.prop(s, "blue_noise")
        layout.prop(s, "fit_irradiance")
        layout.prop(s, "tracking")
        temporal = layout.column(heading="Temporal")
        temporal.prop(s, "temporal_filter", text="Filter")
        temporal.prop(s, "filter_brightness", text="Brightness")
        layout.prop(s, "cluster_max", text="Clusters")
        layout.prop(s, "adaptive_tolerance", text="Tolerance")
        if s.adaptive_count > 0:
            sidebar.draw_wrapped(layout, context, f"Last build chose {s.adaptive_count} suns, "
                                 f"error {100.0 * s.adaptive_error:.2f} %")


class PENUMBRA_PT_light_rig_output(_SubPanel, bpy.types.Panel):
    bl_label = "Output"

    def draw(self, context):
        layout = _split(self.layout)
        s = context.scene.penumbra.light_rig
        layout.prop(s, "target_renderer", text="Renderer")
        layout.prop(s, "json_path")
        shadows = layout.column(heading="Shadows")
        shadows.prop(s, "limit_shadows", text="8 Strongest")
        shadows.prop(s, "shadow_budget", text="Budget")
        if bpy.app.version < (4, 2, 0):
            sidebar.draw_wrapped(layout, context, "EEVEE Legacy draws at most 128 lights and 8 shadowed suns: "
                                 "limit shadows, or keep Lights at 128 or fewer", icon="INFO")
        elif missing_bounce_light(context.scene, s.target_renderer):
            sidebar.draw_wrapped(layout, context, "Ray Tracing is off: EEVEE gives the suns' light no bounce "
                                 "between objects (Render Properties)", icon="INFO")
        overflow = shadow_pool.overflow_warning(context.scene, s.target_renderer,
                                                shadow_pool.shadowed_suns(s.collection))
        if overflow:
            sidebar.draw_wrapped(layout, context, overflow, icon="ERROR")


def missing_bounce_light(scene, target_renderer):
    """Whether the rig is for EEVEE Next with Ray Tracing off: then its suns'
    light bounces nowhere, which Cycles' would (docs/lights.md, "Ray tracing
    gives back the bounce light")."""
    return (bpy.app.version >= (4, 2, 0) and rig_objects.targets_eevee(target_renderer, scene)
            and not scene.eevee.use_raytracing)


classes = (PENUMBRA_PT_light_rig, PENUMBRA_PT_light_rig_source, PENUMBRA_PT_light_rig_sampling,
           PENUMBRA_PT_light_rig_output)
