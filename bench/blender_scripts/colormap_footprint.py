"""Footprint check for colormap_benchmark.py (run inside Blender): the
"Penumbra Pixel Footprint" node group against the true pixel footprint on a
plane, computed here independently from the camera (the pixel's four
corners projected onto the plane z = 0).

For each camera pitch the group's outputs (Footprint, Minor, Major) are
rendered as an emission colour (1 spp, a 0.01 px box filter, so each pixel
is shaded at its centre) and compared at a column of pixels with
- true √area: the square root of the area of the quadrilateral that the
  pixel's corners project to,
- true major/minor: the singular values of the parallelogram spanned by the
  projections of the pixel's edge midpoints (P(x+½) − P(x−½), P(y+½) − P(y−½)),
  the finite-difference Jacobian over one pixel.
Writes footprint_results.json into the folder given after --."""

import json
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import colormap_scene  # noqa: E402
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402

WIDTH, HEIGHT = 64, 36
PITCHES = (30.0, 60.0, 75.0, 84.0, 88.0)   # camera rotation about x: 0 looks straight down, 90 at the horizon


def pixel_point(scene, camera, x, y):
    """World-space ray (origin, direction) through raster position (x, y),
    x from the left, y from the top, in pixels."""
    frame = [camera.matrix_world @ v for v in camera.data.view_frame(scene=scene)]
    top_right, bottom_right, bottom_left, top_left = frame
    u, v = x / WIDTH, y / HEIGHT
    point = top_left + (top_right - top_left) * u + (bottom_left - top_left) * v
    if camera.data.type == "ORTHO":
        forward = (camera.matrix_world.to_3x3() @ Vector((0, 0, -1))).normalized()
        return point, forward
    origin = camera.matrix_world.translation
    return origin, (point - origin).normalized()


def on_plane(origin, direction):
    if direction.z >= -1e-12:
        return None
    t = -origin.z / direction.z
    return origin + direction * t


def true_footprint(scene, camera, x, y):
    corners = [on_plane(*pixel_point(scene, camera, x + dx, y + dy)) for dx, dy in
               ((0, 0), (1, 0), (1, 1), (0, 1))]
    mids = [on_plane(*pixel_point(scene, camera, x + dx, y + dy)) for dx, dy in
            ((0, 0.5), (1, 0.5), (0.5, 0), (0.5, 1))]
    if any(p is None for p in corners + mids):
        return None
    xs = [p.x for p in corners]
    ys = [p.y for p in corners]
    area = 0.5 * abs(sum(xs[i] * ys[(i + 1) % 4] - xs[(i + 1) % 4] * ys[i] for i in range(4)))
    ju = np.array((mids[1] - mids[0])[:2])
    jv = np.array((mids[3] - mids[2])[:2])
    singular = np.linalg.svd(np.column_stack([ju, jv]), compute_uv=False)
    centre_origin, centre_dir = pixel_point(scene, camera, x + 0.5, y + 0.5)
    view_angle = math.degrees(math.acos(min(1.0, abs(centre_dir.z))))
    return {"sqrt_area": math.sqrt(area), "major": float(singular[0]), "minor": float(singular[1]),
            "view_angle": view_angle}


def build(pitch, orthographic=False):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.samples = 1
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    bpy.ops.mesh.primitive_plane_add(size=2000.0, location=(0, 0, 0))
    plane = bpy.context.active_object
    # Any noise-driven ramp: the bake adds the footprint group, which depends on the camera alone.
    material, _, emission = colormap_scene.noise_ramp_material(name="footprint")
    plane.data.materials.append(material)
    bpy.ops.object.camera_add(location=(0.3, -2, 1.2), rotation=(math.radians(pitch), 0, math.radians(8)))
    camera = bpy.context.active_object
    if orthographic:
        camera.data.type = "ORTHO"
        camera.data.ortho_scale = 3.0
    scene.camera = camera
    bpy.context.view_layer.objects.active = plane
    return scene, material, emission, camera


def measure(folder, pitch, orthographic=False):
    scene, material, emission, camera = build(pitch, orthographic)
    scene.penumbra.colormap.output_folder = folder
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    footprint = tree.nodes["Penumbra Pixel Footprint"]
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    for i, name in enumerate(("Footprint", "Minor", "Major")):
        tree.links.new(footprint.outputs[name], combine.inputs[i])
    tree.links.new(combine.outputs[0], emission.inputs["Color"])
    path = os.path.join(folder, f"footprint_{pitch:g}{'_ortho' if orthographic else ''}.exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = native.require().image.read(path)
    rows = []
    x = WIDTH // 2
    for y in range(0, HEIGHT, 3):
        truth = true_footprint(scene, camera, x, y)
        if truth is None:
            continue
        node = image[y, x, :3]
        rows.append(dict(truth, row=y, node_footprint=float(node[0]), node_minor=float(node[1]),
                         node_major=float(node[2])))
    return rows


def main():
    folder = sys.argv[sys.argv.index("--") + 1]
    os.makedirs(folder, exist_ok=True)
    penumbra.register()
    results = {"size": [WIDTH, HEIGHT], "blender": bpy.app.version_string, "cameras": []}
    for pitch in PITCHES:
        results["cameras"].append({"pitch": pitch, "orthographic": False, "rows": measure(folder, pitch)})
    results["cameras"].append({"pitch": 75.0, "orthographic": True, "rows": measure(folder, 75.0, True)})
    with open(os.path.join(folder, "footprint_results.json"), "w") as f:
        json.dump(results, f, indent=1)
    penumbra.unregister()


if __name__ == "__main__":
    main()
