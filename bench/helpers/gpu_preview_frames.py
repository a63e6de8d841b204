"""Run by bench/visibility_gpu_preview_benchmark.py inside a Blender with a
GPU (3.4 in a window under Xvfb, or the bpy 5.x module with --gpu-init):

    xvfb-run -a blender --factory-startup --python bench/helpers/gpu_preview_frames.py -- --vertices 10000,100000
    .venv313/bin/python bench/helpers/gpu_preview_frames.py --gpu-init --vertices 10000,100000

Issue 27's goal measurement. The procedural character at each size with a
synthetic model in the stored layout (order 4, 2 lobes, 1–3 joint blocks a
vertex, as a bake keeps): what Penumbra costs per frame does not depend on
the weights' values. With `live_update` off, frames alternate between the
preview off and on: the median `scene.frame_set` of each, plus, with it on,
the CPU time of the draw callback's upload (in a window, the real callback
under a forced redraw; without one, the same upload called directly), and
frame change plus one forced redraw both ways. Then the model's GPU memory,
its texture layout, its load time and the draw time at 1280×720. Prints one
line `RESULT {json}`.
"""

import os
import statistics
import sys
import tempfile
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [os.path.join(ROOT, "build", "addon"), os.path.join(ROOT, "examples", "scenes")]
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
SIZES = [int(v) for v in (ARGS[ARGS.index("--vertices") + 1] if "--vertices" in ARGS else "10000").split(",")]
SETTLE_SECONDS = 0.3
# Frames of each state, a number for every size (the last one repeats): a
# forced redraw at 1M vertices takes seconds on llvmpipe.
FRAMES = [int(f) for f in (ARGS[ARGS.index("--frames") + 1] if "--frames" in ARGS else "12").split(",")]

if "--gpu-init" in ARGS:
    import gpu
    gpu.init()

sys.path.append(ROOT)
import penumbra  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from penumbra.visibility import gpu_preview  # noqa: E402
from bench.helpers.gpu_preview_scene import character, gpu_draw_seconds  # noqa: E402


def view3d():
    wm = bpy.context.window_manager
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                region = next(r for r in area.regions if r.type == "WINDOW")
                space = area.spaces.active
                space.region_3d.view_location = (0.0, 0.0, 1.3)
                space.region_3d.view_distance = 5.0
                return {"window": window, "area": area, "region": region, "screen": window.screen}
    return None


def redraw(override):
    if override is None:  # no window: the draw callback's upload, called as it would
        for name, preview in gpu_preview._previews.items():
            if preview.batch is None:
                from penumbra.visibility import gpu_model, mesh_data
                preview.batch = gpu_model.ModelOnGpu(preview.entry.model, preview.entry.neighbours,
                                                     mesh_data.polygon_topology(bpy.context.scene.objects[name].data),
                                                     preview.entry.buffers.triangles)
            if preview.frame is not None:
                t = time.perf_counter()
                preview.batch.set_frame(preview.frame)
                preview.frame = None
                gpu_preview.last_timings["upload"] = time.perf_counter() - t
        return
    if hasattr(bpy.context, "temp_override"):
        with bpy.context.temp_override(**override):
            bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)
    else:
        bpy.ops.wm.redraw_timer(override, type="DRAW", iterations=1)


def ms(samples):
    return round(1000.0 * statistics.median(samples), 3)


def frame_costs(scene, override, frames):
    """Alternating frames with the preview off and on, `frames` of each: medians in ms."""
    settings = scene.penumbra.visibility
    off, on, upload, on_cpu, off_redraw, on_redraw, split = [], [], [], [], [], [], {}
    frame = 2
    for k in range(2 * frames + 2):
        preview = k % 2 == 1
        settings.gpu_preview = preview
        redraw(override)  # the toggle's own work (the model's upload) is done before the timed frame
        # llvmpipe rasterizes and uploads in its own threads after the calls
        # return: let it finish, or it competes with the timed frame.
        time.sleep(SETTLE_SECONDS)
        frame = 2 + (frame - 1) % 22
        t = time.perf_counter()
        scene.frame_set(frame)
        frame_set = time.perf_counter() - t
        gpu_preview.last_timings.pop("upload", None)
        redraw(override)
        with_redraw = time.perf_counter() - t
        if k < 2:
            continue  # warm-up pair
        if preview:
            assert settings.gpu_preview_status == "", settings.gpu_preview_status
            on.append(frame_set)
            upload.append(gpu_preview.last_timings["upload"])
            on_cpu.append(gpu_preview.last_timings["cpu_total"])
            on_redraw.append(with_redraw)
            if "--raw" in ARGS:
                print("RAW", {k: round(v * 1e3, 2) for k, v in gpu_preview.last_timings.items()}, round(frame_set * 1e3, 2))
            for key, value in gpu_preview.last_timings.items():
                split.setdefault(key, []).append(value)
        else:
            off.append(frame_set)
            off_redraw.append(with_redraw)
    settings.gpu_preview = False
    on_total = [a + b for a, b in zip(on, upload)]
    return {"frames": frames, "off_frame_set_ms": ms(off), "on_frame_set_ms": ms(on), "on_upload_ms": ms(upload),
            "on_total_ms": ms(on_total), "ratio": round(statistics.median(on_total) / statistics.median(off), 3),
            "preview_cpu_ms": round(ms(on_cpu) + ms(upload), 3),
            "split_ms": {k: ms(v) for k, v in split.items() if k != "model_upload"},
            "off_frame_and_redraw_ms": ms(off_redraw) if override else None,
            "on_frame_and_redraw_ms": ms(on_redraw) if override else None}


def measure(vertices, frames, tmp, override):
    t = time.perf_counter()
    scene, obj = character(vertices, tmp)
    out = {"vertices": len(obj.data.vertices), "build_seconds": round(time.perf_counter() - t, 1)}
    out.update(frame_costs(scene, override, frames), load_average=round(os.getloadavg()[0], 2))
    # The model's load: file to the GPU's textures.
    from penumbra.visibility import frame_shading, gpu_model, mesh_data
    frame_shading.forget()
    t = time.perf_counter()
    entry = frame_shading.loaded_model(obj)
    loaded = time.perf_counter()
    on_gpu = gpu_model.ModelOnGpu(entry.model, entry.neighbours, mesh_data.polygon_topology(obj.data),
                                  entry.buffers.triangles)
    uploaded = time.perf_counter()
    _, frame = gpu_preview.frame_of(obj, scene)
    on_gpu.set_frame(frame)
    geometry = frame.geometry[0][0] * frame.geometry[0][1] * 4  # R32F
    out.update({"load_file_s": round(loaded - t, 3), "load_gpu_s": round(uploaded - loaded, 3),
                "gpu_model_bytes_per_vertex": round(on_gpu.bytes / out["vertices"], 1),
                "gpu_frame_bytes_per_vertex": round(geometry / out["vertices"], 1),
                "texture_layout": {k: list(v) for k, v in on_gpu.layout.items()},
                "geometry_layout": list(frame.geometry[0]),
                "draw_1280x720_ms": round(1000.0 * gpu_draw_seconds(
                    lambda view_projection: on_gpu.draw(view_projection, gpu_preview.DEPTH_BIAS), repeats=3)[0], 2)})
    return out


def measure_all(result):
    import gpu
    penumbra.register()
    result["renderer"] = f"{gpu.platform.renderer_get()} / {gpu.platform.version_get()}"
    result["max_texture_size"] = gpu.capabilities.max_texture_size_get()
    override = None if bpy.app.background else view3d()
    if override is not None:
        bpy.context.preferences.system.viewport_aa = "OFF"
        bpy.context.scene.display.viewport_aa = "OFF"
    with tempfile.TemporaryDirectory() as tmp:
        result["sizes"] = [measure(v, FRAMES[min(k, len(FRAMES) - 1)], tmp, override) for k, v in enumerate(SIZES)]


report(measure_all)
