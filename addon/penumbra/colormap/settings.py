"""Colour-map lookup settings stored in the .blend (scene.penumbra.colormap)."""

import bpy
from .. import compat
from ..core_settings import limits
from . import filter_quality


class ColormapSceneSettings(bpy.types.PropertyGroup):
    lut_width: bpy.props.IntProperty(
        name="Lookup Width", **limits("colormap.lut_width"),
        description="Columns of the lookup image (mean axis); the paper uses 256")
    lut_height: bpy.props.IntProperty(
        name="Lookup Height", **limits("colormap.lut_height"),
        description="Rows of the lookup image (standard-deviation axis)")
    sigma_spacing: bpy.props.EnumProperty(
        name="Sigma Spacing",
        items=[("LINEAR", "Linear", "Rows evenly spaced in sigma (most accurate in docs/colormap.md)"),
               ("QUADRATIC", "Quadratic", "Rows packed near sigma 0")],
        default="LINEAR")
    sampling: bpy.props.EnumProperty(
        name="Ramp Sampling",
        items=[("CYCLES", "As Rendered",
                "The table the scene's render engine evaluates a ColorRamp through (Cycles in 3.x: 256 "
                "entries; EEVEE, and Cycles from 4.x: 257), so the filter converges to the plain ramp's render"),
               ("EXACT", "Exact", "Blender's own ColorRamp evaluation (stops, or 1024 samples for curved modes)")],
        default="CYCLES")
    sigma_max: bpy.props.FloatProperty(
        name="Sigma Max", **limits("colormap.sigma_max"), soft_max=2.0,
        description="Widest filter the lookup holds when the ramp is not driven by a Noise Texture "
                    "(noise-driven ramps use the measured noise statistics)")
    mean_min: bpy.props.FloatProperty(name="Mean Min", **limits("colormap.mean_min"),
                                      description="Smallest driving mean in the lookup")
    mean_max: bpy.props.FloatProperty(name="Mean Max", **limits("colormap.mean_max"),
                                      description="Largest driving mean in the lookup")
    output_folder: bpy.props.StringProperty(
        name="Folder", default="//penumbra_luts/", subtype="DIR_PATH", options=compat.BLEND_RELATIVE_PATH,
        description="Where lookup images are written (next to the .blend by default; the temporary "
                    "folder while the file is unsaved)")
    filter_quality: bpy.props.EnumProperty(
        name="Filter Quality", items=filter_quality.enum_items(), default=filter_quality.DEFAULT,
        description="How the Noise Filter of the next bake spends its time: taps per sample, octaves carried "
                    "as variance, one Gaussian or a mixture (a baked material keeps its own until baked again)")
    write_png: bpy.props.BoolProperty(
        name="Also 16-bit PNG", default=False,
        description="Write a 16-bit PNG copy beside the float EXR (values clamped to [0, 1])")


classes = (ColormapSceneSettings,)
