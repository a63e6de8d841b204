"""Visibility baker demo (run by examples/demo_blender.py inside Blender):
build the procedural rigged character, bake its pose-space visibility model,
shade poses it never saw under one of Blender's bundled HDR worlds, and
render them with Cycles through the material set up by the add-on."""

import json
import math
import os
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _world(scene, name="forest.exr"):
    path = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", name)
    world = bpy.data.worlds.new("Demo World")
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        world.use_nodes = True
    tree = world.node_tree
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path)
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    scene.world = world
    return path


def run(out_folder):
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import visibility_character
    from penumbra.visibility import runtime

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    obj, rig = visibility_character.build(detail=1.5, frames=24)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    hdri = _world(scene)

    started = time.perf_counter()
    model_path = os.path.join(out_folder, "character.pzh")
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=24, frame_step=2, rays=128, lobes=2,
                                              filepath=model_path)
    if result != {"FINISHED"}:
        raise RuntimeError("visibility bake failed")
    seconds_bake = time.perf_counter() - started
    summary = json.loads(obj.penumbra_visibility.report)

    bpy.ops.penumbra.setup_material()
    obj.penumbra_visibility.enabled = True
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, -6.5, 1.5)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = 240, 240
    # The shading is already lit radiance: show it without a tone curve, a
    # little darker so the bright HDRI does not clip the self-shadowing.
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = -1.0
    renders = {}
    timings = {}
    for frame, brdf in ((6, "DIFFUSE"), (12, "DIFFUSE"), (12, "PHONG"), (18, "TRANSLUCENT")):
        obj.penumbra_visibility.brdf = brdf
        scene.frame_set(frame)  # even frames were never baked: the handler shades them from the model
        timings[f"{frame}_{brdf.lower()}"] = dict(runtime.last_timings)
        path = os.path.join(out_folder, f"visibility_frame{frame:02d}_{brdf.lower()}.png")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        renders[f"{frame}_{brdf.lower()}"] = path
    ao = np.empty(len(obj.data.vertices), dtype=np.float32)
    obj.data.attributes["penumbra_visibility"].data.foreach_get("value", ao)
    return {
        "vertices": len(obj.data.vertices),
        "hdri": hdri,
        "model": model_path,
        "model_bytes": summary["model_bytes"],
        "dense_bytes": summary["dense_bytes"],
        "active_joints": summary["active_joints"],
        "holdout_ao_mean_abs": summary["model_holdout"]["ao_mean_abs"],
        "zh_fit_sh_rms": summary["zh_fit"]["sh_rms"],
        "seconds_bake_and_fit": round(seconds_bake, 3),
        "mean_visibility_last_frame": float(ao.mean()),
        "runtime_seconds": timings,
        "renders": renders,
    }
