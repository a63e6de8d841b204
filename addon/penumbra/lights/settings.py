"""Light-rig settings stored in the .blend (scene.penumbra.light_rig). The
operator penumbra.build_light_rig takes its defaults from here when run from
the panel; a script can pass every setting to the operator directly."""

import bpy
from .. import compat
from ..core_settings import limits

MAPPING_ITEMS = (
    ("EQUIRECTANGULAR", "Equirectangular", "Full sphere, Blender's World convention (image centre faces +X)"),
    ("HEMISPHERE_POLAR", "Polar (Hemisphere)",
     "Upper hemisphere as latitude-longitude rows, e.g. the paper's 360x90 polar projection"),
    ("FISHEYE", "Fisheye (Hemisphere)", "Circular equidistant fisheye looking up; top of image faces +Y"),
    ("MIRROR_BALL", "Mirror Ball", "Photograph of a mirrored sphere taken looking along +Y"),
)
SAMPLER_ITEMS = (
    ("HAVRAN", "Havran", "Continuous, bijective hemisphere mapping (smooth light motion)"),
    ("STANDARD", "Standard", "Marginal/conditional inversion of the image (may jump between rows and at the seam)"),
)
TRACKING_ITEMS = (
    ("FOLLOW", "Follow", "Each light carries over from the previous frame, turned with the map's own motion and "
                         "refitted, so identities stay and lights do not jump (a new shot starts afresh)"),
    ("RESAMPLE", "Resample", "The paper's: every frame sampled anew, light k from the same point (lights wander "
                             "when the map turns)"),
)
TARGET_RENDERER_ITEMS = (
    ("SCENE", "Scene", "The renderer the scene is set to when the rig is built"),
    ("CYCLES", "Cycles", "Suns as Cycles draws them"),
    ("EEVEE", "EEVEE", "Suns as this Blender's EEVEE draws them: EEVEE Legacy before 4.2 (another sun power), "
                       "EEVEE Next from 4.2 (a shadowed sun's shadow also cuts the part of it below a surface's "
                       "horizon)"),
)
POWER_ITEMS = (
    ("REGION", "Region", "Each light carries the power and colour of its region of the map, at its energy centroid"),
    ("EQUAL", "Equal", "The paper's: every light gets the same power"),
)


class LightRigSceneSettings(bpy.types.PropertyGroup):
    filepath: bpy.props.StringProperty(
        name="Source", subtype="FILE_PATH", options=compat.BLEND_RELATIVE_PATH,
        description="HDR image, first frame of a numbered sequence, or video; empty uses the World's environment texture")
    mapping: bpy.props.EnumProperty(name="Mapping", items=MAPPING_ITEMS, default="EQUIRECTANGULAR")
    colorspace: bpy.props.StringProperty(
        name="Colour Space", default="",
        description="OpenColorIO colour space of the source (Blender's names, e.g. sRGB for an 8-bit video); "
                    "empty: the source is already scene-linear")
    count: bpy.props.IntProperty(name="Lights", **limits("lights.count"), soft_max=1024,
                                 description="Number of lights (the budget when Adaptive is on)")
    sampler: bpy.props.EnumProperty(name="Sampler", items=SAMPLER_ITEMS, default="HAVRAN")
    power: bpy.props.EnumProperty(name="Power", items=POWER_ITEMS, default="REGION")
    blue_noise: bpy.props.BoolProperty(name="Blue Noise", **limits("lights.blue_noise"),
                                       description="Start from Lloyd-relaxed Halton points")
    fit_irradiance: bpy.props.BoolProperty(
        name="Fit Irradiance", **limits("lights.fit_irradiance"),
        description="Refit each sun's colour, direction and angle so the suns, as this Blender draws them, light a "
                    "diffuse surface as the map does (up to 256 lights; slower per frame)")
    tracking: bpy.props.EnumProperty(name="Tracking", items=TRACKING_ITEMS, default="FOLLOW")
    temporal_filter: bpy.props.BoolProperty(name="Temporal Filter", **limits("lights.temporal_filter"),
                                            description="Low-pass each light's direction and power over time")
    filter_brightness: bpy.props.BoolProperty(
        name="Filter Brightness", **limits("lights.filter_brightness"),
        description="Also low-pass each frame's total brightness (removes a lamp's flicker, and the source's own "
                    "exposure changes); off: every frame is as bright as its map")
    cluster_max: bpy.props.IntProperty(name="Cluster Max", **limits("lights.cluster_max"),
                                       description="Merge nearby lights into at most this many (0: off)")
    adaptive_tolerance: bpy.props.FloatProperty(
        name="Adaptive Tolerance", **limits("lights.adaptive_tolerance"), subtype="FACTOR",
        description="Per shot, the fewest suns (Lights is the budget) whose irradiance error, as the target "
                    "renderer draws them, stays below this in every frame (0: fixed count)")
    frame_start: bpy.props.IntProperty(name="Start", default=1, description="Scene frame of the source's first frame")
    frame_end: bpy.props.IntProperty(name="End", default=250, description="Last scene frame to fill")
    limit_shadows: bpy.props.BoolProperty(
        name="Shadows for 8 Strongest", default=False,
        description="Only the 8 strongest suns cast shadows (EEVEE Legacy's limit)")
    shadow_budget: bpy.props.IntProperty(
        name="Shadow Budget", default=0, min=0,
        description="Only this many suns cast shadows: the strongest of those sharp enough to cast a visible "
                    "shadow, at most 53° wide (0: every sun, or Shadows for 8 Strongest; EEVEE Legacy draws "
                    "8 sun shadows, so a rig of more suns for it shadows the 8 strongest sharp ones)")
    target_renderer: bpy.props.EnumProperty(
        name="Target Renderer", items=TARGET_RENDERER_ITEMS, default="SCENE",
        description="The renderer the suns are fitted for (docs/lights.md, \"Suns in EEVEE\"). EEVEE Next "
                    "bounces the suns' light between objects only with Ray Tracing on (Render Properties) or "
                    "baked light probes")
    json_path: bpy.props.StringProperty(name="JSON", default="//penumbra_light_rig.json", subtype="FILE_PATH",
                                        options=compat.BLEND_RELATIVE_PATH,
                                        description="Per-frame lights for game engines, written beside the .blend")
    collection: bpy.props.PointerProperty(type=bpy.types.Collection, name="Rig Collection")
    last_report: bpy.props.StringProperty(name="Last Build", default="")
    # What the last build's adaptive count chose, kept with the .blend so the
    # panel shows it after reopening (0 and -1: the last build had a fixed count).
    adaptive_count: bpy.props.IntProperty(
        name="Chosen Count", default=0, min=0,
        description="Suns the last adaptive build chose: the largest count any shot needed within the tolerance")
    adaptive_error: bpy.props.FloatProperty(
        name="Error Reached", default=-1.0, subtype="FACTOR",
        description="The largest irradiance error of any frame at its shot's chosen count, the suns drawn as the "
                    "target renderer draws them (-1: fixed count)")


classes = (LightRigSceneSettings,)
