"""penumbra.bake_colormap_lut: replace the active ColorRamp by a node group
that samples a pre-filtered lookup image, and penumbra.restore_color_ramp to
put the ramp back.

Everything that can fail is checked before anything is changed (plan);
the lookup is then built (on a worker thread when run from the UI, through
modal_job.py, so Esc cancels and the header shows progress); only then are
files written (atomically, by the core) and the node tree edited (apply)."""

import math
import os
import tempfile

import bpy
import numpy as np

from . import filter_quality, filtered_ramp, footprint, native_filter, noise_filter, noise_maths, noise_model
from . import noise_statistics
from . import node_groups, point_footprint, ramp as ramp_io, sample_count, table_image
from .material import BakeError, Rollback, editable_material
from .surface_filter import filters_of
from .. import color, modal_job, native, node_links, world
from ..compat import socket_is
from ..errors import describe


def _pixel_size(scene):
    """2 tan(fov/2) / resolution along the fitted axis: a pixel's size at unit depth."""
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        return None, "the scene has no camera: the footprint is zero (plain ramp) until you add one and bake again"
    data = camera.data
    scale = scene.render.resolution_percentage / 100.0
    res_x, res_y = scene.render.resolution_x * scale, scene.render.resolution_y * scale
    if data.type == "ORTHO":
        return data.ortho_scale / max(res_x, res_y), None
    if data.type == "PANO":
        return 2.0 * math.tan(data.angle_x / 2.0) / res_x, "panoramic camera: the footprint assumes a pinhole"
    fit = data.sensor_fit
    if fit == "VERTICAL" or (fit == "AUTO" and res_y > res_x):
        return 2.0 * math.tan(data.angle_y / 2.0) / res_y, None
    return 2.0 * math.tan(data.angle_x / 2.0) / res_x, None


def _raster_offset(scene):
    """Raster position of the optical axis, in pixels (half the resolution,
    moved by the camera's shift): the footprint group snaps a sample to its
    pixel's centre with it."""
    scale = scene.render.resolution_percentage / 100.0
    res_x, res_y = scene.render.resolution_x * scale, scene.render.resolution_y * scale
    camera = scene.camera
    shift_x = shift_y = 0.0
    if camera is not None and camera.type == "CAMERA":
        shift_x, shift_y = camera.data.shift_x, camera.data.shift_y
    size = max(res_x, res_y)
    return res_x / 2.0 - shift_x * size, res_y / 2.0 - shift_y * size


def _coordinate_scale(socket, obj):
    """Texture-coordinate units per world unit of the noise's Vector input,
    `socket` what drives it (NoiseModel.vector_from; None: unlinked)
    (Generated / unlinked: 1 / object dimensions; Object: 1 / object scale)."""
    dims = sorted((d for d in (obj.dimensions if obj else ()) if d > 1e-9), reverse=True)[:2]
    generated = 1.0 / math.sqrt(dims[0] * dims[-1]) if dims else 1.0
    if socket is None:
        return generated, None
    if socket.node.bl_idname == "ShaderNodeTexCoord":
        if socket_is(socket, "Generated"):
            return generated, None
        if socket_is(socket, "Object") and socket.node.object is None and obj is not None:
            s = sorted(abs(v) for v in obj.scale)
            return 1.0 / math.sqrt(max(s[1] * s[2], 1e-12)), None
    return 1.0, (f"the noise's coordinates come from '{socket.node.name}.{socket.name}': assuming one texture "
                 "unit per world unit (adjust the Noise Filter's Scale input)")


def _ramp_fingerprint(node):
    """What the lookup and the node group are built from: the ramp's stops and
    modes, what drives its Fac, and the settings of a driving noise. Equal
    fingerprints: a lookup built from one fits the other."""
    source = ramp_io.driving_socket(node)
    noise = ramp_io.driving_noise(node)
    noise_settings = None
    if noise is not None:
        def linked(socket):
            # The link Blender evaluates (node_links), so muting a link counts as a change.
            link = node_links.live_link(socket)
            return None if link is None else (link.from_node.name, link.from_socket.identifier)
        noise_settings = (noise.name, noise.bl_idname, getattr(noise, "noise_dimensions", None),
                          getattr(noise, "musgrave_dimensions", None), getattr(noise, "noise_type", None),
                          getattr(noise, "musgrave_type", None), getattr(noise, "normalize", None),
                          tuple((i.identifier, linked(i), getattr(i, "default_value", None) if linked(i) is None and
                                 isinstance(getattr(i, "default_value", None), float) else None)
                                for i in noise.inputs if i.enabled))
    return (ramp_io.ramp_stops(node).tobytes(), tuple(ramp_io.ramp_modes(node)),
            (source.node.name, source.identifier) if source is not None else None, noise_settings)


class BakePlan:
    """Everything checked and gathered from the scene before any change.

    Run from the UI, the lookup is built in a thread while Blender keeps
    running (a script, a timer or another window can edit the tree, or undo
    can replace it), so the plan holds names, and apply() looks the material,
    the ramp and the image up again and refuses if what the lookup was built
    from changed (recheck)."""

    def __init__(self, context, settings, image_name=""):
        self.warnings = []
        self.scene = context.scene
        self.settings = settings
        self.image = None
        self.image_name = image_name
        self.material = None
        self.node = None
        self.noise = None
        if image_name:
            self._plan_image(image_name)
        else:
            self._plan_ramp(context)
            self.material_name, self.node_name = self.material.name, self.node.name
            self.fingerprint = _ramp_fingerprint(self.node)
        self.spec = {
            "width": settings.lut_width, "height": settings.lut_height,
            "sigma_max": self.sigma_max, "mean_min": self.mean_min, "mean_max": self.mean_max,
            "sigma_spacing": settings.sigma_spacing.lower(),
        }
        if not (self.sigma_max > 0 and math.isfinite(self.sigma_max)):
            raise BakeError("Sigma Max must be a finite number > 0")
        if not self.mean_max > self.mean_min:
            raise BakeError("Mean Max must be greater than Mean Min")
        self.folder = self._output_folder()

    def _plan_image(self, image_name):
        image = bpy.data.images.get(image_name)
        if image is None:
            raise BakeError(f"No image named '{image_name}'")
        width, height = image.size
        if width < 1 or height < 1:
            raise BakeError(f"Image '{image_name}' has no pixels: {world.unreadable(image)}")
        pixels = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(pixels)
        row = pixels.reshape(height, width, 4)[height // 2]  # the middle row is the colour map
        rgb = row[:, :3]
        space = image.colorspace_settings.name
        if not image.is_float and space not in ("Non-Color", "Raw"):
            # Byte pixels hold the image's encoding; ramp colours are in the
            # scene-linear working space (per file from Blender 5.0).
            rgb = color.to_working_space(color.blender_config(), rgb[None, :, :].copy(), space)[0]
        self.image = image
        self.samples = np.concatenate([rgb, row[:, 3:4]], axis=1).astype(np.float32)
        if not np.isfinite(self.samples).all():
            bad = int((~np.isfinite(self.samples).all(axis=1)).sum())
            raise BakeError(f"Image '{image_name}' has {bad} NaN or infinite pixel(s) in its middle row (the colour "
                            "map): fix or replace the image first")
        self.sigma_max = self.settings.sigma_max
        self.mean_min, self.mean_max = self.settings.mean_min, self.settings.mean_max
        self.name = bpy.path.clean_name(image.name)

    def _plan_ramp(self, context):
        self.material = editable_material(context)
        tree = self.material.node_tree
        node = tree.nodes.active
        if node is None or node.bl_idname != "ShaderNodeValToRGB":
            what = f"'{node.name}' ({node.bl_idname})" if node is not None else "nothing"
            raise BakeError(f"The active node of '{self.material.name}' is {what}, not a ColorRamp: "
                            "click a ColorRamp node first")
        self.node = node
        self.stops = ramp_io.ramp_stops(node)
        self.modes = ramp_io.ramp_modes(node)
        self.table_size = ramp_io.renderer_table_size(context.scene)
        if not np.isfinite(self.stops).all():
            raise BakeError(f"ColorRamp '{node.name}' has a NaN or infinite colour; fix the stop first")
        self.name = bpy.path.clean_name(f"{self.material.name}_{node.name}")
        self.noise = ramp_io.driving_noise(node)
        self.mean_min, self.mean_max = self.settings.mean_min, self.settings.mean_max
        self.sigma_max = self.settings.sigma_max
        if self.noise is not None:
            self._plan_noise(context)

    def _read_noise_model(self):
        fed = ramp_io.driving(self.node)
        try:
            return noise_model.read_noise(fed.node, fed.output, fed.path)
        except noise_model.NoiseNotDerivable as error:
            raise BakeError(f"{error} (nothing was changed)") from None

    def _plan_noise(self, context):
        self.noise_model = model = self._read_noise_model()
        if not model.lacunarity > 1.0:
            raise BakeError(f"the noise's Lacunarity is {model.lacunarity:g}: the filter needs a value > 1")
        if model.dimensions == "1D":
            self.warnings.append("1D noise follows W, which has no footprint: the filter sees its octaves but "
                                 "cannot spread its taps along W")
        # The widest filter needed is the noise's spread over a huge footprint;
        # the mean axis covers every value the noise can take.
        self.sigma_max = 1.05 * math.sqrt(noise_statistics.octave_table()["total_var"] * model.total_weight_sq)
        self.mean_min, self.mean_max = model.mean_min, model.mean_max
        self.orthographic = context.scene.camera is not None and context.scene.camera.type == "CAMERA" and \
            context.scene.camera.data.type == "ORTHO"
        self.pixel_size, warning = _pixel_size(context.scene)
        self.raster_offset = _raster_offset(context.scene)
        if warning:
            self.warnings.append(warning)
        self.coordinate_scale, warning = _coordinate_scale(self.noise_model.vector_from, context.object)
        if warning:
            self.warnings.append(warning)
        self.filter_stddev = noise_statistics.pixel_filter_stddev(context.scene)
        self.quality_key = self.settings.filter_quality
        self.quality = filter_quality.quality(self.quality_key)
        # The one-evaluation presets keep the 16 taps for one sample (the
        # per-sample verdicts of issue #12 hold there; docs/colormap.md).
        self.point = self.quality.taps == 1
        wanted = noise_maths.TAP_COUNT if self.point else self.quality.taps
        self.taps = min(wanted, noise_maths.tap_count(model, context.scene.render.engine))
        if self.taps < wanted:
            self.warnings.append(f"EEVEE: the noise filter uses {self.taps} taps, not {wanted} "
                                 f"({noise_maths.noise_evaluations_per_tap(model)} Noise evaluations per tap: "
                                 "Detail and Distortion), so that EEVEE can compile the material; bake again "
                                 "after switching to Cycles for the full filter")

    def _output_folder(self):
        folder = self.settings.output_folder or "//penumbra_luts/"
        if folder.startswith("//") and not bpy.data.filepath:
            return os.path.join(bpy.app.tempdir or tempfile.gettempdir(), "penumbra_luts")
        return os.path.normpath(bpy.path.abspath(folder))

    # ---- the work that may run in a thread: no bpy here -------------------
    def compute(self, progress=None):
        core = native.require()
        s = self.spec
        if self.image is not None:
            return core.colormap.lut(self.samples, s["width"], s["height"], s["sigma_max"], s["mean_min"],
                                     s["mean_max"], sigma_spacing=s["sigma_spacing"], progress=progress)
        knots = core.colormap.ramp_to_knots(self.stops, *self.modes, sampling=self.settings.sampling, channels=4,
                                            table_size=self.table_size)
        self.sampling_error = knots["max_sampling_error"]
        return core.colormap.lut_knots(knots["positions"], knots["colors"], knots["interpolation"], s["width"],
                                       s["height"], s["sigma_max"], s["mean_min"], s["mean_max"],
                                       sigma_spacing=s["sigma_spacing"], progress=progress)

    # ---- writing and editing the scene ------------------------------------
    def write_and_load(self, lut):
        core = native.require()
        os.makedirs(self.folder, exist_ok=True)
        path = self.lookup_paths()[0]
        # σ = 0 at the bottom (Blender's v = 0), so the node maps σ to v directly.
        pixels = np.ascontiguousarray(lut[::-1])
        core.image.write_exr(path, pixels, half=False, colorspace="Non-Color")
        if self.settings.write_png:
            core.image.write_png16(os.path.splitext(path)[0] + ".png", pixels, colorspace="Non-Color")
        image = None
        for existing in bpy.data.images:
            if existing.filepath and os.path.normpath(bpy.path.abspath(existing.filepath)) == path:
                image = existing
                image.reload()
                break
        if image is None:
            image = bpy.data.images.load(path, check_existing=False)
            table_image.relative_to_blend(image)
        image.colorspace_settings.name = "Non-Color"  # no colour transform on load
        image.alpha_mode = "CHANNEL_PACKED"
        return image, path

    def recheck(self):
        """Looks the image, or the material and its ramp, up again by name (the
        references taken when planning may be stale) and raises BakeError if
        the lookup no longer fits them. Changes nothing."""
        again = "bake again"
        if self.image_name:
            self.image = bpy.data.images.get(self.image_name)
            if self.image is None:
                raise BakeError(f"Image '{self.image_name}' was removed or renamed while its lookup was being "
                                f"built: {again}")
            return
        material = bpy.data.materials.get(self.material_name)
        if material is None or material.node_tree is None:
            raise BakeError(f"Material '{self.material_name}' was removed or renamed while the lookup of its "
                            f"ColorRamp '{self.node_name}' was being built: {again}")
        node = material.node_tree.nodes.get(self.node_name)
        if node is None or node.bl_idname != "ShaderNodeValToRGB":
            raise BakeError(f"ColorRamp '{self.node_name}' was removed from '{self.material_name}' while its "
                            f"lookup was being built: {again}")
        if _ramp_fingerprint(node) != self.fingerprint:
            raise BakeError(f"ColorRamp '{self.node_name}' in '{self.material_name}' was changed (its stops, "
                            f"or what drives its Fac) while its lookup was being built: {again}")
        self.material, self.node, self.noise = material, node, ramp_io.driving_noise(node)
        if self.noise is not None:  # the sockets it links, from this tree (an undo replaces the tree)
            self.noise_model = self._read_noise_model()

    def apply(self, lut):
        """Writes the files and edits the tree; if anything fails, puts the
        tree, the data blocks and the output folder back as they were."""
        self.recheck()
        rollback = Rollback(self.material.node_tree if self.node is not None else None, self.node)
        files = _LookupFiles(self)
        try:
            return self._apply(lut)
        except BaseException:
            rollback.restore()
            files.restore()
            raise
        finally:
            files.discard_backups()

    def lookup_paths(self):
        exr = os.path.join(self.folder, f"{self.name}_lut.exr")
        return exr, os.path.splitext(exr)[0] + ".png"

    def _apply(self, lut):
        image, path = self.write_and_load(lut)
        if self.node is None:
            group = filtered_ramp.filtered_ramp_group(image, self.spec)
            return {"image": image, "path": path, "group": group, "node": None}
        tree = self.material.node_tree
        ramp = self.node
        point = self.noise is not None and self.point
        mixture = self.noise is not None and (self.quality.mixture or point)
        single_fetch = point and self.scene.render.engine == "CYCLES"
        group = filtered_ramp.filtered_ramp_group(image, self.spec, mixture=mixture, single_fetch=single_fetch,
                                                  point=point)
        single = filtered_ramp.filtered_ramp_group(image, self.spec, mixture=mixture, single_fetch=single_fetch,
                                                   point=point, with_mixture=False) if point else None
        group_node = tree.nodes.new("ShaderNodeGroup")
        group_node.node_tree = group
        group_node.name = group_node.label = node_groups.FILTERED_RAMP
        group_node.location = ramp.location
        group_node["penumbra_original_ramp"] = ramp.name
        if single is not None:      # swapped by the sample count, as the Noise Filter's (sample_count.fit_group)
            sample_count.remember_group(group_node, sample_count.GROUP_AT_ONE_SAMPLE, group)
            sample_count.remember_group(group_node, sample_count.GROUP_ABOVE_ONE_SAMPLE, single)
            sample_count.fit_group(group_node, self.scene)
        # Outputs: whatever the ramp fed now comes from the group.
        for out_name in ("Color", "Alpha"):
            targets = [link.to_socket for link in ramp.outputs[out_name].links]
            for socket in targets:  # a new link into an input replaces the old one
                tree.links.new(group_node.outputs[out_name], socket)
        source = ramp_io.fac_source_in_tree(ramp)
        if self.noise is not None:
            self._wire_noise(tree, group_node, source)
        elif source is not None:
            tree.links.new(source, group_node.inputs["Mean"])
        else:
            group_node.inputs["Mean"].default_value = ramp.inputs["Fac"].default_value
        # The original stays, muted and out of the way, for undo and restore.
        ramp.mute = True
        ramp.label = "Penumbra: original ramp (muted)"
        ramp.location = (ramp.location.x, ramp.location.y - 320)
        tree.nodes.active = group_node
        return {"image": image, "path": path, "group": group, "node": group_node}

    def _footprint_node(self, tree, group, name, location):
        """A footprint group's node with the camera's pixel size and type."""
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        node.name = node.label = name
        node.location = location
        node.inputs["Pixel Size"].default_value = self.pixel_size or 0.0
        node.inputs["Orthographic"].default_value = 1.0 if self.orthographic else 0.0
        return node

    def _wire_noise(self, tree, group_node, source):
        octave_image, table = noise_statistics.octave_image(self.folder)
        filter_node = tree.nodes.new("ShaderNodeGroup")
        # Band-limited without taps at one sample either: one group for
        # every sample count (native_filter.py).
        band_limited = self.quality.native and not self.quality.taps_at_one and \
            native_filter.applies(self.noise_model)
        filter_node.node_tree = noise_filter.noise_filter_group(octave_image, table, self.noise_model,
                                                                self.filter_stddev, self.taps,
                                                                self.quality.analytic_octaves, self.point,
                                                                with_taps=not band_limited, native=self.quality.native)
        filter_node[filter_quality.NODE_PROPERTY] = self.quality_key
        eevee_taps = noise_maths.tap_count(self.noise_model, "BLENDER_EEVEE")
        if eevee_taps < self.taps and not band_limited:
            # Too costly for EEVEE at this many taps: keep a smaller group
            # for it, which the render_init handler swaps in.
            sample_count.remember_group(filter_node, sample_count.GROUP_FOR_CYCLES, filter_node.node_tree)
            eevee = noise_filter.noise_filter_group(octave_image, table, self.noise_model, self.filter_stddev,
                                                    eevee_taps, self.quality.analytic_octaves, self.point,
                                                    native=self.quality.native)
            sample_count.remember_group(filter_node, sample_count.GROUP_FOR_EEVEE, eevee)
        if self.point and not band_limited:
            sample_count.remember_group(filter_node, sample_count.GROUP_AT_ONE_SAMPLE, filter_node.node_tree)
            above = noise_filter.noise_filter_group(octave_image, table, self.noise_model, self.filter_stddev,
                                                    self.taps, self.quality.analytic_octaves, point=True,
                                                    with_taps=False, native=self.quality.native)
            sample_count.remember_group(filter_node, sample_count.GROUP_ABOVE_ONE_SAMPLE, above)
            sample_count.fit_group(filter_node, self.scene)
        sample_count.drive_samples(filter_node, self.scene)
        filter_node.name = filter_node.label = "Penumbra Noise Filter"
        filter_node.location = (group_node.location.x - 220, group_node.location.y + 40)
        footprint_node = self._footprint_node(tree, footprint.footprint_group(), node_groups.FOOTPRINT,
                                              (group_node.location.x - 440, group_node.location.y - 120))
        footprint_node.inputs["Raster Offset X"].default_value = self.raster_offset[0]
        footprint_node.inputs["Raster Offset Y"].default_value = self.raster_offset[1]
        if self.point:      # the one-evaluation filter's own, cheap footprint
            point_node = self._footprint_node(tree, point_footprint.point_footprint_group(),
                                              node_groups.POINT_FOOTPRINT,
                                              (group_node.location.x - 440, group_node.location.y - 320))
            for name in ("Minor", "Major"):
                tree.links.new(point_node.outputs[name], filter_node.inputs["Point " + name])
        if self.noise_model.vector_from is not None:
            tree.links.new(self.noise_model.vector_from, filter_node.inputs["Vector"])
        else:  # an unlinked texture vector means Generated coordinates
            coords = tree.nodes.new("ShaderNodeTexCoord")
            coords.name = coords.label = "Penumbra Noise Coordinates"
            coords.location = (footprint_node.location.x, footprint_node.location.y + 200)
            tree.links.new(coords.outputs["Generated"], filter_node.inputs["Vector"])
        tree.links.new(footprint_node.outputs["Minor"], filter_node.inputs["Minor"])
        tree.links.new(footprint_node.outputs["Major"], filter_node.inputs["Major"])
        for name in ("Axis U", "Axis V"):
            tree.links.new(footprint_node.outputs[name], filter_node.inputs[name])
        model = self.noise_model
        for name, source, value in (("Scale", model.scale_from, model.scale), ("W", model.w_from, model.w)):
            if source is not None:
                tree.links.new(source, filter_node.inputs[name])
            elif value is not None:
                filter_node.inputs[name].default_value = value
        filter_node.inputs["Units per World"].default_value = self.coordinate_scale
        for name in ("Mean", "Sigma", "Offsets", "Variances", "Mixture"):
            if name in group_node.inputs:  # one Gaussian: no mixture inputs
                tree.links.new(filter_node.outputs[name], group_node.inputs[name])


class _LookupFiles:
    """The output folder as apply() found it: new files are removed and
    overwritten lookups restored after a failure. The lookups are moved
    aside and back by _penumbra.replace_file_durably, so that after a power
    cut a backup, or a restored lookup, is really there."""

    def __init__(self, plan):
        self.folder = plan.folder
        self.created_folder = not os.path.isdir(self.folder)
        self.files = set() if self.created_folder else set(os.listdir(self.folder))
        self.backups = {}
        for path in plan.lookup_paths():
            if os.path.isfile(path):
                backup = path + ".penumbra-backup"
                native.require().replace_file_durably(path, backup)
                self.backups[path] = backup

    def restore(self):
        """After the material's Rollback.restore: the images left are the
        ones from before, and one that showed an overwritten lookup is
        reloaded from the restored file."""
        if os.path.isdir(self.folder):
            for name in set(os.listdir(self.folder)) - self.files:
                if not name.endswith(".penumbra-backup"):
                    os.remove(os.path.join(self.folder, name))
        for path, backup in self.backups.items():
            native.require().replace_file_durably(backup, path)
            for image in bpy.data.images:
                if image.filepath and os.path.normpath(bpy.path.abspath(image.filepath)) == path:
                    image.reload()
        self.backups = {}
        if self.created_folder and os.path.isdir(self.folder) and not os.listdir(self.folder):
            os.rmdir(self.folder)

    def discard_backups(self):
        for backup in self.backups.values():
            if os.path.exists(backup):
                os.remove(backup)
        self.backups = {}


class _LookupBake(modal_job.Job):
    """Builds the lookup (a worker: compute has no bpy), then writes it and
    edits the tree (apply, which puts everything back if it fails)."""

    def __init__(self, plan):
        super().__init__()
        self.plan = plan

    def status(self):
        return "Baking the filtered colour map"

    def failure(self, error):
        return f"Nothing was changed: {describe(error)}"

    def steps(self):
        plan = self.plan
        lut = yield modal_job.Worker(plan.compute)
        result = plan.apply(lut)
        what = f"'{plan.node.name}' in '{plan.material.name}'" if plan.node is not None else f"image '{plan.image.name}'"
        return [("INFO", f"Filtered {what}: lookup {result['path']}")] + [("WARNING", w) for w in plan.warnings]


class PENUMBRA_OT_bake_colormap_lut(modal_job.JobOperator, bpy.types.Operator):
    """Replace the active ColorRamp by a node group sampling a pre-filtered lookup image
(or bake the lookup of an image's colour map)"""
    bl_idname = "penumbra.bake_colormap_lut"
    bl_label = "Bake Filtered Colour Map"
    bl_options = {"REGISTER", "UNDO"}

    image_name: bpy.props.StringProperty(
        name="Image", default="",
        description="Bake the colour map held in this image's middle row instead of the active ColorRamp")

    def make_job(self, context):
        return _LookupBake(BakePlan(context, context.scene.penumbra.colormap, self.image_name))


class PENUMBRA_OT_restore_color_ramp(bpy.types.Operator):
    """Put the original ColorRamp back in place of the active Penumbra Filtered Ramp"""
    bl_idname = "penumbra.restore_color_ramp"
    bl_label = "Restore Original ColorRamp"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            material = editable_material(context)
        except BakeError as error:
            self.report({"ERROR"}, describe(error))
            return {"CANCELLED"}
        tree = material.node_tree
        group_node = tree.nodes.active
        ramp_name = group_node.get("penumbra_original_ramp") if group_node is not None else None
        if not isinstance(ramp_name, str) or not ramp_name:
            what = f"'{group_node.name}'" if group_node is not None else "nothing"
            self.report({"ERROR"}, f"The active node of '{material.name}' is {what}, not a Penumbra Filtered Ramp: "
                                   "click the filtered ramp whose ColorRamp should come back")
            return {"CANCELLED"}
        covering = filters_of(tree, group_node)
        if covering:
            # The filter reads the lookup through this group: restoring under
            # it would leave the filter without its inputs and the ramp unlinked.
            self.report({"ERROR"}, f"'{group_node.name}' is replaced by the surface filter '{covering[0].name}': "
                                   "remove the filter first (Remove Filter, penumbra.remove_surface_filter); "
                                   "nothing was changed")
            return {"CANCELLED"}
        ramp = tree.nodes.get(ramp_name)
        if ramp is None or ramp.bl_idname != "ShaderNodeValToRGB":
            why = "was deleted or renamed" if ramp is None else f"is now a {ramp.bl_label} node"
            self.report({"ERROR"}, f"The original ColorRamp '{ramp_name}' of '{group_node.name}' {why}: "
                                   "undo that change to restore it, or keep the filtered ramp (nothing was changed)")
            return {"CANCELLED"}
        for out_name in ("Color", "Alpha"):
            targets = [link.to_socket for link in group_node.outputs[out_name].links]
            for socket in targets:
                tree.links.new(ramp.outputs[out_name], socket)
        # The helper nodes the bake added (noise filter, footprint, noise
        # coordinates): collect names first, remove after (a removed node frees
        # its links, so never remove while walking them).
        doomed = set()
        for socket in group_node.inputs:
            for link in socket.links:
                if link.from_node.name.startswith("Penumbra Noise Filter"):
                    doomed.add(link.from_node.name)
                    for inner in link.from_node.inputs:
                        for inner_link in inner.links:
                            source = inner_link.from_node
                            if source.name.startswith("Penumbra"):
                                doomed.add(source.name)
        for name in doomed:
            sample_count.remove_driver(tree.nodes[name])
            tree.nodes.remove(tree.nodes[name])
        ramp.location = group_node.location
        tree.nodes.remove(group_node)
        ramp.mute = False
        ramp.label = ""
        tree.nodes.active = ramp
        self.report({"INFO"}, f"Restored ColorRamp '{ramp.name}'")
        return {"FINISHED"}


classes = (PENUMBRA_OT_bake_colormap_lut, PENUMBRA_OT_restore_color_ramp)
