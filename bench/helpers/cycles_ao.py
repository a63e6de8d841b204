"""Cycles' own AO bake of a mesh, the baseline the visibility benchmarks
(bench/visibility_benchmark.py, bench/visibility_humanoid_benchmark.py)
measure the baker against."""

import time

import bpy
import numpy as np


def cycles_ao(obj, frames, samples):
    """Cycles' AO bake (CPU, `samples`, no denoising) to a point colour
    attribute at each frame: ((V, frames) AO, seconds per frame)."""
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    if hasattr(scene.render.bake, "target"):
        scene.render.bake.target = "VERTEX_COLORS"
    mesh = obj.data
    if "ao" not in mesh.color_attributes:
        mesh.color_attributes.new("ao", "FLOAT_COLOR", "POINT")
    mesh.color_attributes.active_color = mesh.color_attributes["ao"]
    if not mesh.materials:
        material = bpy.data.materials.new("bake")
        material.use_nodes = True
        mesh.materials.append(material)
    values = np.empty(len(mesh.vertices) * 4, dtype=np.float32)
    ao, seconds = [], []
    for frame in frames:
        scene.frame_set(frame)
        started = time.perf_counter()
        bpy.ops.object.bake(type="AO", target="VERTEX_COLORS")
        seconds.append(time.perf_counter() - started)
        mesh.color_attributes["ao"].data.foreach_get("color", values)
        ao.append(values.reshape(-1, 4)[:, 0].astype(np.float64))
    return np.stack(ao, axis=1), seconds
