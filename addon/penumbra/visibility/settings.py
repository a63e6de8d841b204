"""Visibility-baker settings stored in the .blend.

Per object (`object.penumbra_visibility`): what to bake, the model it uses,
how to shade it, and the report of the last bake. Per scene
(`scene.penumbra.visibility`): run-time options shared by every object."""

import bpy
from .. import compat
from ..core_settings import limits


def _refresh(self, context):
    # Late import: frame_shading imports this module.
    from . import enabled_objects, frame_shading, gpu_preview
    enabled_objects.forget()  # `enabled` may be what changed
    frame_shading.request_refresh()
    gpu_preview.request_refresh()


def _gpu_preview_toggled(self, context):
    from . import gpu_preview
    gpu_preview.toggled(context.scene)


class VisibilitySceneSettings(bpy.types.PropertyGroup):
    threads: bpy.props.IntProperty(
        name="Threads", **limits("threads"),
        description="Worker threads for baking and shading (0: every core)")
    live_update: bpy.props.BoolProperty(
        name="Live Update", default=True,
        description="Re-shade enabled objects on frame changes and pose edits", update=_refresh)
    gpu_preview: bpy.props.BoolProperty(
        name="GPU Preview", default=False, update=_gpu_preview_toggled,
        description="Draw the shading of enabled objects in the 3D viewport with a GPU shader that follows the "
                    "pose (a display mode: the attributes and renders are unchanged)")
    gpu_preview_status: bpy.props.StringProperty(
        name="GPU Preview Status", default="",
        description="Why the GPU preview draws nothing (no GPU, a model it cannot draw), if it does not")


class VisibilityObjectSettings(bpy.types.PropertyGroup):
    # Bake settings (the operator's defaults come from here)
    frame_start: bpy.props.IntProperty(name="Start", default=1, description="First training frame")
    frame_end: bpy.props.IntProperty(name="End", default=24, description="Last training frame")
    frame_step: bpy.props.IntProperty(name="Step", default=1, min=1, description="Frames between training poses")
    rays: bpy.props.IntProperty(name="Rays", **limits("visibility.rays"),
                                description="Ray directions per vertex over the whole sphere")
    lobes: bpy.props.IntProperty(name="Lobes", **limits("visibility.lobes"), description="ZH lobes per vertex")
    sh_order: bpy.props.IntProperty(name="SH Order", **limits("visibility.sh_order"),
                                    description="Spherical-harmonic order (bands) of the visibility")
    occluders: bpy.props.PointerProperty(name="Occluders", type=bpy.types.Collection,
                                         description="Other objects that shadow this mesh (optional)")
    filepath: bpy.props.StringProperty(name="Model File", subtype="FILE_PATH", default="", options=compat.BLEND_RELATIVE_PATH,
                                       description="Where the model is written (empty: next to the .blend)")
    # Run time
    enabled: bpy.props.BoolProperty(name="Enable", default=False, update=_refresh,
                                    description="Shade this object from its visibility model on every frame")
    brdf: bpy.props.EnumProperty(
        name="BRDF", default="DIFFUSE", update=_refresh,
        items=(("DIFFUSE", "Diffuse", "Lambertian, shadowed by the baked visibility"),
               ("PHONG", "Phong", "Normalized Phong about the reflection of the scene camera"),
               ("TRANSLUCENT", "Translucent", "Thin-membrane translucency: shadowed front, unshadowed back")))
    phong_exponent: bpy.props.FloatProperty(name="Exponent", **limits("visibility.phong_exponent"), soft_max=1000.0,
                                            update=_refresh)
    transmission: bpy.props.FloatVectorProperty(name="Transmission", subtype="COLOR", size=3, min=0.0,
                                                **limits("visibility.transmission"), update=_refresh)
    # Result of the last bake, saved with the .blend
    model_path: bpy.props.StringProperty(name="Model", subtype="FILE_PATH", default="",
                                         options=compat.BLEND_RELATIVE_PATH)
    report: bpy.props.StringProperty(name="Report", default="", description="JSON summary of the last bake")
    status: bpy.props.StringProperty(name="Status", default="", description="Last run-time problem, if any")


classes = (VisibilitySceneSettings, VisibilityObjectSettings)
