"""Light rig demo (run inside Blender by examples/demo_blender.py): a bundled
HDRI on the World, rotated by a Mapping node, decomposed into 64 suns; a
sphere on a plane rendered with Cycles lit by the World (the reference) and
by the rig alone (the result). Where this Blender can draw EEVEE (the bpy
5.x module, after gpu.init()), the same scene also in EEVEE: lit by the
World and by a rig of EEVEE_LIGHTS suns built for EEVEE (target_renderer),
both against Cycles' World render, and the rig also against Cycles' direct
light (no bounce: what EEVEE's lamps draw at factory settings). Then a
12-frame rotating sequence made from the HDRI, decomposed into a keyframed,
temporally filtered rig. The contact sheet shows the renders, their
difference and the lights on the map.
run(out_folder, demo) -> dict."""

import math
import os
import sys
import time

import bpy
import numpy as np

from penumbra import native

sys.path[:0] = [os.path.dirname(os.path.abspath(__file__)), os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenes")]
import contact_sheet as cs  # noqa: E402  (examples/contact_sheet.py)
import demo_render  # noqa: E402  (examples/demo_render.py)
import light_rig_scene  # noqa: E402  (examples/scenes/light_rig_scene.py)

HDRI = "sunrise.exr"
MAPPING_DEGREES = 30.0  # the World's Mapping node turns the map about Z
LIGHTS = 64
# EEVEE Next's factory shadow pool (512 MB) holds the shadows of about 32
# suns here; 64 overflow it and EEVEE drops shadows, as the operator warns
# (docs/lights.md, "EEVEE Next's shadow pool").
EEVEE_LIGHTS = 32
DIFFERENCE_SCALE = 0.2  # |Δ| relative to the World render's mean, at the bright end of the heat ramp
BOX = 9  # renders are compared as BOX × BOX pixel averages, which keeps most of Cycles' noise out
EXPOSURE = -1.0  # stops, for display: the sunrise is bright


def _settings(quick):
    # EEVEE on Mesa's software OpenGL costs about a Cycles render per sample
    # at this size: the quick mode keeps 4 samples (the are 16).
    if quick:
        return {"size": (192, 144), "spp": 8, "eevee_samples": 4, "enlarge": 2, "frames": 6,
                "sequence_lights": 16}
    return {"size": (384, 288), "spp": 32, "eevee_samples": 16, "enlarge": 1, "frames": 12,
            "sequence_lights": 32}


def _world(scene, hdri):
    """The HDRI through a Mapping node turned MAPPING_DEGREES about Z."""
    world = bpy.data.worlds.new("Demo World")
    scene.world = world
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        world.use_nodes = True
    nt = world.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(hdri)
    mapping = nt.nodes.new("ShaderNodeMapping")
    coords = nt.nodes.new("ShaderNodeTexCoord")
    mapping.inputs["Rotation"].default_value = (0, 0, math.radians(MAPPING_DEGREES))
    nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])
    return world


def _set_world_light(world, on):
    """World on: it lights the scene (importance-sampled). Off: strength 0,
    so only the rig's suns light it."""
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0 if on else 0.0
    if hasattr(world, "cycles"):
        world.cycles.sampling_method = "AUTOMATIC" if on else "NONE"


def _preview_picture():
    """The operator's preview (lights on the map), as display RGB."""
    preview = bpy.data.images["Penumbra Light Rig Preview"]
    w, h = preview.size
    px = np.empty(w * h * 4, np.float32)
    preview.pixels.foreach_get(px)
    return demo_render.display(px.reshape(h, w, 4)[::-1, :, :3])


def _static_rig(scene, world, out_folder, settings, demo):
    """64 suns from the World; renders with the World and with the rig."""
    started = time.perf_counter()
    json_static = os.path.join(out_folder, "rig_static.json")
    bpy.ops.penumbra.build_light_rig(filepath="", count=LIGHTS, target_renderer="CYCLES", json_path=json_static)
    build_seconds = time.perf_counter() - started
    rig = scene.penumbra.light_rig
    suns = [o for o in rig.collection.objects if o.type == "LIGHT"]
    demo.step("light rig", f"{os.path.basename(json_static)}: {len(suns)} suns from the World", "", build_seconds)

    started = time.perf_counter()
    _set_world_light(world, True)
    rig.collection.hide_render = True
    world_render = demo_render.render(scene, os.path.join(out_folder, "render_world.exr"), settings["spp"])
    rig.collection.hide_render = False
    _set_world_light(world, False)
    rig_render = demo_render.render(scene, os.path.join(out_folder, "render_rig.exr"), settings["spp"])
    _set_world_light(world, True)
    render_seconds = time.perf_counter() - started

    alpha = world_render[..., 3]
    difference, rmse, mean_ratio = _compare(world_render, rig_render)
    return {"json": json_static, "suns": len(suns), "build_seconds": round(build_seconds, 3),
            "render_seconds": round(render_seconds, 3), "render_relative_rmse": rmse,
            "render_mean_ratio": mean_ratio,
            "pictures": {"world": world_render, "rig": rig_render, "alpha": alpha,
                         "difference": difference,
                         "map": _preview_picture()}}


def _compare(reference_render, render):
    """(|render - reference| / mean per pixel, relative RMSE, mean ratio)
    where the camera sees only the sphere and the plane (the reference's
    alpha), in BOX × BOX averages, relative to the reference's mean there."""
    reference, result = _box_average(reference_render[..., :3]), _box_average(render[..., :3])
    inside = _box_average(reference_render[..., 3:4])[..., 0] > 0.999
    scale = float(reference[inside].mean())
    difference = np.where(inside, np.abs(result - reference).mean(axis=-1) / scale, 0.0)
    rmse = float(np.sqrt(((result - reference)[inside] ** 2).mean()) / scale)
    return difference, rmse, float(result[inside].mean() / scale)


def _eevee_available():
    """Whether EEVEE can render here: the bpy 5.x module makes its GPU
    context with gpu.init() (Mesa's software OpenGL without a display);
    `blender -b` and the bpy 4.5 module have none."""
    if bpy.app.version < (5, 0, 0) or bpy.app.binary_path:
        return False
    import gpu
    gpu.init()
    return True


def _eevee(scene, world, out_folder, settings, static):
    """The World and a rig of EEVEE_LIGHTS suns built for EEVEE, drawn by EEVEE
    (factory settings, a transparent film), against Cycles' World render;
    the rig also against Cycles' direct light. Leaves the scene on Cycles."""
    started = time.perf_counter()
    rig = scene.penumbra.light_rig
    rig.collection.hide_render = True
    _set_world_light(world, True)
    bpy.ops.penumbra.build_light_rig(filepath="", count=EEVEE_LIGHTS, target_renderer="EEVEE",
                                     json_path=os.path.join(out_folder, "eevee_rig.json"))
    scene.render.engine = "BLENDER_EEVEE"  # EEVEE Next's id from 5.0 on
    scene.eevee.taa_render_samples = settings["eevee_samples"]
    rig.collection.hide_render = True
    renders = {"world": demo_render.render(scene, os.path.join(out_folder, "render_eevee_world.exr"), 1)}
    rig.collection.hide_render = False
    _set_world_light(world, False)
    renders["rig"] = demo_render.render(scene, os.path.join(out_folder, "render_eevee_rig.exr"), 1)
    _set_world_light(world, True)
    scene.render.engine = "CYCLES"
    direct = _direct_light_render(scene, rig, out_folder, settings)
    result = {"samples": settings["eevee_samples"], "suns": EEVEE_LIGHTS,
              "cycles_direct_mean_ratio": _compare(static["pictures"]["world"], direct)[2]}
    for name, picture in renders.items():
        difference, rmse, mean_ratio = _compare(static["pictures"]["world"], picture)
        result[name] = {"render_relative_rmse": rmse, "render_mean_ratio": mean_ratio}
        static["pictures"][f"eevee_{name}"] = picture
        static["pictures"][f"eevee_{name}_difference"] = difference
    _, rmse, mean_ratio = _compare(direct, renders["rig"])
    result["rig_vs_direct"] = {"render_relative_rmse": rmse, "render_mean_ratio": mean_ratio}
    result["seconds"] = round(time.perf_counter() - started, 3)
    return result


def _direct_light_render(scene, rig, out_folder, settings):
    """Cycles' World render with no bounce: the light EEVEE at factory
    settings draws from lamps, which give no bounce light without baked
    probes or Ray Tracing (docs/lights.md, "What stands between the rig and
    goal 1"). Leaves the bounces and the rig as they were."""
    bounces, hidden = scene.cycles.max_bounces, rig.collection.hide_render
    scene.cycles.max_bounces = 0
    rig.collection.hide_render = True
    try:
        return demo_render.render(scene, os.path.join(out_folder, "render_direct.exr"), settings["spp"])
    finally:
        scene.cycles.max_bounces, rig.collection.hide_render = bounces, hidden


def _box_average(image):
    """Each pixel of (H, W, C) replaced by the mean of the BOX × BOX pixels
    around it (edges repeated)."""
    r = BOX // 2
    for axis in (0, 1):
        padded = np.concatenate([np.repeat(np.take(image, [0], axis), r + 1, axis), image,
                                 np.repeat(np.take(image, [-1], axis), r, axis)], axis=axis)
        sums = np.cumsum(padded, axis=axis, dtype=np.float64)
        n = image.shape[axis]
        image = ((np.take(sums, np.arange(BOX, BOX + n), axis) - np.take(sums, np.arange(n), axis)) / BOX)
    return image.astype(np.float32)


def _animated_rig(scene, hdri, out_folder, settings, demo):
    """A rotating sequence → keyframed, temporally filtered rig."""
    core = native.require()
    started = time.perf_counter()
    seq = os.path.join(out_folder, "sequence")
    os.makedirs(seq, exist_ok=True)
    image = core.image.read(hdri)
    frames = settings["frames"]
    for i in range(frames):
        core.image.write_exr(os.path.join(seq, f"sunrise_{i + 1:04d}.exr"),
                             core.lights.rotate_map_z(image, math.radians(6 * i)), half=True, colorspace="Linear")
    json_anim = os.path.join(out_folder, "rig_animated.json")
    lights = settings["sequence_lights"]
    bpy.ops.penumbra.build_light_rig(filepath=os.path.join(seq, "sunrise_0001.exr"), count=lights,
                                     frame_start=1, frame_end=frames, target_renderer="CYCLES", json_path=json_anim)
    seconds = time.perf_counter() - started
    demo.step("animated rig", f"{os.path.basename(json_anim)}: {lights} suns × {frames} frames", "", seconds)
    return {"json": json_anim, "frames": frames, "suns": lights, "report": scene.penumbra.light_rig.last_report,
            "seconds": round(seconds, 3)}


def _sheet(static, settings, demo):
    p = static["pictures"]
    k = settings["enlarge"]

    def tile(rgb):
        return cs.enlarge(cs.over(rgb, p["alpha"], cs.BACKGROUND), k)

    sheet = cs.Sheet("Light rig: the World against 64 suns",
                     f"{HDRI} on the World through a Mapping node ({MAPPING_DEGREES:g}° about Z); "
                     f"Cycles, {settings['spp']} samples per pixel")
    sheet.row([
        cs.Tile(tile(demo_render.display(demo_render.unpremultiply(p["world"]), EXPOSURE)),
                ["reference: lit by the World", "the HDRI itself"]),
        cs.Tile(tile(demo_render.display(demo_render.unpremultiply(p["rig"]), EXPOSURE)),
                ["result: lit by the rig", f"{static['suns']} suns, World off"]),
        cs.Tile(tile(cs.heat(p["difference"], DIFFERENCE_SCALE)),
                ["|rig - World| / mean", f"{BOX}×{BOX} px averages, 0 - {DIFFERENCE_SCALE:g}"]),
    ], f"RMSE {100 * static['render_relative_rmse']:.1f} % of the mean ({BOX}×{BOX} px averages; Cycles "
       f"noise included); mean brightness rig / World {static['render_mean_ratio']:.3f}")
    eevee = static.get("eevee")
    if eevee:
        w, r = eevee["world"], eevee["rig"]
        sheet.row([
            cs.Tile(tile(demo_render.display(demo_render.unpremultiply(p["eevee_world"]), EXPOSURE)),
                    ["EEVEE, lit by the World", f"{eevee['samples']} samples"]),
            cs.Tile(tile(demo_render.display(demo_render.unpremultiply(p["eevee_rig"]), EXPOSURE)),
                    ["EEVEE, lit by the rig", f"{eevee['suns']} suns built for EEVEE",
                     f"mean {eevee['rig_vs_direct']['render_mean_ratio']:.3f} of Cycles, no bounce"]),
            cs.Tile(tile(cs.heat(p["eevee_rig_difference"], DIFFERENCE_SCALE)),
                    ["|EEVEE rig - Cycles World| / mean", f"0 - {DIFFERENCE_SCALE:g}",
                     f"Cycles, no bounce: mean {eevee['cycles_direct_mean_ratio']:.3f}"]),
        ], f"EEVEE / Cycles' World render: World RMSE {100 * w['render_relative_rmse']:.1f} %, mean "
           f"{w['render_mean_ratio']:.3f}; rig RMSE {100 * r['render_relative_rmse']:.1f} %, mean "
           f"{r['render_mean_ratio']:.3f}")
    map_width = 3 * settings["size"][0] * k + 2 * cs.GAP
    picture = p["map"]
    factor = max(1, map_width // picture.shape[1])
    sheet.row([cs.Tile(cs.enlarge(picture, factor),
                       ["the lights on the map", "the operator's preview: a ring per sun"])])
    path = demo.sheet_path("lights")
    size = sheet.write(path)
    return path, size


def run(out_folder, demo):
    settings = _settings(demo.quick)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    hdri = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", HDRI)
    world = _world(scene, hdri)
    light_rig_scene.sphere_on_plane(scene)
    demo_render.use_cycles(scene, *settings["size"], transparent=True)
    scene.cycles.max_bounces = 2  # the same in both renders; the rig replaces the direct light
    if hasattr(scene.cycles, "use_light_tree"):
        # Blender 4.0+: the light tree costs much more than it saves with
        # 64 suns on 2 cores; sampling them by power (as 3.x does) is enough.
        scene.cycles.use_light_tree = False

    static = _static_rig(scene, world, out_folder, settings, demo)
    started = time.perf_counter()
    if _eevee_available():
        static["eevee"] = _eevee(scene, world, out_folder, settings, static)
    sheet_path, size = _sheet(static, settings, demo)
    error = f"RMSE {100 * static['render_relative_rmse']:.1f} % of the World render"
    made = "World vs rig renders"
    if "eevee" in static:
        e = static["eevee"]
        made += " in Cycles and EEVEE"
        error += "".join(f"; EEVEE {name} {100 * e[key]['render_relative_rmse']:.1f} % "
                         f"(mean {e[key]['render_mean_ratio']:.3f})"
                         for key, name in (("world", "World"), ("rig", "rig")))
        error += f", {e['rig_vs_direct']['render_mean_ratio']:.3f} of Cycles' direct light"
    demo.step("lights sheet", f"{os.path.basename(sheet_path)}: {made}, {size[0]}×{size[1]}", error,
              static["render_seconds"] + time.perf_counter() - started)
    animated = _animated_rig(scene, hdri, out_folder, settings, demo)
    static.pop("pictures")
    return {"hdri": hdri, "static": static, "animated": animated, "sheet": sheet_path}
