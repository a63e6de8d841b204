"""The visibility sheet's GPU row (issue 27, run by examples/demo_visibility.py):
the GPU preview's per-vertex shading of a pose the model never saw, read back
through an RGBA32F offscreen buffer (gpu_model.ModelOnGpu.shade_offscreen),
beside the CPU run time's `penumbra_shading` of the same pose, their largest
per-vertex difference, and the preview's CPU milliseconds per frame. Needs a
GPU context: the bpy 5.x module gets one from gpu.init(); where there is none
(`blender -b`, the bpy 4.x module) the row says why instead."""

import statistics
import time

import bpy
import numpy as np

import contact_sheet as cs  # examples/contact_sheet.py
import demo_render  # examples/demo_render.py

GPU_SHADING = "demo_gpu_shading"  # point colour: the preview's shading, read back
GPU_DIFFERENCE = "demo_gpu_difference"  # point colour: max over RGB and AO of |GPU - CPU|
DIFFERENCE_SCALE = 1e-3  # the exactness tolerance of issue 27: the heat ramp's bright end
TIMED_FRAMES = 7  # preview updates timed; the median is printed


def unavailable_reason():
    """None when the GPU preview can draw here, else why not. The bpy 5.x
    module has no GPU context until gpu.init(); it is called once, only then."""
    from penumbra.visibility import gpu_preview
    reason = gpu_preview.gpu_unavailable_reason()
    if reason and bpy.app.background and bpy.app.version >= (5, 0, 0) and "gpu.init" in reason:
        import gpu
        gpu.init()
        reason = gpu_preview.gpu_unavailable_reason()
    return reason


def _point_colours(mesh, name):
    values = np.empty(len(mesh.vertices) * 4, dtype=np.float32)
    mesh.attributes[name].data.foreach_get("color", values)
    return values.reshape(-1, 4)


def _point_values(mesh, name):
    values = np.empty(len(mesh.vertices), dtype=np.float32)
    mesh.attributes[name].data.foreach_get("value", values)
    return values


def _set_colours(mesh, name, rgb):
    if name not in mesh.color_attributes:
        mesh.color_attributes.new(name, "FLOAT_COLOR", "POINT")
    rgba = np.concatenate([rgb, np.ones((len(rgb), 1), dtype=np.float32)], axis=1)
    mesh.attributes[name].data.foreach_set("color", np.ascontiguousarray(rgba, dtype=np.float32).reshape(-1))


def read_back(obj, scene, frame, brdf):
    """The CPU shading of `frame` (the frame handler's attributes) and the GPU
    preview's of the same pose, read back. Returns (GPU rgb (V, 3), what was
    measured)."""
    import gpu
    from penumbra.visibility import gpu_model, gpu_preview, mesh_data
    obj.penumbra_visibility.brdf = brdf
    scene.frame_set(frame)
    mesh = obj.data
    cpu_rgb = _point_colours(mesh, "penumbra_shading")[:, :3].copy()
    cpu_ao = _point_values(mesh, "penumbra_visibility")
    entry, inputs = gpu_preview.frame_of(obj, scene)
    on_gpu = gpu_model.ModelOnGpu(entry.model, entry.neighbours, mesh_data.polygon_topology(mesh))
    on_gpu.set_frame(inputs)
    gpu_rgb, gpu_ao = on_gpu.shade_offscreen()
    # What the preview's CPU does per frame: pose features, the evaluated
    # positions, packing (frame_of) and the upload (set_frame); the draw is the GPU's.
    seconds = []
    for _ in range(TIMED_FRAMES):
        started = time.perf_counter()
        on_gpu.set_frame(gpu_preview.frame_of(obj, scene)[1])
        seconds.append(time.perf_counter() - started)
    del on_gpu
    # The attributes hold RGB clamped at 0 and AO clamped to [0, 1]; the readback is unclamped.
    rgb_difference = np.abs(np.maximum(gpu_rgb, 0.0) - cpu_rgb).max(axis=1)
    ao_difference = np.abs(np.clip(gpu_ao, 0.0, 1.0) - cpu_ao)
    difference = np.maximum(rgb_difference, ao_difference)
    _set_colours(mesh, GPU_SHADING, np.maximum(gpu_rgb, 0.0))
    _set_colours(mesh, GPU_DIFFERENCE, np.repeat(difference[:, None], 3, axis=1))
    mesh.update()
    return {"frame": frame, "brdf": brdf.lower(), "vertices": len(cpu_ao),
            "renderer": f"{gpu.platform.renderer_get()} / {gpu.platform.version_get()}",
            "max_abs_rgb": float(rgb_difference.max()), "max_abs_visibility": float(ao_difference.max()),
            "max_abs": float(difference.max()), "cpu_rgb_max": float(cpu_rgb.max()),
            "preview_cpu_ms_per_frame": round(1e3 * statistics.median(seconds), 3), "timed_frames": TIMED_FRAMES}


def row(obj, scene, frame, brdf, render_attribute, tile):
    """The sheet's GPU row: (tiles, caption, summary). render_attribute(name)
    renders the object showing that point colour as emission and returns the
    render's RGBA; tile(rgb, alpha) frames a picture as the other rows' are."""
    reason = unavailable_reason()
    if reason:
        blank = np.empty((8, 8, 3), dtype=np.float32)
        blank[:] = cs.BACKGROUND
        lines = [f"GPU preview readback: not run in Blender {bpy.app.version_string}", reason,
                 "it runs in the bpy 5.x module after gpu.init(), or in Blender under Xvfb"]
        return [cs.Tile(blank, lines)], "", {"not_run": reason}
    result = read_back(obj, scene, frame, brdf)
    renders = [render_attribute(name) for name in ("penumbra_shading", GPU_SHADING, GPU_DIFFERENCE)]
    alpha = renders[0][..., 3]
    # Shown a stop darker, as the sheet's other shading tiles are.
    cpu, gpu_picture = (demo_render.display(demo_render.unpremultiply(r), exposure=-1.0) for r in renders[:2])
    difference = demo_render.unpremultiply(renders[2])[..., 0]
    tiles = [cs.Tile(tile(cpu, alpha), ["CPU shading", "penumbra_shading, forest.exr"]),
             cs.Tile(tile(gpu_picture, alpha), ["GPU preview", "read back, RGBA32F buffer"]),
             cs.Tile(tile(cs.heat(difference, DIFFERENCE_SCALE), alpha),
                     ["|GPU - CPU| per vertex", f"heat scale 0 - {DIFFERENCE_SCALE:g}"]),
             cs.Tile(cs.heat_legend(DIFFERENCE_SCALE), ["GPU difference scale"])]
    caption = (f"frame {frame} (never baked), {result['brdf']}: max |GPU - CPU| {result['max_abs']:.1e} over "
               f"{result['vertices']} vertices; preview CPU {result['preview_cpu_ms_per_frame']:.2f} ms/frame")
    return tiles, caption, result


def summary_line(result):
    """The GPU part of the sheet step's printed line."""
    if "not_run" in result:
        return "GPU readback not run here (no GPU context)"
    return (f"GPU vs CPU max {result['max_abs']:.1e}, preview CPU "
            f"{result['preview_cpu_ms_per_frame']:.2f} ms/frame")
