"""The visibility run time's frame-change measurement, shared by
bench/visibility_benchmark.py (the procedural character) and
bench/visibility_humanoid_benchmark.py (the realistic one): a frame change
with Penumbra's handler against Blender's own frame change of the same scene,
alternated frame by frame in the same run, the handler's breakdown, and the
accuracy of the dispatched SIMD kernel on the same pose. Inside the bpy
module, with the add-on registered and a model baked on `obj`."""

import os
import subprocess
import time

import bpy
import numpy as np

from penumbra import native
from penumbra.visibility import armature_data, frame_shading, mesh_data, world_lighting

from bench.helpers.paths import BUILD


def _median_and_spread(values):
    """Median and half the interquartile range (the ± beside each time)."""
    q1, median, q3 = np.percentile(values, [25, 50, 75])
    return float(median), float((q3 - q1) / 2)


def frame_change_costs(obj, frames, repeats=21, brdf="PHONG"):
    """Frame changes of `obj`'s scene with the run time on (alternating
    frames[k % len] with it, frames[(k + 1) % len] without) and Blender's own
    frame change without it; medians in seconds, the handler's breakdown
    (frame_shading.last_timings), the ratio, and the accuracy on the last pose."""
    core = native.require()
    settings = obj.penumbra_visibility
    settings.brdf = brdf
    scene = bpy.context.scene
    rows, plain = [], []
    for k in range(repeats):
        settings.enabled = True    # shades at once (outside the timing)
        started = time.perf_counter()
        scene.frame_set(frames[(2 * k) % len(frames)])
        total = time.perf_counter() - started
        rows.append(dict(frame_shading.last_timings, frame_change=total))
        settings.enabled = False
        started = time.perf_counter()
        scene.frame_set(frames[(2 * k + 1) % len(frames)])
        plain.append(time.perf_counter() - started)
    result = {key: float(np.median([r[key] for r in rows])) for key in rows[0]}
    result["frame_change"], result["frame_change_spread"] = _median_and_spread([r["frame_change"] for r in rows])
    result["frame_change_without_penumbra"], result["frame_change_without_penumbra_spread"] = \
        _median_and_spread(plain)
    # What the frame change spends outside the handler beyond Blender's own
    # frame change: mostly Blender evaluating the mesh's modifiers again for
    # the attributes the handler wrote.
    result["after_handler"] = float(np.median([r["frame_change"] - r["total"] for r in rows])) - \
        result["frame_change_without_penumbra"]
    result["ratio"] = result["frame_change"] / result["frame_change_without_penumbra"]
    result["vertices"] = len(obj.data.vertices)
    result["repeats"] = repeats
    result["load_average"] = os.getloadavg()[0]  # the machine may be shared: say how busy it was
    settings.enabled = True
    result["simd_target"] = core.sh.simd_target()
    result.update(frame_change_accuracy(core, obj, scene))
    settings.enabled = False
    return result


def summary(result):
    """One log line of frame_change_costs' result."""
    r = result
    return (f"run time at {r['vertices']} vertices ({r['simd_target']}): frame change "
            f"{1e3 * r['frame_change']:.2f} ± {1e3 * r['frame_change_spread']:.2f} ms, without Penumbra "
            f"{1e3 * r['frame_change_without_penumbra']:.2f} ± {1e3 * r['frame_change_without_penumbra_spread']:.2f}"
            f" ms, ratio {r['ratio']:.2f} (goal <= 4.5 at 100k); gather {1e3 * r['gather']:.2f} "
            f"(mesh {1e3 * r['read_mesh']:.2f}), normals {1e3 * r['normals']:.2f}, pose -> lobes "
            f"{1e3 * r['pose_to_lobes']:.2f}, frames {1e3 * r['frames']:.2f}, shading "
            f"{1e3 * r['shading']:.2f}, write {1e3 * r['write_attributes']:.2f}, after the handler "
            f"{1e3 * r['after_handler']:.2f} ms; {r['simd_target']} vs {r['reference_target']}: "
            f"max |Δrgb| {r['max_abs_difference_rgb']:.2e} (of max {r['max_rgb']:.2f}), "
            f"max |Δao| {r['max_abs_difference_ao']:.2e}; own vs Blender's normals: max |Δrgb| "
            f"{r['normals_difference_rgb']:.2e}, max |Δao| {r['normals_difference_ao']:.2e}")


def frame_change_accuracy(core, obj, scene):
    """On the current pose: the dispatched SIMD kernel against the one-lane
    scalar reference, and the fused run time (normals by Blender's rule,
    computed in C++) against the separate passes fed Blender's own normals."""
    out = {}
    rgb, ao, _ = frame_shading.shade_object(obj, scene)
    rgb, ao = rgb.copy(), ao.copy()
    core.sh.force_simd_target(core.sh.simd_targets()[-1])
    try:
        out["reference_target"] = core.sh.simd_target()
        rgb_ref, ao_ref, _ = frame_shading.shade_object(obj, scene)
    finally:
        core.sh.force_simd_target("")
    out["max_abs_difference_rgb"] = float(np.abs(rgb - rgb_ref).max())
    out["max_abs_difference_ao"] = float(np.abs(ao - ao_ref).max())
    out["max_rgb"] = float(np.abs(rgb_ref).max())
    entry = frame_shading.loaded_model(obj)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    frame = mesh_data.evaluated_mesh(obj, depsgraph, with_topology=False)   # Blender's normals
    s = obj.penumbra_visibility
    lighting, _, _ = world_lighting.world_lighting_checked(scene, entry.model.order)
    camera = np.array(scene.camera.matrix_world.translation) if scene.camera else np.zeros(3)
    rgb_blender, ao_blender, _ = entry.model.shade(
        armature_data.bone_rotations(armature_data.armature_of(obj), entry.model.joints), frame.positions, frame.normals,
        frame.triangles, entry.neighbours, lighting, model=s.brdf.lower(), phong_exponent=s.phong_exponent,
        camera=camera, transmission=np.array(s.transmission[:]))
    out["normals_difference_rgb"] = float(np.abs(np.maximum(rgb_blender, 0.0) - rgb).max())
    out["normals_difference_ao"] = float(np.abs(np.clip(ao_blender, 0.0, 1.0) - ao).max())
    return out


def kernel_per_target():
    """ns per vertex of the shading kernel on each SIMD target (one thread,
    100k vertices, 2 lobes, order 4, Phong), from bench/cpp/pose_shading_bench.cpp."""
    exe = os.path.join(BUILD, "bench", "penumbra_pose_shading_bench")
    out = subprocess.run([exe, "--quick"], capture_output=True, text=True, check=True).stdout
    per_target = {}
    for line in out.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) > 7 and cells[0].startswith("batched ") and cells[1:7] == ["100000", "2", "4", "phong", "float32", "1"]:
            per_target[cells[0].split()[1]] = float(cells[7])  # the last row per target: the per-target loop
    return per_target


DESCRIPTION = (
    "A frame change (`scene.frame_set`) of the character with the run time enabled (2 lobes, order 4, "
    "Phong), alternated frame by frame in the same run with Blender's own frame change of the same "
    "scene without Penumbra; times are medians, ± half the interquartile range. `gather` is everything "
    "the handler reads from Blender (model lookup, bone rotations, the evaluated mesh's positions and "
    "world matrix, World, camera); `of which the mesh` is the positions. The rest of the handler is one "
    "C++ call on two threads: Blender's vertex normals computed from the posed positions (its own rule, "
    "so Blender is never asked for them, which would make it compute them), then one fused pass over "
    "blocks of vertices (normal, frame, pose → lobes, shading, clamped write; the kernels on the SIMD "
    "target Highway dispatched for this CPU, shading in float); the fused pass's wall time is split "
    "between `normals`, `frames`, `pose → lobes` and `shading` by the thread time each took. `write "
    "attributes` is the two point attributes and `mesh.update()`; `after the handler` is what the frame "
    "change spends beyond the handler and Blender's own frame change: mostly Blender evaluating the "
    "mesh's modifiers again for the attributes just written, which every Blender does (4.x and 5.x tag "
    "the mesh on the attribute writes themselves).")


def table(results, extra_header="", extra=lambda x: ""):
    """Markdown rows of frame_change_costs results; `extra` adds a last column."""
    lines = ["| vertices | SIMD target | gather ms | of which the mesh ms | normals ms | pose → lobes ms | frames ms | "
             "shading ms | write attributes ms | after the handler ms | whole frame change ms | without Penumbra ms "
             "| ratio (goal ≤ 4.5 at 100k) |" + (f" {extra_header} |" if extra_header else ""),
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if extra_header else "")]
    for x in results:
        lines.append(
            f"| {x['vertices']} | {x['simd_target']} | {1e3 * x['gather']:.2f} | {1e3 * x['read_mesh']:.2f} | "
            f"{1e3 * x['normals']:.2f} | {1e3 * x['pose_to_lobes']:.2f} | {1e3 * x['frames']:.2f} | "
            f"{1e3 * x['shading']:.2f} | {1e3 * x['write_attributes']:.2f} | {1e3 * x['after_handler']:.2f} | "
            f"{1e3 * x['frame_change']:.2f} ± {1e3 * x['frame_change_spread']:.2f} | "
            f"{1e3 * x['frame_change_without_penumbra']:.2f} ± {1e3 * x['frame_change_without_penumbra_spread']:.2f} | "
            f"**{x['ratio']:.2f}** |" + (f" {extra(x)} |" if extra_header else ""))
    return lines


def accuracy_line(results):
    """The SIMD kernel and the run time's own normals against their references, as a sentence."""
    return ("Accuracy on the same pose. The dispatched kernel against the same kernel compiled as the one-lane "
            "scalar reference (both in float; they differ by rounding where the SIMD targets fuse multiply-adds): "
            + "; ".join(f"{x['vertices']} vertices, {x['simd_target']} vs {x['reference_target']}: max |Δrgb| "
                        f"{x['max_abs_difference_rgb']:.1e} (largest rgb {x['max_rgb']:.2f}), max |Δao| "
                        f"{x['max_abs_difference_ao']:.1e}" for x in results)
            + ". The run time with its own normals against the separate passes fed Blender's normals (the same "
            "in Blender 4.x/5.x bit for bit; the rest is the frames' float rounding): " + "; ".join(
                f"{x['vertices']} vertices: max |Δrgb| {x['normals_difference_rgb']:.1e}, max |Δao| "
                f"{x['normals_difference_ao']:.1e}" for x in results)
            + ". tests/cpp/sh/pose_shading_test.cpp holds every target to 1e-10 of the straightforward reference "
            "in double and to 3e-5 (relative) of double in float.")
