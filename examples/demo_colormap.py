"""Colour-map filtering demo: a Noise Texture through a sharp ColorRamp on a
plane receding to the horizon; press "Bake Filtered Colour Map" (the operator
penumbra.bake_colormap_lut) and render the plain ramp and Penumbra's node
group at 4 samples per pixel, side by side. run(out_folder) -> dict."""

import math
import os
import time

import bpy
import numpy as np

from penumbra import native


def _scene(out_folder):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.cycles.samples = 4
    scene.render.resolution_x, scene.render.resolution_y = 192, 108
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.penumbra.colormap.output_folder = out_folder
    bpy.ops.mesh.primitive_plane_add(size=400.0, location=(0, 190, 0))
    plane = bpy.context.active_object
    material = bpy.data.materials.new("noise ramp")
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    coords = tree.nodes.new("ShaderNodeTexCoord")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 2.0
    noise.inputs["Detail"].default_value = 4.0
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    e = ramp.color_ramp.elements
    e[0].position, e[0].color = 0.47, (0.8, 0.05, 0.02, 1.0)
    e[1].position, e[1].color = 0.53, (0.02, 0.3, 0.9, 1.0)
    tree.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    tree.nodes.active = ramp
    plane.data.materials.append(material)
    bpy.ops.object.camera_add(location=(0, -2, 1.2), rotation=(math.radians(84), 0, 0))
    scene.camera = bpy.context.active_object
    bpy.context.view_layer.objects.active = plane
    return scene, material, ramp, emission


def _render(scene, out_folder, name):
    scene.render.filepath = os.path.join(out_folder, name + ".exr")
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - started
    core = native.require()
    image = core.read_image(scene.render.filepath)
    srgb = np.where(image <= 0.0031308, 12.92 * image, 1.055 * np.power(np.clip(image, 0, None), 1 / 2.4) - 0.055)
    png = os.path.join(out_folder, name + ".png")
    core.write_png16(png, np.clip(srgb, 0, 1).astype(np.float32), "sRGB")
    return image, png, seconds


def run(out_folder):
    scene, material, ramp, emission = _scene(out_folder)
    plain, plain_png, plain_s = _render(scene, out_folder, "plain_ramp_4spp")
    started = time.perf_counter()
    result = bpy.ops.penumbra.bake_colormap_lut()
    bake_s = time.perf_counter() - started
    filtered, filtered_png, filtered_s = _render(scene, out_folder, "penumbra_4spp")
    group = material.node_tree.nodes["Penumbra Filtered Ramp"]
    return {
        "bake": sorted(result),
        "bake_seconds": round(bake_s, 3),
        "lookup_image": group.node_tree["penumbra_lookup"]["image"],
        "pictures": [plain_png, filtered_png],
        "render_seconds": {"plain": round(plain_s, 3), "penumbra": round(filtered_s, 3)},
        "far_half_pixel_std": {  # the sparkle in the distance: lower is calmer
            "plain": float(plain[: plain.shape[0] // 2].std(axis=(0, 1)).mean()),
            "penumbra": float(filtered[: filtered.shape[0] // 2].std(axis=(0, 1)).mean()),
        },
    }
