"""Equal-time comparison of the plain ColorRamp and Penumbra's filtered ramp
in Cycles, in one Blender process (issue #25): the benchmark plane, one
material per method (the plain ramp and one baked copy per filter quality),
renders timed as bpy.ops.render.render after one untimed warm-up per method,
methods interleaved, the median of the repeats' seconds (wall and CPU of
this process) and the mean of their RMSEs against a high-sample plain
render. Used by bench/colormap_benchmark.py and
tests/blender/colormap/test_colormap_equal_time.py. Needs bpy and the add-on."""

import os
import statistics
import time

import bpy
import numpy as np

from bench.helpers.colormap_equal_time_maths import PLAIN, equal_time_ratios, plain_error_at  # noqa: F401  (re-exported)


def new_plane_scene(size, threads=2, **plane_options):
    """Factory settings, Cycles on the CPU (no denoising, no adaptive
    sampling), the benchmark plane (colormap_scene.noise_ramp_plane,
    Roughness 0.5 unless given) at `size`. Returns (scene, plane, material)."""
    plane_options.setdefault("roughness", 0.5)
    return _cycles_scene(size, threads, "noise_ramp_plane", plane_options)


def new_bench_scene(name, scale, threads=2):
    """The benchmark scene `name` of colormap_render.SCENES (its builder,
    options and resolution factor on 192×108 times `scale`), set up as
    new_plane_scene. Returns (scene, object, material)."""
    from bench.blender_scripts.colormap_render import BASE_SIZE, SCENES
    builder, options, factor, _ = SCENES[name]
    size = tuple(max(4, round(v * factor * scale)) for v in BASE_SIZE)
    return _cycles_scene(size, threads, builder, dict(options))


LIT_HDRI = ("studiolights/world", "courtyard.exr")  # shipped with Blender; the one without a sun (max 50)


def new_lit_scene(name, scale, threads=2):
    """Issue #25's lit scene: the benchmark scene `name` (plane or torus)
    with the ramp as the Base Color of a Principled BSDF (Roughness 0.4)
    instead of an emission, under Blender's courtyard HDRI as the World
    (importance map 128 wide), 2 diffuse and 2 glossy bounces. Returns
    (scene, object, material)."""
    scene, obj, material = new_bench_scene(name, scale, threads)
    tree = material.node_tree
    emission = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeEmission")
    ramp = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeValToRGB")
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Roughness"].default_value = 0.4
    tree.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    tree.links.new(bsdf.outputs[0], output.inputs["Surface"])
    tree.nodes.remove(emission)
    world = scene.world.node_tree
    environment = world.nodes.new("ShaderNodeTexEnvironment")
    environment.image = bpy.data.images.load(os.path.join(bpy.utils.system_resource("DATAFILES",
                                                                                       path=LIT_HDRI[0]), LIT_HDRI[1]))
    world.links.new(environment.outputs["Color"], world.nodes["Background"].inputs["Color"])
    world.nodes["Background"].inputs["Strength"].default_value = 1.0
    # The World's importance map is rebuilt at every render: at its default
    # 1024 it took over a second, more than the small renders themselves.
    scene.world.cycles.sampling_method = "MANUAL"
    scene.world.cycles.sample_map_resolution = 128
    cycles = scene.cycles
    cycles.max_bounces, cycles.diffuse_bounces, cycles.glossy_bounces = 4, 2, 2
    cycles.transmission_bounces = cycles.volume_bounces = cycles.transparent_max_bounces = 0
    return scene, obj, material


def _cycles_scene(size, threads, builder, options):
    from bench.helpers.paths import use_addon
    use_addon()                 # examples/scenes: colormap_scene
    import colormap_scene
    from bench.blender_scripts.colormap_render import new_scene   # factory settings, size, EXR, black world
    scene = new_scene(size, threads)
    if not hasattr(bpy.types.Scene, "penumbra"):    # a batch script that only imported the add-on
        import penumbra
        penumbra.register()
        scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_animated_seed = False
    obj, material, _ramp, _emission, _camera = getattr(colormap_scene, builder)(**options)
    return scene, obj, material


def bake_quality(scene, plane, material, quality, folder):
    """A copy of the (unbaked) `material` baked with the filter preset
    `quality`; returns it."""
    baked = material.copy()
    baked.name = f"{material.name} {quality}"
    plane.material_slots[0].material = baked
    bpy.context.view_layer.objects.active = plane
    ramp = next(n for n in baked.node_tree.nodes if n.bl_idname == "ShaderNodeValToRGB")
    baked.node_tree.nodes.active = ramp
    scene.penumbra.colormap.filter_quality = quality
    scene.penumbra.colormap.output_folder = folder
    result = bpy.ops.penumbra.bake_colormap_lut()
    plane.material_slots[0].material = material
    if result != {"FINISHED"}:
        raise RuntimeError(f"the bake with quality {quality} failed: {result}")
    return baked


class Renderer:
    """Renders the plane with one of its materials at a sample count and seed."""

    def __init__(self, scene, plane, materials, folder):
        self.scene, self.plane, self.materials, self.folder = scene, plane, materials, folder
        self.count = 0

    def render(self, method, spp, seed):
        """(image, wall seconds, CPU seconds of this process)."""
        from penumbra import native
        self.plane.material_slots[0].material = self.materials[method]
        self.scene.cycles.samples = spp
        self.scene.cycles.seed = seed
        bpy.context.view_layer.update()          # the Samples driver reads the new count
        self.scene.frame_set(self.scene.frame_current)
        self.count += 1
        path = os.path.join(self.folder, f"render_{self.count}.exr")
        self.scene.render.filepath = path
        started, cpu = time.perf_counter(), time.process_time()
        bpy.ops.render.render(write_still=True)
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu
        image = native.require().image.read(path)
        os.remove(path)
        return image, wall, cpu


def rmse(image, reference, mask=None):
    squared = (image[..., :3] - reference[..., :3]) ** 2
    return float(np.sqrt(squared.mean() if mask is None else squared[mask].mean()))


def sweep(renderer, reference, counts, repeats=3, seed0=0, mask=None):
    """{method: {spp: {"rmse", "rmse_sd", "wall", "cpu"}}} for counts
    {method: [spp, ...]}: after one warm-up render per method, for each
    repeat every (method, spp) in turn (interleaved), seed seed0 + repeat;
    times are medians, errors the mean (and standard deviation) over the
    repeats' seeds. With a pixel `mask` (colormap_render.interior_mask),
    also "rmse_interior" and "rmse_interior_sd" over those pixels."""
    for method in counts:
        renderer.render(method, 1, seed0)
    raw = {(m, s): [] for m, spps in counts.items() for s in spps}
    for repeat in range(repeats):
        for method, spps in counts.items():
            for spp in spps:
                image, wall, cpu = renderer.render(method, spp, seed0 + repeat)
                inner = rmse(image, reference, mask) if mask is not None else float("nan")
                raw[(method, spp)].append((rmse(image, reference), wall, cpu, inner))
    out = {m: {} for m in counts}
    for (method, spp), rows in raw.items():
        out[method][spp] = {"wall": statistics.median(r[1] for r in rows),
                            "cpu": statistics.median(r[2] for r in rows)}
        for key, column in (("rmse", 0), ("rmse_interior", 3)):
            if key == "rmse_interior" and mask is None:
                continue
            errors = [r[column] for r in rows]
            out[method][spp][key] = statistics.fmean(errors)
            out[method][spp][key + "_sd"] = statistics.stdev(errors) if len(errors) > 1 else 0.0
    return out


def reference_image(renderer, spp, seed=1000):
    image, _, _ = renderer.render(PLAIN, spp, seed)
    return image
