"""The humanoid part of gpu_model_check.py (issue 27 item 2): the ~100k-vertex
humanoid (examples/scenes/visibility_humanoid.py), baked cheaply by the
operator (a few frames, few rays: the model's accuracy is not what is
checked, only that the GPU evaluates the same model as the CPU), shaded at
a frame the bake skipped, once per BRDF at order 4 with 2 lobes, under a
uniform World of radiance 1: the vertex shader's readback (RGBA32F) against
frame_shading.shade_object, the CPU run time. Runs inside Blender."""

import os
import time

import bpy
import numpy as np

# gpu_model_check.py puts the repository's root and tests/blender on sys.path.
from bench.helpers.gpu_preview_scene import empty_scene
from visibility_character_scenes import uniform_world

BAKED_FRAMES = (1, 3, 5, 7)  # the operator's range 1..7 step 2
UNSEEN_FRAME = 6             # between two baked poses, never baked
RAYS = 8


def baked_humanoid(detail, tmp):
    """(scene, mesh object, seconds to build, seconds to bake)."""
    import visibility_humanoid
    scene = empty_scene()
    started = time.perf_counter()
    obj, _ = visibility_humanoid.build(detail=detail, frames=BAKED_FRAMES[-1])
    built = time.perf_counter()
    uniform_world(scene)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.5, -4.0, 1.2)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    result = bpy.ops.penumbra.bake_visibility(frame_start=BAKED_FRAMES[0], frame_end=BAKED_FRAMES[-1], frame_step=2,
                                              rays=RAYS, lobes=2, sh_order=4,
                                              filepath=os.path.join(tmp, "humanoid.pzh"))
    assert result == {"FINISHED"}, result
    obj.penumbra_visibility.enabled = True
    scene.penumbra.visibility.live_update = False
    return scene, obj, built - started, time.perf_counter() - built


def humanoid_cases(detail, tmp):
    """{'vertices', 'build_seconds', 'bake_seconds', 'cases': one a BRDF}."""
    from penumbra.visibility import frame_shading, gpu_model, gpu_preview, mesh_data
    scene, obj, build_seconds, bake_seconds = baked_humanoid(detail, tmp)
    settings = obj.penumbra_visibility
    settings.phong_exponent = 12.0
    settings.transmission = (0.6, 0.4, 0.3)
    scene.frame_set(BAKED_FRAMES[-2])
    baked_pose = frame_shading.shade_object(obj, scene)[0].copy()
    scene.frame_set(UNSEEN_FRAME)
    entry = frame_shading.loaded_model(obj)
    on_gpu = gpu_model.ModelOnGpu(entry.model, entry.neighbours, mesh_data.polygon_topology(obj.data),
                                  entry.buffers.triangles)
    cases = []
    for brdf in ("DIFFUSE", "PHONG", "TRANSLUCENT"):
        settings.brdf = brdf
        rgb, ao, _ = frame_shading.shade_object(obj, scene)
        _, frame = gpu_preview.frame_of(obj, scene)
        on_gpu.set_frame(frame)
        gpu_rgb, gpu_ao = on_gpu.shade_offscreen()
        # The CPU run time writes clamped values (frame_shading.shade_object): clamp the same way.
        gpu_rgb, gpu_ao = np.maximum(gpu_rgb, 0.0), np.clip(gpu_ao, 0.0, 1.0)
        cases.append({"brdf": brdf.lower(), "order": entry.model.order, "lobes": entry.model.lobes,
                      "max_abs_rgb": float(np.abs(gpu_rgb - rgb).max()),
                      "max_abs_visibility": float(np.abs(gpu_ao - ao).max()),
                      "rgb_range": [float(rgb.min()), float(rgb.max())],
                      "ao_range": [float(ao.min()), float(ao.max())]})
        if brdf == "DIFFUSE":  # the unseen pose moved the shading away from the baked pose next to it
            cases[-1]["pose_effect"] = float(np.abs(rgb - baked_pose).max())
    return {"vertices": len(obj.data.vertices), "unseen_frame": UNSEEN_FRAME, "baked_frames": list(BAKED_FRAMES),
            "rays": RAYS, "build_seconds": round(build_seconds, 1), "bake_seconds": round(bake_seconds, 1),
            "cases": cases}
