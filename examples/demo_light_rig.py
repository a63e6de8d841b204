"""Light rig demo (run inside Blender by examples/demo_blender.py):
a bundled HDRI on the World, rotated by a Mapping node, decomposed into 64
suns; then a 24-frame rotating sequence made from it, decomposed into a
keyframed, temporally filtered rig. Writes the preview picture (lights on
the map, as the paper's Figure 1), the rig JSON and a small Cycles render of
a sphere on a plane lit by the World and by the rig."""

import math
import os
import sys
import time

import bpy
import numpy as np

from penumbra import color, native

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import light_rig_scene  # noqa: E402  (examples/light_rig_scene.py)


def _render(scene, path):
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 32
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = 160, 120
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return path


def run(out_folder):
    core = native.require()
    started = time.perf_counter()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    worlds = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world")
    hdri = os.path.join(worlds, "sunrise.exr")

    # World: the HDRI through a Mapping node turned 30° about Z.
    world = bpy.data.worlds.new("Demo World")
    scene.world = world
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        world.use_nodes = True
    nt = world.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(hdri)
    mapping = nt.nodes.new("ShaderNodeMapping")
    coords = nt.nodes.new("ShaderNodeTexCoord")
    mapping.inputs["Rotation"].default_value = (0, 0, math.radians(30))
    nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])

    # A sphere on a plane, seen by a camera.
    light_rig_scene.sphere_on_plane(scene)
    _render(scene, os.path.join(out_folder, "render_world.png"))

    # Static rig from the World (filepath empty), 64 lights.
    json_static = os.path.join(out_folder, "rig_static.json")
    bpy.ops.penumbra.build_light_rig(filepath="", count=64, json_path=json_static)
    preview = bpy.data.images["Penumbra Light Rig Preview"]
    w, h = preview.size
    px = np.empty(w * h * 4, np.float32)
    preview.pixels.foreach_get(px)
    rgb = px.reshape(h, w, 4)[::-1, :, :3].copy()
    config = color.blender_config()
    core.image.write_png16(os.path.join(out_folder, "preview_lights_on_map.png"),
                           config.convert(rgb, config.scene_linear, "sRGB"), colorspace="sRGB")
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    _render(scene, os.path.join(out_folder, "render_rig.png"))
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0

    # A rotating 24-frame sequence → keyframed, filtered rig.
    seq = os.path.join(out_folder, "sequence")
    os.makedirs(seq, exist_ok=True)
    image = core.image.read(hdri)
    for i in range(24):
        core.image.write_exr(os.path.join(seq, f"sunrise_{i + 1:04d}.exr"),
                             core.lights.rotate_map_z(image, math.radians(3 * i)), half=True, colorspace="Linear")
    json_anim = os.path.join(out_folder, "rig_animated.json")
    bpy.ops.penumbra.build_light_rig(filepath=os.path.join(seq, "sunrise_0001.exr"), count=32,
                                     frame_start=1, frame_end=24, json_path=json_anim)
    rig = scene.penumbra.light_rig
    suns = [o for o in rig.collection.objects if o.type == "LIGHT"]
    return {
        "hdri": hdri,
        "suns": len(suns),
        "report": rig.last_report,
        "json": [json_static, json_anim],
        "pictures": ["render_world.png", "render_rig.png", "preview_lights_on_map.png"],
        "seconds": round(time.perf_counter() - started, 2),
    }
