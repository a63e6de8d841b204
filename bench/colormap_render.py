"""Cycles comparison for colormap_benchmark.py (run inside Blender):
a plane with a ColorRamp-mapped Noise Texture receding to the horizon.
Ground truth: the plain ramp at GT_SPP samples. At 1, 4 and 16 spp: the plain
ramp, the ramp applied to the filtered mean C(f̄) and Penumbra's node group.
Writes EXR renders and a JSON of RMSE and times into the folder given after --."""

import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "addon"))
sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
import colormap_scene  # noqa: E402
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402

OUT = sys.argv[sys.argv.index("--") + 1]
GT_SPP = int(os.environ.get("PENUMBRA_GT_SPP", "1024"))
WIDTH, HEIGHT = 256, 144


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    plane, material, ramp, emission, camera = colormap_scene.noise_ramp_plane(roughness=0.5)
    return scene, material, ramp, emission


def set_method(material, ramp, emission, method):
    tree = material.node_tree
    group = tree.nodes["Penumbra Filtered Ramp"]
    noise_filter = tree.nodes["Penumbra Noise Filter"]
    noise = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    ramp.mute = method == "penumbra"
    if method == "penumbra":
        tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    else:
        tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
        source = noise.outputs["Fac"] if method == "plain" else noise_filter.outputs["Mean"]
        tree.links.new(source, ramp.inputs["Fac"])


def render(scene, spp, path, seed=0):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - started


def main():
    os.makedirs(OUT, exist_ok=True)
    penumbra.register()
    scene, material, ramp, emission = build_scene()
    scene.penumbra.colormap.output_folder = OUT
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    core = native.require()
    results = {"blender": bpy.app.version_string, "size": [WIDTH, HEIGHT], "gt_spp": GT_SPP, "runs": []}
    set_method(material, ramp, emission, "plain")
    gt_path = os.path.join(OUT, "ground_truth.exr")
    results["gt_seconds"] = render(scene, GT_SPP, gt_path, seed=99)
    truth = core.image.read(gt_path)
    for method in ("plain", "mean", "penumbra"):
        set_method(material, ramp, emission, method)
        for spp in (1, 4, 16):
            path = os.path.join(OUT, f"{method}_{spp}spp.exr")
            seconds = render(scene, spp, path, seed=1)
            image = core.image.read(path)
            rmse = float(((image - truth) ** 2).mean() ** 0.5)
            results["runs"].append({"method": method, "spp": spp, "rmse": rmse, "seconds": seconds})
            print(f"{method:9s} {spp:3d} spp  RMSE {rmse:.5f}  {seconds:.2f} s", flush=True)
    with open(os.path.join(OUT, "render_results.json"), "w") as f:
        json.dump(results, f, indent=1)
    penumbra.unregister()


main()
