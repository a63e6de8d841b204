"""penumbra.build_light_rig: HDR image / sequence / video -> keyframed sun rig.

The work is split into steps (open, one step per frame, finish) so the same
job runs synchronously from a script (execute) and as a modal operator with
a timer from the UI (invoke: progress, Esc cancels), both through
modal_job.py. Nothing in the .blend changes until every frame has been
processed; a cancel or an error leaves the file as it was."""

import json
import math
import os
import tempfile

import bpy
import numpy as np

from .. import color, compat, modal_job, native, world
from . import rig_objects, settings, shadow_pool
from ..core_settings import limits

PREVIEW_NAME = "Penumbra Light Rig Preview"
_SETTING_NAMES = ("filepath", "mapping", "colorspace", "count", "sampler", "power", "blue_noise", "fit_irradiance",
                  "tracking", "temporal_filter", "filter_brightness", "cluster_max", "adaptive_tolerance", "frame_start", "frame_end",
                  "limit_shadows", "shadow_budget", "target_renderer", "json_path")


def running_builds():
    """(frames done, frames in all) of each light rig being built from the UI
    (the header shows them; so can a script or a test between two timer ticks)."""
    return [(build.rig.done, build.rig.frames) for build in modal_job.running() if isinstance(build, _RigBuild)]


# The widest grid the World's light is summed on when it is more than one
# rotated image: the core's working map is no wider (MapOptions::max_width's
# default), so a wider grid would only cost time.
WORLD_GRID_MAX_WIDTH = 2048


class _WorldSum:
    """Frames of the World's light when it is more than one image seen through
    a rotation (Backgrounds mixed or added, a Mapping Location or Scale):
    every term in the config's scene_linear role, summed on a latlong grid by
    world.environment_radiance frame by frame. A file's frames are read by
    the core in the image's colour space (or `colorspace`); a packed image, a
    still or a colour is the same in every frame."""

    def __init__(self, core, config, working, reading, colorspace):
        self.config, self.terms, self.values = config, reading.terms, []
        self.frame_count, self.frames_per_second, widths = 1, 0.0, []
        for term in self.terms:
            if term.kind != "environment":
                colour = np.ascontiguousarray(term.colour[None, None, :], dtype=np.float32)
                self.values.append(config.to_scene_linear(colour, working)[0, 0])
                continue
            path = world.image_file(term.image)
            if path is None:
                pixels = config.to_scene_linear(world.image_pixels(term.image, config, colorspace), working)
                self.values.append(pixels)
                width = pixels.shape[1]
            else:
                source = core.lights.open_source(path)
                self.values.append((source, colorspace or term.image.colorspace_settings.name))
                width = source.width
                self.frame_count = max(self.frame_count, source.frame_count)
                if self.frames_per_second <= 0.0:
                    self.frames_per_second = source.frames_per_second
            # A mirror ball of width w spans the sphere's 2π in about 2w pixels.
            widths.append(width if term.projection == "EQUIRECTANGULAR" else 2 * width)
        self.width = max(2, min(WORLD_GRID_MAX_WIDTH, max(widths)) // 2 * 2)

    def frame(self, index):
        """(width/2, width, 3) scene-linear radiance of frame `index`."""
        values = []
        for value in self.values:
            if isinstance(value, tuple):
                source, space = value
                value = self.config.to_scene_linear(source.read(min(index, source.frame_count - 1)), space)
            values.append(value)
        return world.environment_radiance(self.terms, values, self.width)


class _Job:
    """One build: open the source, add frames one by one, then apply."""

    def __init__(self, op, context):
        self.core = native.require()
        self.context = context
        self.scene = context.scene
        self.op = op
        self.strength = 1.0
        self.array = None  # pixels of a packed/generated World image, in the working space
        self.world_sum = None  # the World's light when it is more than one rotated image
        self.source_label = "World image (packed)"
        self.world_from_map = None
        self.mapping = op.mapping
        self.config = color.blender_config()
        # Scene-linear in this file: light colours are read in it (per file
        # from Blender 5.0; see color.working_space).
        self.working = color.working_space(self.config)
        self._check_colorspace(op.colorspace)
        if op.filepath:
            self.path, self.colorspace = bpy.path.abspath(op.filepath), op.colorspace
        else:
            self.path, self.colorspace = self._from_world(op.colorspace)
        self._check_colorspace(self.colorspace)
        wanted = max(1, op.frame_end - op.frame_start + 1)
        if self.world_sum is not None:
            self.source = None
            self.frames = min(self.world_sum.frame_count, wanted)
            self.fps = self.world_sum.frames_per_second
        elif self.array is not None:
            self.source = None
            self.frames = 1
            self.fps = 0.0
        else:
            self.source = self.core.lights.open_source(self.path)
            self.fps = self.source.frames_per_second
            self.frames = min(self.source.frame_count, wanted)
        if self.frames > 1 and self.fps <= 0.0:
            self.fps = self.scene.render.fps / self.scene.render.fps_base
        # The fit assumes every sun casts a shadow unless only a few do: then
        # the shadowless majority is drawn as Cycles draws it.
        self.eevee = rig_objects.targets_eevee(op.target_renderer, self.scene)
        self.shadows = rig_objects.shadow_choice(op.shadow_budget, op.limit_shadows,
                                                 rig_objects.legacy_eevee(self.eevee))
        self.sun_model = rig_objects.sun_model(eevee=self.eevee, shadow=self.shadows.count == 0)
        self.builder = self.core.lights.RigBuilder(
            count=op.count, sampler=op.sampler, blue_noise=op.blue_noise, power=op.power, mapping=self.mapping,
            temporal_filter=op.temporal_filter, frames_per_second=self.fps, cluster_max=op.cluster_max,
            adaptive_tolerance=op.adaptive_tolerance, world_from_map=self.world_from_map,
            fit_irradiance=op.fit_irradiance, tracking=op.tracking, filter_brightness=op.filter_brightness,
            sun_model=self.sun_model)
        self.done = 0

    def _check_colorspace(self, name):
        if name and not self.config.has_colorspace(name):
            names = ", ".join(self.config.colorspace_names())
            raise ValueError(f"unknown colour space '{name}'; Blender's config has: {names}")

    def _from_world(self, colorspace):
        """(path, colour space) of the World's map, read by penumbra.world with
        its strength, rotation and projection. A file is read by the core in
        its own colour space (or `colorspace`); a packed or generated image's
        pixels go to self.array, in the working space (path ''). A World that
        is more than one image seen through a rotation goes to self.world_sum,
        which hands over its light summed on a latlong grid (path '')."""
        reading = world.read_scene(self.scene)
        if reading.kind != "environment":
            raise ValueError(f"no source file given, and the World is not lit by an image ({reading.note}): "
                             "connect an Environment Texture with an image to the Background at the active "
                             "World Output, or give a Source file")
        if not reading.supported:
            raise ValueError(f"no source file given, and the World's map cannot be used as it is wired "
                             f"({reading.note}): fix that, or give a Source file")
        term = reading.rotated_image
        if term is None:
            self.world_sum = _WorldSum(self.core, self.config, self.working, reading, colorspace)
            self.mapping, self.source_label = "EQUIRECTANGULAR", f"World: {reading.source}"
            # Summed in the scene_linear role, like a file; colours converted back in apply.
            return "", self.working
        self.strength = term.weight * term.strength
        self.world_from_map = term.lookup.rotation.T
        self.mapping = term.projection  # the World's own: how Blender shows the map
        image = term.image
        path = world.image_file(image)
        if path is not None:
            return path, colorspace or image.colorspace_settings.name
        self.array = world.image_pixels(image, self.config, colorspace)
        # The rig is built in the config's scene_linear role, as from a file
        # (its luminance splits the map), and its colours converted back.
        return "", self.working

    def step(self):
        """Adds the next frame; returns True when every frame is in."""
        if self.world_sum is not None:
            self.builder.add_frame(self.world_sum.frame(self.done))
        elif self.array is not None:
            self.builder.add_frame(self.config.to_scene_linear(self.array, self.colorspace))
        else:
            self.builder.add_frame_from(self.source, self.done, self.config if self.colorspace else None,
                                        self.colorspace)
        self.done += 1
        return self.done >= self.frames

    def apply(self):
        rig = self.builder.finish(self.fps)
        if self.colorspace and self.config.scene_linear != self.working:
            # The core converted the source to the config's scene_linear role
            # (Linear Rec.709); this file's working space differs (Blender 5.0+).
            # Light colours are linear sums of pixels, so converting them is
            # the same as converting the map.
            rgb = np.asarray(rig["rgb"], dtype=np.float32)
            rig["rgb"] = self.config.convert(np.ascontiguousarray(rgb), self.config.scene_linear, self.working)
        if self.strength != 1.0:
            rig["rgb"] = rig["rgb"] * self.strength
            rig["power"] = rig["power"] * self.strength
        op = self.op
        s = self.scene.penumbra.light_rig
        # Everything that can fail without touching the .blend comes first:
        # the JSON (its text and folder) and the preview picture.
        json_path, json_text = self.rig_json(rig)
        image = self.builder.preview(rig["directions"][0], rig["rgb"][0], 512)
        write = rig_objects.write_rig(self.scene, s, rig, op.frame_start, op.limit_shadows, eevee=self.eevee,
                                      shadow_budget=op.shadow_budget)
        try:
            rig_objects.store_preview(PREVIEW_NAME, image)
            self.write_json(json_path, json_text)
        except BaseException:
            write.rollback()
            raise
        write.commit()
        self.store_adaptive(s, rig)
        collection = write.collection
        defects = {k: sum(d[k] for d in rig["defects"]) for k in ("nan", "inf", "negative")}
        bad = sum(defects.values())
        msg = (f"{rig['slots']} lights over {len(rig['defects'])} frame(s) in '{collection.name}'; JSON: {json_path}")
        if s.adaptive_count > 0:
            msg += f"; adaptive: {s.adaptive_count} suns, error {100.0 * s.adaptive_error:.2f} %"
        shadowed = shadow_pool.shadowed_suns(collection)
        if self.shadows.renderer_cap and shadowed < rig["slots"]:
            which = (f"the {shadowed} strongest sharp suns cast them" if shadowed else
                     "no sun is sharp enough to cast a visible one")
            msg += f"; EEVEE Legacy draws at most {rig_objects.LEGACY_SHADOWED_SUNS} sun shadows: {which}"
        overflow = shadow_pool.overflow_warning(self.scene, op.target_renderer, shadowed)
        if overflow:
            msg += "; " + overflow
        if bad:
            msg += (f"; replaced {defects['nan']} NaN, {defects['inf']} Inf and {defects['negative']} "
                    "negative pixel values by 0")
        s.last_report = msg[:250]
        return msg, bool(bad or overflow)

    @staticmethod
    def store_adaptive(settings_, rig):
        """Keeps the adaptive count's choice in the .blend (0 and -1: a fixed count)."""
        count = int(rig["adaptive_count"])
        errors = np.asarray(rig["adaptive_error"], dtype=float)
        settings_.adaptive_count = count
        settings_.adaptive_error = float(errors.max()) if count > 0 and errors.size else -1.0

    def write_json(self, path, text):
        """Publishes the rig's JSON, last, once the rig is in the scene (a failed
        build leaves the JSON there before): whole, and kept through a power cut."""
        self.core.write_file_durably(path, text.encode())

    def rig_json(self, rig):
        """The rig's JSON and where it goes, its folder made; returns (path, text)."""
        path = bpy.path.abspath(self.op.json_path or "//penumbra_light_rig.json")
        if path.startswith("//") or not bpy.data.filepath and self.op.json_path.startswith("//"):
            path = os.path.join(bpy.app.tempdir or tempfile.gettempdir(),
                                os.path.basename(self.op.json_path.lstrip("/")) or "penumbra_light_rig.json")
        frames = []
        for t in range(len(rig["defects"])):
            lights = []
            for k in range(rig["slots"]):
                lights.append({"index": k,
                               "direction": [round(float(v), 7) for v in rig["directions"][t][k]],
                               "rgb": [float(v) for v in rig["rgb"][t][k]]})
            frames.append({"frame": self.op.frame_start + t, "lights": lights})
        doc = {
            "format": "penumbra-light-rig",
            "version": 1,
            "source": self.path or self.source_label,
            "colorspace": self.working,
            "coordinates": "Blender world: +Z up; direction points from the scene towards the light",
            "units": "rgb = irradiance in W/m^2 on a surface facing the light, scene-linear "
                     "(a point-like Blender sun: strength = max(rgb), colour = rgb / strength)",
            "frames_per_second": rig["frames_per_second"],
            "filter_taps": list(rig["filter_taps"]),
            "frames": frames,
        }
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        return path, json.dumps(doc)


class PENUMBRA_OT_build_light_rig(modal_job.JobOperator, bpy.types.Operator):
    """Decompose an HDR image, sequence or video into a rig of keyframed sun lights"""
    bl_idname = "penumbra.build_light_rig"
    bl_label = "Build Light Rig"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(name="Source", subtype="FILE_PATH", default="",
                                       options=compat.BLEND_RELATIVE_PATH)
    mapping: bpy.props.EnumProperty(name="Mapping", items=settings.MAPPING_ITEMS, default="EQUIRECTANGULAR")
    colorspace: bpy.props.StringProperty(name="Colour Space", default="")
    count: bpy.props.IntProperty(name="Lights", **limits("lights.count"))
    sampler: bpy.props.EnumProperty(name="Sampler", items=settings.SAMPLER_ITEMS, default="HAVRAN")
    power: bpy.props.EnumProperty(name="Power", items=settings.POWER_ITEMS, default="REGION")
    blue_noise: bpy.props.BoolProperty(name="Blue Noise", **limits("lights.blue_noise"))
    fit_irradiance: bpy.props.BoolProperty(name="Fit Irradiance", **limits("lights.fit_irradiance"))
    tracking: bpy.props.EnumProperty(name="Tracking", items=settings.TRACKING_ITEMS, default="FOLLOW")
    temporal_filter: bpy.props.BoolProperty(name="Temporal Filter", **limits("lights.temporal_filter"))
    filter_brightness: bpy.props.BoolProperty(name="Filter Brightness", **limits("lights.filter_brightness"))
    cluster_max: bpy.props.IntProperty(name="Cluster Max", **limits("lights.cluster_max"))
    adaptive_tolerance: bpy.props.FloatProperty(name="Adaptive Tolerance", **limits("lights.adaptive_tolerance"))
    frame_start: bpy.props.IntProperty(name="Start", default=1)
    frame_end: bpy.props.IntProperty(name="End", default=250)
    limit_shadows: bpy.props.BoolProperty(name="Shadows for 8 Strongest", default=False)
    shadow_budget: bpy.props.IntProperty(name="Shadow Budget", default=0, min=0)
    target_renderer: bpy.props.EnumProperty(name="Target Renderer", items=settings.TARGET_RENDERER_ITEMS,
                                            default="SCENE")
    json_path: bpy.props.StringProperty(name="JSON", default="//penumbra_light_rig.json")

    def _take_scene_defaults(self, context):
        s = context.scene.penumbra.light_rig
        for name in _SETTING_NAMES:
            if not self.properties.is_property_set(name):
                setattr(self, name, getattr(s, name))

    def make_job(self, context):
        self._take_scene_defaults(context)
        # The count's lower bound is the property's (the core's range).
        if self.frame_end < self.frame_start:
            raise ValueError(f"frame_end ({self.frame_end}) is before frame_start ({self.frame_start})")
        return _RigBuild(_Job(self, context))


class _RigBuild(modal_job.Job):
    """One frame a step on the main thread (the source is read through bpy's
    colour management), then the rig is written."""

    cancelled_message = "Light rig cancelled; nothing was changed"

    def __init__(self, rig):
        super().__init__()
        self.rig = rig

    def status(self):
        return f"Light rig: frame {self.rig.done}/{self.rig.frames}"

    def steps(self):
        rig = self.rig
        while not rig.step():
            yield rig.done / rig.frames
        msg, warn = rig.apply()
        return [("WARNING" if warn else "INFO", msg)]


classes = (PENUMBRA_OT_build_light_rig,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
