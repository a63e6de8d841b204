"""Colour-map filtering demo (run inside Blender by examples/demo_blender.py):
a Noise Texture through a sharp ColorRamp on a plane receding to the
horizon. The plain ramp is rendered at 1 and 16 samples per pixel and, as
the reference, at many samples over a crop near the horizon; then "Bake
Filtered Colour Map" (penumbra.bake_colormap_lut) swaps in Penumbra's node
group, rendered at 1 sample per pixel. The contact sheet shows the crops
against the reference with their RMSE. run(out_folder, demo) -> dict."""

import os
import sys
import time

import bpy
import numpy as np

sys.path[:0] = [os.path.dirname(os.path.abspath(__file__)), os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenes")]
import colormap_scene  # noqa: E402  (examples/scenes/colormap_scene.py)
import contact_sheet as cs  # noqa: E402  (examples/contact_sheet.py)
import demo_render  # noqa: E402  (examples/demo_render.py)

DIFFERENCE_SCALE = 0.25  # |Δ| (mean over RGB) at the bright end of the heat ramp


EQUAL_TIME_SPP = 16   # the filtered render set beside the plain ramp at equal time
MAX_PLAIN_SPP = 4096


def _settings(quick):
    if quick:
        return {"size": (288, 162), "crop": (108, 43, 180, 84), "enlarge": 6, "reference_spp": 64}
    # crop: (x0, y0, x1, y1) in pixels from the top left, just below the
    # horizon, where the noise is finer than a pixel and a plain ramp sparkles.
    return {"size": (576, 324), "crop": (216, 86, 360, 167), "enlarge": 3, "reference_spp": 512}


def _scene(out_folder, settings):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    demo_render.use_cycles(scene, *settings["size"])
    world = bpy.data.worlds.new("black")  # the plane emits; nothing else lights anything
    if bpy.app.version < (5, 0, 0):
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    if hasattr(world, "cycles"):
        world.cycles.sampling_method = "NONE"
    scene.world = world
    scene.penumbra.colormap.output_folder = out_folder
    colormap_scene.noise_ramp_plane(roughness=0.5)  # as bench/blender_scripts/colormap_render.py
    return scene


def _render(scene, out_folder, name, spp, crop=None):
    """Renders (the crop only, when given) and returns (RGB, seconds)."""
    render = scene.render
    render.use_border = render.use_crop_to_border = crop is not None
    if crop is not None:
        width, height = render.resolution_x, render.resolution_y
        x0, y0, x1, y1 = crop
        render.border_min_x, render.border_max_x = x0 / width, x1 / width
        render.border_min_y, render.border_max_y = 1.0 - y1 / height, 1.0 - y0 / height  # from the bottom
    started = time.perf_counter()
    pixels = demo_render.render(scene, os.path.join(out_folder, name + ".exr"), spp, seed=1)
    seconds = time.perf_counter() - started
    render.use_border = render.use_crop_to_border = False
    return pixels[..., :3], seconds


def _crop(image, crop):
    x0, y0, x1, y1 = crop
    return image[y0:y1, x0:x1]


def run(out_folder, demo):
    settings = _settings(demo.quick)
    scene = _scene(out_folder, settings)
    crop = settings["crop"]

    # The plain ramp, and its reference over the crop.
    started = time.perf_counter()
    reference, reference_s = _render(scene, out_folder, f"reference_{settings['reference_spp']}spp",
                                     settings["reference_spp"], crop)
    plain1, plain1_s = _render(scene, out_folder, "plain_ramp_1spp", 1)
    plain16, plain16_s = _render(scene, out_folder, "plain_ramp_16spp", 16)
    plain_seconds = time.perf_counter() - started

    started = time.perf_counter()
    if bpy.ops.penumbra.bake_colormap_lut() != {"FINISHED"}:
        raise RuntimeError("colour-map bake failed")
    bake_s = time.perf_counter() - started
    material = bpy.data.materials["noise ramp"]
    group = material.node_tree.nodes["Penumbra Filtered Ramp"]
    demo.step("colour-map lookup", group.node_tree["penumbra_lookup"]["image"], "", bake_s)
    filtered, filtered_s = _render(scene, out_folder, "penumbra_1spp", 1)
    filtered16, filtered16_s = _render(scene, out_folder, f"penumbra_{EQUAL_TIME_SPP}spp", EQUAL_TIME_SPP)

    # The plain ramp rendered for the filtered render's time: a user pays for
    # seconds, not samples (issue #25). Its sample count comes from the plain
    # renders' own seconds (a fixed cost plus a cost per sample).
    with_filter = _disconnect_filter(material)
    plain_spp = _plain_spp_for(filtered16_s, (1, plain1_s), (16, plain16_s))
    plain_eq, plain_eq_s = _render(scene, out_folder, f"plain_ramp_{plain_spp}spp", plain_spp)
    if not 0.8 < plain_eq_s / filtered16_s < 1.25:   # once more, from the nearer measurement
        plain_spp = _plain_spp_for(filtered16_s, (16, plain16_s), (plain_spp, plain_eq_s))
        plain_eq, plain_eq_s = _render(scene, out_folder, f"plain_ramp_{plain_spp}spp", plain_spp)
    with_filter()

    results = []
    for name, image, spp, seconds in (("plain ramp", plain1, 1, plain1_s), ("plain ramp", plain16, 16, plain16_s),
                                      ("Penumbra filtered ramp", filtered, 1, filtered_s),
                                      ("Penumbra filtered ramp", filtered16, EQUAL_TIME_SPP, filtered16_s),
                                      ("plain ramp", plain_eq, plain_spp, plain_eq_s)):
        part = _crop(image, crop)
        results.append({"method": name, "spp": spp, "seconds": round(seconds, 3), "picture": part,
                        "rmse": float(np.sqrt(((part - reference) ** 2).mean()))})
    equal_time = {"filtered": {k: results[3][k] for k in ("spp", "seconds", "rmse")},
                  "plain": {k: results[4][k] for k in ("spp", "seconds", "rmse")}}
    started = time.perf_counter()
    sheet_path, size = _sheet(settings, reference, results, plain1, filtered, demo)
    rmse = {f"{r['method']} {r['spp']} spp": r["rmse"] for r in results}
    f, p = equal_time["filtered"], equal_time["plain"]
    demo.step("colour-map sheet", f"{os.path.basename(sheet_path)}: {len(results)} crops, {size[0]}×{size[1]}",
              f"equal time: RMSE {p['rmse']:.3f} plain ({p['spp']} spp, {p['seconds']:.2f} s) vs "
              f"{f['rmse']:.3f} Penumbra ({f['spp']} spp, {f['seconds']:.2f} s)",
              plain_seconds + filtered_s + filtered16_s + plain_eq_s + time.perf_counter() - started)
    for r in results:
        r.pop("picture")
    return {"bake_seconds": round(bake_s, 3), "reference_spp": settings["reference_spp"],
            "reference_seconds": round(reference_s, 3), "crop": list(crop), "rmse": rmse, "renders": results,
            "equal_time": equal_time, "sheet": sheet_path}


def _plain_spp_for(seconds, low, high):
    """The plain ramp's sample count whose render takes `seconds`, from two
    of its renders (spp, seconds) on a line; at least 1."""
    (s0, t0), (s1, t1) = sorted([low, high])
    per_sample = (t1 - t0) / (s1 - s0) if s1 != s0 else 0.0
    if per_sample <= 0.0:   # timing noise: no fixed cost then
        per_sample = t1 / s1
    return min(MAX_PLAIN_SPP, max(1, int(round(s1 + (seconds - t1) / per_sample))))


def _disconnect_filter(material):
    """Shows the plain ramp again (the bake muted it and routed its output
    through the filter); returns the function that puts the filter back."""
    tree = material.node_tree
    group = tree.nodes["Penumbra Filtered Ramp"]
    ramp = tree.nodes[group["penumbra_original_ramp"]]
    targets = {name: [link.to_socket for link in group.outputs[name].links] for name in ("Color", "Alpha")}
    ramp.mute = False
    for name, sockets in targets.items():
        for socket in sockets:
            tree.links.new(ramp.outputs[name], socket)

    def restore():
        ramp.mute = True
        for name, sockets in targets.items():
            for socket in sockets:
                tree.links.new(group.outputs[name], socket)
    return restore


def _sheet(settings, reference, results, plain1, filtered, demo):
    k = settings["enlarge"]
    x0, y0, x1, y1 = settings["crop"]
    sheet = cs.Sheet("Colour map: a sharp ColorRamp on noise, far away",
                     f"Noise Texture through a two-stop ramp on a plane; Cycles; reference: the plain ramp "
                     f"at {settings['reference_spp']} spp")
    full = []
    for image, label in ((plain1, "plain ramp, 1 spp"), (filtered, "Penumbra filtered ramp, 1 spp")):
        picture = demo_render.display(image)
        cs.outline(picture, x0 - 2, y0 - 2, x1 + 2, y1 + 2)
        full.append(cs.Tile(picture, [label, "the box: the crop below"]))
    sheet.row(full, "whole frame")
    shown_reference = cs.enlarge(demo_render.display(reference), k)
    for r in results:
        difference = np.abs(r["picture"] - reference).mean(axis=-1)
        sheet.row([cs.Tile(shown_reference, [f"reference, {settings['reference_spp']} spp"]),
                   cs.Tile(cs.enlarge(demo_render.display(r["picture"]), k), [f"{r['method']}, {r['spp']} spp"]),
                   cs.Tile(cs.enlarge(cs.heat(difference, DIFFERENCE_SCALE), k),
                           [f"|difference|, 0 - {DIFFERENCE_SCALE:g}"])],
                  f"{r['method']} at {r['spp']} spp, {r['seconds']:.2f} s: RMSE {r['rmse']:.4f}"
                  + (" (equal time)" if r is results[-1] or r is results[-2] else ""))
    path = demo.sheet_path("colormap")
    return path, sheet.write(path)
