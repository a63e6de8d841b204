"""Run by tests/python/test_gpu_preview_in_blender.py (and
bench/visibility_gpu_preview_benchmark.py, for the 100k-vertex timing) in a Blender that
has a GPU: Debian's Blender 3.4 in a real window under Xvfb (Mesa's
llvmpipe, OpenGL 4.5), or the bpy 5.x module after gpu.init() (EGL):

    xvfb-run -a blender --factory-startup --python gpu_preview_check.py -- [--vertices 10000] [--timing-vertices 100000]
    .venv313/bin/python gpu_preview_check.py --gpu-init [--vertices 10000] [--sweep production]

Shades on the GPU, reads back from an RGBA32F offscreen buffer (one vertex
per pixel) and compares per vertex with the CPU:
  1. the procedural test character, baked (order 4, 2 lobes), unseen poses,
     a non-uniform environment World and the scene camera, each BRDF: the
     preview's inputs (gpu_preview.object_inputs) shaded on the GPU against
     frame_shading.shade_object, the CPU run time that writes the attributes, and
     against the attributes themselves;
  2. random lobes, frames, positions, lighting and cameras (poles, cameras
     behind the surface, invalid vertices) for every SH order 1–8, 1–4 lobes
     and each BRDF, against _penumbra.sh.shade_pose.
Then times a pose: the CPU part, the upload, the GPU shading, and (in a
window) the viewport's own redraw with the preview on and off.
Prints one line `RESULT {json}`.
"""

import math
import os
import statistics
import sys
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path[:0] = [os.path.join(ROOT, "build", "addon"), os.path.join(ROOT, "examples", "scenes")]

ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]


def option(name, default):
    return type(default)(ARGS[ARGS.index(name) + 1]) if name in ARGS else default


VERTICES = option("--vertices", 10000)
TIMING_VERTICES = option("--timing-vertices", 0)
RANDOM_VERTICES = option("--random-vertices", 500)
SWEEP = option("--sweep", "full")   # full: every order 1–8 × 1–4 lobes; production: 2 lobes, and order 4

if "--gpu-init" in ARGS:
    import gpu
    gpu.init()

sys.path.append(ROOT)  # bench.helpers
import penumbra  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.gpu_preview_scene import gpu_draw_seconds  # noqa: E402
from penumbra.visibility import frame_shading, gpu_preview  # noqa: E402
import visibility_character  # noqa: E402


def detail_for(vertices):
    # visibility_character: about 890 · detail² vertices (8.1k measured at detail 3.0).
    return max(1.0, math.sqrt(vertices / 890.0))


def sky_world(scene):
    """A World lit by an environment image: a sky gradient and a warm sun, so
    every SH coefficient of the lighting is non-zero."""
    world = bpy.data.worlds.new("Sky")
    from penumbra import compat
    tree = compat.ensure_nodes(world)
    height, width = 32, 64
    rows = (np.arange(height) + 0.5) / height          # bottom-up, 0..1
    cols = (np.arange(width) + 0.5) / width
    elevation = (rows - 0.5) * math.pi
    pixels = np.zeros((height, width, 4), dtype=np.float32)
    sky = np.clip(np.sin(elevation), 0.0, None)[:, None]
    pixels[..., 0] = 0.2 + 0.5 * sky
    pixels[..., 1] = 0.25 + 0.6 * sky
    pixels[..., 2] = 0.3 + 1.2 * sky
    sun = np.exp(-(((rows[:, None] - 0.75) / 0.08) ** 2 + ((cols[None, :] - 0.3) / 0.05) ** 2))
    pixels[..., 0] += 6.0 * sun
    pixels[..., 1] += 4.5 * sun
    pixels[..., 2] += 2.0 * sun
    pixels[..., 3] = 1.0
    image = bpy.data.images.new("SkyGradient", width, height, float_buffer=True)
    image.pixels.foreach_set(pixels.ravel())
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    scene.world = world
    return world


def scene_camera(scene, location):
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = location
    return camera


def empty_scene():
    """Removes everything from the current file (reading the factory
    settings again would leave a window's script without a context)."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.armatures, bpy.data.actions,
                       bpy.data.cameras, bpy.data.lights, bpy.data.worlds, bpy.data.images, bpy.data.materials):
        for block in list(collection):
            collection.remove(block)
    return bpy.context.scene


def baked_character(vertices, frames=24, rays=32, tmp=None):
    scene = empty_scene()
    obj, rig = visibility_character.build(detail=detail_for(vertices), frames=frames)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    sky_world(scene)
    scene_camera(scene, (1.5, -6.0, 2.0))
    path = os.path.join(tmp or bpy.app.tempdir or "/tmp", f"gpu_preview_check_{len(obj.data.vertices)}.pzh")
    t = time.perf_counter()
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=frames, frame_step=2, rays=rays, lobes=2,
                                              sh_order=4, filepath=path)
    assert result == {"FINISHED"}, result
    seconds = time.perf_counter() - t
    obj.penumbra_visibility.enabled = True
    return scene, obj, seconds


def attribute(obj, name, width):
    data = obj.data.attributes[name].data
    out = np.empty(len(data) * width, dtype=np.float32)
    data.foreach_get("color" if width == 4 else "value", out)
    return out.reshape(-1, width) if width > 1 else out


def pipeline_comparison(scene, obj):
    """GPU shading of the preview's inputs vs the CPU run time, per unseen pose and BRDF."""
    out = {"max_abs_rgb": 0.0, "max_abs_visibility": 0.0, "max_abs_attributes": 0.0, "cases": [],
           "vertices": len(obj.data.vertices)}
    settings = obj.penumbra_visibility
    settings.phong_exponent = 12.0
    settings.transmission = (0.6, 0.4, 0.3)
    for frame in (4, 10, 18):            # even frames: the bake took 1, 3, 5, ...
        scene.frame_set(frame)
        for brdf in ("DIFFUSE", "PHONG", "TRANSLUCENT"):
            settings.brdf = brdf
            rgb, ao, _ = frame_shading.shade_object(obj, scene)        # CPU; writes the attributes
            inputs = gpu_preview.object_inputs(obj, scene)
            gpu_rgb, gpu_visibility = gpu_preview.shade_offscreen(inputs)
            # The attributes hold the clamped values (frame_shading.shade_object); clamp the same way.
            gpu_rgb = np.maximum(gpu_rgb, 0.0)
            gpu_visibility = np.clip(gpu_visibility, 0.0, 1.0)
            d_rgb = float(np.abs(gpu_rgb - rgb).max())
            d_vis = float(np.abs(gpu_visibility - ao).max())
            stored = attribute(obj, frame_shading.SHADING_ATTRIBUTE, 4)[:, :3]
            stored_ao = attribute(obj, frame_shading.VISIBILITY_ATTRIBUTE, 1)
            d_attr = float(max(np.abs(gpu_rgb - stored).max(), np.abs(gpu_visibility - stored_ao).max()))
            out["max_abs_rgb"] = max(out["max_abs_rgb"], d_rgb)
            out["max_abs_visibility"] = max(out["max_abs_visibility"], d_vis)
            out["max_abs_attributes"] = max(out["max_abs_attributes"], d_attr)
            out["cases"].append({"frame": frame, "brdf": brdf, "max_abs_rgb": d_rgb, "max_abs_visibility": d_vis,
                                 "rgb_max": float(rgb.max()), "rgb_mean": float(rgb.mean())})
    settings.brdf = "DIFFUSE"
    return out


def _unit(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def configurations(sweep):
    orders, lobe_counts = range(1, gpu_preview.MAX_ORDER + 1), range(1, gpu_preview.MAX_LOBES + 1)
    if sweep == "full":
        return [(o, c) for o in orders for c in lobe_counts]
    return sorted({(o, 2) for o in orders} | {(4, c) for c in lobe_counts})


def random_comparison(vertices, sweep):
    """The configurations the preview supports (all, or the production
    neighbourhood), against _penumbra.sh.shade_pose."""
    from penumbra import native
    core = native.require()
    rng = np.random.default_rng(7)
    worst_abs, worst_relative, count, invalid = 0.0, 0.0, 0, 0
    for order, lobes in configurations(sweep):
        for model in gpu_preview.MODELS:
            n = vertices
            normals = _unit(rng, n).astype(np.float32)
            tangents = _unit(rng, n).astype(np.float32)
            axes = _unit(rng, n * lobes).reshape(n, lobes, 3).astype(np.float32)
            bands = rng.normal(size=(n, lobes, order)).astype(np.float32)
            positions = rng.normal(size=(n, 3)).astype(np.float32)
            # Poles (φ free), a tangent along the normal, a zero normal, NaN band,
            # a zero axis with zero bands (unused lobe, valid), a zero axis with bands (invalid).
            normals[0:3] = [[0, 0, 1], [0, 0, -1], [1e-9, 0, 1]]
            tangents[3] = normals[3]
            normals[4] = 0.0
            bands[5, 0, 0] = np.nan
            axes[6, -1] = 0.0
            bands[6, -1] = 0.0
            axes[7, 0] = 0.0
            lighting = rng.normal(size=(order * order, 3))
            camera = rng.normal(size=3) * 2.0
            exponent = float(rng.choice([0.0, 1.0, 7.5, 60.0]))
            transmission = tuple(rng.random(3))
            rgb, info = core.sh.shade_pose(order, lighting, axes, bands, normals, tangents, brdf=model,
                                           exponent=exponent, positions=positions, camera=camera,
                                           transmission=transmission, with_stats=True)
            inputs = gpu_preview.inputs_from_arrays(order, lighting, axes, bands, normals, tangents,
                                                    positions=positions, model=model, phong_exponent=exponent,
                                                    camera=camera, transmission=transmission)
            gpu_rgb, gpu_visibility = gpu_preview.shade_offscreen(inputs)
            difference = max(float(np.abs(gpu_rgb - rgb).max()),
                             float(np.abs(gpu_visibility - info["visibility"]).max()))
            scale = max(1.0, float(np.abs(rgb).max()))
            worst_abs = max(worst_abs, difference)
            worst_relative = max(worst_relative, difference / scale)
            invalid += int(info["invalid_vertices"])  # shade to 0 on the CPU: the GPU must agree
            count += 1
    return {"configurations": count, "max_abs": worst_abs, "max_relative": worst_relative,
            "invalid_vertices": invalid, "vertices": vertices}


def _median_ms(samples):
    return round(1000.0 * statistics.median(samples), 3)


def _view3d():
    wm = bpy.context.window_manager
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                return window, area
    return None, None


def timing(scene, obj, repeats=3):
    """Milliseconds per pose, medians: the CPU part (synthesis, frames, packing),
    the upload, the GPU shading of every vertex (points) with its readback, the
    preview's triangles drawn at 1280×720, and, in a window, the 3D viewport's
    own redraw with the preview off and on."""
    frames = list(range(2, 2 + repeats))
    cpu, upload, shade, draw = [], [], [], []
    split = {"read": [], "pose_to_lobes": [], "frames": [], "pack": []}
    covered = 0
    for frame in frames:
        scene.frame_set(frame)
        t0 = time.perf_counter()
        inputs = gpu_preview.object_inputs(obj, scene)
        t1 = time.perf_counter()
        batch = gpu_preview.DrawBatch(inputs)
        t2 = time.perf_counter()
        gpu_preview.shade_offscreen(inputs)
        t3 = time.perf_counter()
        seconds, covered = gpu_draw_seconds(batch.draw)
        cpu.append(t1 - t0)
        upload.append(t2 - t1)
        shade.append(t3 - t2)
        draw.append(seconds)
        for key in split:
            split[key].append(inputs.seconds[key])
    out = {"vertices": len(obj.data.vertices), "cpu_ms": _median_ms(cpu), "upload_ms": _median_ms(upload),
           "gpu_shade_readback_ms": _median_ms(shade), "gpu_draw_1280x720_ms": _median_ms(draw),
           "draw_pixels_covered": covered, "cpu_split_ms": {k: _median_ms(v) for k, v in split.items()}}
    out["frame_ms"] = round(out["cpu_ms"] + out["upload_ms"] + out["gpu_draw_1280x720_ms"], 3)
    window, area = _view3d()
    if window is not None and not bpy.app.background:
        region = next(r for r in area.regions if r.type == "WINDOW")
        space = area.spaces.active
        space.region_3d.view_location = (0.0, 0.0, 1.3)  # the character fills the view
        space.region_3d.view_distance = 5.0
        override = {"window": window, "area": area, "region": region, "screen": window.screen}

        def redraw():
            t = time.perf_counter()
            if hasattr(bpy.context, "temp_override"):
                with bpy.context.temp_override(**override):
                    bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)
            else:
                bpy.ops.wm.redraw_timer(override, type="DRAW", iterations=1)
            return time.perf_counter() - t

        # Workbench's anti-aliasing redraws a still view many times over: off, for a frame time.
        bpy.context.preferences.system.viewport_aa = "OFF"
        scene.display.viewport_aa = "OFF"
        settings = scene.penumbra.visibility
        settings.live_update = False      # the preview alone, not the CPU attributes as well
        settings.gpu_preview = False
        redraw()
        off = statistics.median(redraw() for _ in range(repeats))
        settings.gpu_preview = True
        redraw()
        on = statistics.median(redraw() for _ in range(repeats))
        follow = []
        for frame in frames:
            t = time.perf_counter()
            scene.frame_set(frame)          # handler: the preview's CPU part
            redraw()                        # draw callback: upload + draw, with Blender's own viewport
            follow.append(time.perf_counter() - t)
        out["viewport"] = {"region": [region.width, region.height], "redraw_preview_off_ms": _median_ms([off]),
                           "redraw_preview_on_ms": _median_ms([on]),
                           "frame_change_and_redraw_ms": _median_ms(follow),
                           "status": settings.gpu_preview_status,
                           "drawn": bool(gpu_preview._previews)
                           and all(p.batch is not None for p in gpu_preview._previews.values())}
        settings.gpu_preview = False
        settings.live_update = True
    return out


def check(result):
    import gpu
    penumbra.register()
    result["unavailable"] = gpu_preview.gpu_unavailable_reason()
    result["renderer"] = f"{gpu.platform.renderer_get()} / {gpu.platform.version_get()}"
    scene, obj, bake_seconds = baked_character(VERTICES)
    result["bake_seconds"] = round(bake_seconds, 2)
    result["pipeline"] = pipeline_comparison(scene, obj)
    result["random"] = random_comparison(RANDOM_VERTICES, SWEEP)
    result["timing"] = [timing(scene, obj)]
    if TIMING_VERTICES:
        frame_shading.forget()
        scene, obj, bake_seconds = baked_character(TIMING_VERTICES, frames=8, rays=16)
        result["timing"].append(timing(scene, obj))
        result["timing"][-1]["bake_seconds"] = round(bake_seconds, 2)
    penumbra.unregister()


report(check)
