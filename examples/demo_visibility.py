"""Visibility demo (run inside Blender by examples/demo_blender.py): build the
procedural rigged character, bake its pose-space visibility model from the
odd frames, and shade even frames it never saw. On each of those poses,
Cycles' own ambient-occlusion bake is the reference for Penumbra's
`penumbra_visibility`; the contact sheet shows both, their absolute
difference and Penumbra's shading under one of Blender's bundled HDR worlds,
then the GPU preview's shading of an unseen pose read back beside the CPU's
(examples/demo_visibility_gpu.py). run(out_folder, demo) -> dict."""

import json
import os
import sys
import time

import bpy
import numpy as np
from mathutils import Vector

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import contact_sheet as cs  # noqa: E402  (examples/contact_sheet.py)
import demo_render  # noqa: E402  (examples/demo_render.py)
import demo_visibility_gpu  # noqa: E402  (examples/demo_visibility_gpu.py)

HELD_OUT = (6, 12, 18)  # even frames: the model was baked from the odd ones
COMPARE = "demo_ao_compare"  # point colour: (Cycles AO, Penumbra AO, |difference|)
DIFFERENCE_SCALE = 0.05  # |Δ AO| at the bright end of the heat ramp
AO_BLACK = 0.5  # AO shown black; 1 is white (the character occludes little of its own sky)
BRDFS = {6: "DIFFUSE", 12: "PHONG", 18: "TRANSLUCENT"}
GPU_POSE = 12  # the unseen pose the GPU preview's readback shows (both modes shade it)


def _settings(quick):
    if quick:
        return {"detail": 1.0, "rays": 64, "ao_samples": 32, "size": (180, 180), "spp": 4, "enlarge": 2,
                "poses": HELD_OUT[1:2]}
    return {"detail": 1.5, "rays": 128, "ao_samples": 256, "size": (360, 360), "spp": 16, "enlarge": 1,
            "poses": HELD_OUT}


def _world(scene, name="forest.exr"):
    path = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", name)
    world = bpy.data.worlds.new("Demo World")
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        world.use_nodes = True
    tree = world.node_tree
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path)
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    if hasattr(world, "cycles"):
        # The renders show emission only (the shading is already lit), so
        # Cycles need not build the World's importance map for each one.
        world.cycles.sampling_method = "NONE"
    scene.world = world
    return path


def _camera(scene, target=(0.0, 0.0, 1.4), direction=(0.45, -1.0, 0.35), distance=4.8, lens=60.0):
    """A camera in front of the character, a little to its left and above."""
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.data.lens = lens
    position = Vector(target) + distance * Vector(direction).normalized()
    camera.location = position
    camera.rotation_euler = (Vector(target) - Vector(position)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera


def _emission_material(name, attribute_name):
    """A material that shows a point attribute as emission of strength 1."""
    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True
    tree = material.node_tree
    for node in list(tree.nodes):
        if node.bl_idname != "ShaderNodeOutputMaterial":
            tree.nodes.remove(node)
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = "GEOMETRY"
    attribute.attribute_name = attribute_name
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(attribute.outputs["Color"], emission.inputs["Color"])
    tree.links.new(emission.outputs["Emission"], tree.nodes["Material Output"].inputs["Surface"])
    return material


def _cycles_ao(obj, scene, samples):
    """Cycles' ambient-occlusion bake of the current pose, per vertex."""
    mesh = obj.data
    if "cycles_ao" not in mesh.color_attributes:
        mesh.color_attributes.new("cycles_ao", "FLOAT_COLOR", "POINT")
    mesh.color_attributes.active_color = mesh.color_attributes["cycles_ao"]
    scene.cycles.samples = samples
    bpy.ops.object.bake(type="AO", target="VERTEX_COLORS")
    values = np.empty(len(mesh.vertices) * 4, dtype=np.float32)
    mesh.color_attributes["cycles_ao"].data.foreach_get("color", values)
    return values.reshape(-1, 4)[:, 0].copy()


def _point_values(mesh, name):
    values = np.empty(len(mesh.vertices), dtype=np.float32)
    mesh.attributes[name].data.foreach_get("value", values)
    return values


def _bake(obj, out_folder, settings):
    started = time.perf_counter()
    model_path = os.path.join(out_folder, "character.pzh")
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=23, frame_step=2, rays=settings["rays"],
                                              lobes=2, filepath=model_path)
    if result != {"FINISHED"}:
        raise RuntimeError("visibility bake failed")
    seconds = time.perf_counter() - started
    return model_path, json.loads(obj.penumbra_visibility.report), seconds


def _compare_pose(obj, scene, frame, settings, out_folder, materials, heads):
    """Shades `frame` with the model, bakes Cycles' AO of it and renders both,
    their difference and the lit shading. Returns (row of tiles, caption,
    errors); `heads`: label the columns (the first row)."""
    mesh = obj.data
    obj.penumbra_visibility.brdf = BRDFS[frame]
    scene.frame_set(frame)  # the handler shades the pose from the model
    penumbra_ao = _point_values(mesh, "penumbra_visibility")
    started = time.perf_counter()
    cycles_ao = _cycles_ao(obj, scene, settings["ao_samples"])
    ao_seconds = time.perf_counter() - started
    difference = np.abs(penumbra_ao - cycles_ao)
    packed = np.stack([cycles_ao, penumbra_ao, difference, np.ones_like(difference)], axis=1)
    mesh.attributes[COMPARE].data.foreach_set("color", packed.reshape(-1))
    mesh.update()

    # One render carries all three: R = Cycles AO, G = Penumbra, B = |Δ|.
    obj.data.materials[0] = materials["compare"]
    ao = demo_render.render(scene, os.path.join(out_folder, f"frame{frame:02d}_ao_cycles_penumbra_difference.exr"),
                            settings["spp"])
    obj.data.materials[0] = materials["shading"]
    lit = demo_render.render(scene, os.path.join(out_folder, f"frame{frame:02d}_shading_{BRDFS[frame].lower()}.exr"),
                             settings["spp"])
    alpha = ao[..., 3]
    ao = demo_render.unpremultiply(ao)
    # The shading is lit radiance: shown a stop darker so the bright HDRI does
    # not clip the self-shadowing.
    lit_display = demo_render.display(demo_render.unpremultiply(lit), exposure=-1.0)

    def tile(rgb):
        return cs.enlarge(cs.over(rgb, alpha, cs.BACKGROUND), settings["enlarge"])

    errors = {"frame": frame, "mean_abs": float(difference.mean()), "max_abs": float(difference.max()),
              "cycles_ao_seconds": round(ao_seconds, 3)}
    # AO on a linear grey ramp from AO_BLACK to 1, no display curve.
    grey = [cs.grey(np.clip((ao[..., k] - AO_BLACK) / (1.0 - AO_BLACK), 0.0, 1.0)) for k in (0, 1)]
    pictures = [grey[0], grey[1], cs.heat(ao[..., 2], DIFFERENCE_SCALE), lit_display]
    row = [cs.Tile(tile(p), h if heads else ()) for p, h in zip(pictures, (
        ["reference: Cycles AO", f"{settings['ao_samples']} samples, grey {AO_BLACK:g} - 1"],
        ["result: Penumbra AO", f"prediction, grey {AO_BLACK:g} - 1"],
        ["|Penumbra - Cycles|", f"heat scale 0 - {DIFFERENCE_SCALE:g}"],
        ["Penumbra shading", "under forest.exr"]))]
    caption = (f"frame {frame} (never baked): mean |ΔAO| {errors['mean_abs']:.4f}, max {errors['max_abs']:.3f}; "
               f"shading {BRDFS[frame].lower()}")
    return row, caption, errors


def _gpu_row(obj, scene, settings, out_folder):
    """The GPU preview's readback of GPU_POSE beside the CPU shading (or why it did not run)."""
    def render_attribute(name):
        obj.data.materials[0] = bpy.data.materials.get(f"show {name}") or _emission_material(f"show {name}", name)
        return demo_render.render(scene, os.path.join(out_folder, f"frame{GPU_POSE:02d}_{name}.exr"), settings["spp"])

    def tile(rgb, alpha):
        return cs.enlarge(cs.over(rgb, alpha, cs.BACKGROUND), settings["enlarge"])

    shading = obj.data.materials[0]
    try:
        return demo_visibility_gpu.row(obj, scene, GPU_POSE, BRDFS[GPU_POSE], render_attribute, tile)
    finally:
        obj.data.materials[0] = shading


def run(out_folder, demo):
    sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
    import visibility_character

    settings = _settings(demo.quick)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    obj, rig = visibility_character.build(detail=settings["detail"], frames=24)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    hdri = _world(scene)
    _camera(scene)
    demo_render.use_cycles(scene, *settings["size"], transparent=True)

    model_path, report, bake_seconds = _bake(obj, out_folder, settings)
    vertices = len(obj.data.vertices)
    demo.step("visibility model", f"{os.path.basename(model_path)}: {report['frames']} poses, {vertices} vertices, "
              f"{report['model_bytes'] / 1e6:.2f} MB", f"held-out AO {report['model_holdout']['ao_mean_abs']:.4f}",
              bake_seconds)

    bpy.ops.penumbra.setup_material()
    obj.penumbra_visibility.enabled = True
    obj.data.color_attributes.new(COMPARE, "FLOAT_COLOR", "POINT")
    materials = {"shading": obj.data.materials[0], "compare": _emission_material("AO compare", COMPARE)}

    started = time.perf_counter()
    sheet = cs.Sheet("Visibility: poses the model never saw",
                     f"{vertices}-vertex character, model baked from {report['frames']} poses at "
                     f"{settings['rays']} rays; reference: Cycles' AO bake per vertex")
    poses = []
    for frame in settings["poses"]:
        row, caption, errors = _compare_pose(obj, scene, frame, settings, out_folder, materials, heads=not poses)
        sheet.row(row, caption)
        poses.append(errors)
    mean_abs = float(np.mean([p["mean_abs"] for p in poses]))
    sheet.row([cs.Tile(cs.heat_legend(DIFFERENCE_SCALE), ["difference scale"])])
    gpu_tiles, gpu_caption, gpu_result = _gpu_row(obj, scene, settings, out_folder)
    sheet.row(gpu_tiles, gpu_caption)
    sheet_path = demo.sheet_path("visibility")
    size = sheet.write(sheet_path)
    poses_made = f"{len(poses)} unseen pose" + ("s" if len(poses) > 1 else "")
    demo.step("visibility sheet", f"{os.path.basename(sheet_path)}: {poses_made}, {size[0]}×{size[1]}",
              f"mean |ΔAO| {mean_abs:.4f} vs Cycles AO; {demo_visibility_gpu.summary_line(gpu_result)}",
              time.perf_counter() - started)
    return {
        "vertices": vertices,
        "hdri": hdri,
        "model": model_path,
        "model_bytes": report["model_bytes"],
        "active_joints": report["active_joints"],
        "holdout_ao_mean_abs": report["model_holdout"]["ao_mean_abs"],
        "seconds_bake_and_fit": round(bake_seconds, 3),
        "unseen_poses_vs_cycles_ao": poses,
        "gpu_preview_vs_cpu": gpu_result,
        "sheet": sheet_path,
    }
