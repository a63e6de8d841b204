#!/usr/bin/env python3
"""The renderers' limits (issue #14, item 4): the shadowed comparison of
docs/lights-benchmark.md (a sphere on a plane under Blender's sunrise.exr,
128x96) in EEVEE, beside Cycles in the same Blender:
  - EEVEE Legacy in Debian's Blender 3.4, headless under Xvfb (Mesa's
    llvmpipe: OpenGL on the CPU), rigs with and without the add-on's
    "Shadows for 8 Strongest" (limit_shadows);
  - EEVEE Next in the bpy 4.5 module, which makes its GPU context through
    EGL, here Mesa's software rasterizer too.
Writes the section "Shadowed comparison (EEVEE)" of docs/lights-benchmark.md
and its pictures (docs/lights/eevee_*.png):

    .venv/bin/python bench/lights_eevee_benchmark.py [--lock /work/bench.lock]

Each Blender runs this file itself (`--render OUT ENGINE`) and prints one
RESULT line of JSON. PENUMBRA_BENCH_QUICK=1: one rig, few samples (a smoke
test of the script, not a result).

EEVEE Legacy lights the scene with at most 128 lights and gives cascaded
shadow maps to at most 8 suns; EEVEE Next has neither cap (virtual shadow
maps). Both light the scene from the World through a light probe."""

import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "lights-benchmark.md")
PICTURES = os.path.join(ROOT, "docs", "lights")
QUICK = os.environ.get("PENUMBRA_BENCH_QUICK") == "1"
COUNTS = (16,) if QUICK else (16, 64, 256)
CYCLES_SPP = 4 if QUICK else 128
# EEVEE render samples (taa_render_samples; Blender's default is 64): 16 keeps
# an EEVEE Next render on llvmpipe near half a minute.
EEVEE_SAMPLES = 2 if QUICK else 16
MARKER = "\n## Shadowed comparison (EEVEE)"
LEGACY, NEXT = "BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"


# --- inside Blender ----------------------------------------------------------

def build_scene():
    """sunrise.exr on the World, the sphere on the plane, 128x96, black film."""
    import bpy
    sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
    import light_rig_scene
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world",
                                                  "sunrise.exr"))
    world.node_tree.links.new(env.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    light_rig_scene.sphere_on_plane(scene)
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 128, 96, 100
    scene.render.film_transparent = True  # black background: only the lit scene is compared
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", CYCLES_SPP, False
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    return scene, world.node_tree.nodes["Background"].inputs["Strength"]


class Renderer:
    """Renders to OUT/name.exr (and .png for pictures); luminance and times."""

    def __init__(self, scene, out, core):
        import numpy as np
        self.scene, self.out, self.core = scene, out, core
        self.y = np.array([0.2126, 0.7152, 0.0722])
        self.seconds = {}

    def __call__(self, engine, name, picture=False, seed=1):
        import bpy
        self.scene.render.engine = engine
        self.scene.cycles.seed = seed
        started = time.perf_counter()
        bpy.ops.render.render()
        self.seconds[name] = time.perf_counter() - started
        result = bpy.data.images["Render Result"]
        settings = self.scene.render.image_settings
        settings.file_format, settings.color_depth = "OPEN_EXR", "32"
        path = os.path.join(self.out, name + ".exr")
        result.save_render(path)
        if picture:
            settings.file_format, settings.color_depth, settings.color_mode = "PNG", "8", "RGBA"
            result.save_render(os.path.join(self.out, name + ".png"))
        return self.core.image.read(path) @ self.y


def render_all(out, eevee):
    """Cycles' World render (the truth) and a second seed of it, EEVEE's World
    render, and EEVEE renders of rigs of COUNTS suns (Legacy: every sun asking
    for a shadow, then only the 8 strongest; Next: every sun), each rig also
    in Cycles; returns the errors, means, counts and times."""
    import bpy
    import numpy as np
    sys.path.insert(0, os.path.join(ROOT, "build", "addon"))
    import penumbra
    penumbra.register()
    from penumbra import native
    scene, strength = build_scene()
    render = Renderer(scene, out, native.require())
    truth = render("CYCLES", "cycles_world", picture=True)
    mean = float(np.mean(truth))

    def error(luma, reference=truth):
        return float(np.sqrt(np.mean((luma - reference) ** 2)) / mean)

    result = {"blender": bpy.app.version_string, "engine": eevee, "eevee samples": EEVEE_SAMPLES,
              "cycles noise": error(render("CYCLES", "cycles_world_b", seed=2))}
    eevee_world = render(eevee, "eevee_world", picture=True)
    result["eevee world"] = {"error": error(eevee_world), "mean": float(np.mean(eevee_world)) / mean}
    middle = COUNTS[len(COUNTS) // 2]
    for n in COUNTS:
        for limit in ((False, True) if eevee == LEGACY else (False,)):
            strength.default_value = 1.0
            r = bpy.ops.penumbra.build_light_rig(filepath="", count=n, limit_shadows=limit,
                                                 json_path=os.path.join(out, "rig.json"))
            assert r == {"FINISHED"}, r
            strength.default_value = 0.0
            suns = [o for o in scene.objects if o.type == "LIGHT"]
            key = f"{n} {'limited' if limit else 'all'}"
            luma = render(eevee, f"eevee_{n}_{'limited' if limit else 'all'}",
                          picture=n == middle and (limit or eevee == NEXT))
            entry = {"error": error(luma), "vs eevee world": error(luma, eevee_world),
                     "mean": float(np.mean(luma)) / mean, "suns": len(suns),
                     "shadowed": sum(o.data.use_shadow for o in suns)}
            if not limit:
                cycles = render("CYCLES", f"cycles_{n}")
                entry["cycles error"], entry["cycles mean"] = error(cycles), float(np.mean(cycles)) / mean
            result[key] = entry
    result["seconds"] = render.seconds
    return result


def render_main(out, engine):
    import traceback
    try:
        print("RESULT " + json.dumps(render_all(out, engine)), flush=True)
    except Exception:
        traceback.print_exc()
        sys.exit(1)


# --- the driver ----------------------------------------------------------------

def rows(r):
    """Table rows of one Blender's EEVEE renders."""
    legacy = r["engine"] == LEGACY
    name = "EEVEE Legacy" if legacy else "EEVEE Next"
    w = r["eevee world"]
    out = [f"| {r['blender']} | {name}, World | – | – | {100 * w['error']:.2f}% | 0 | {w['mean']:.3f} | "
           f"{r['seconds']['eevee_world']:.1f} |"]
    for n in COUNTS:
        for key, label in (("all", "all"), ("limited", "8 strongest")):
            if f"{n} {key}" not in r:
                continue
            e = r[f"{n} {key}"]
            drawn = f"{min(e['suns'], 128)} of {e['suns']}" if legacy else f"{e['suns']}"
            shadowed = (f"{min(e['shadowed'], 8)} of {e['shadowed']} asking" if legacy else f"{e['shadowed']}")
            out.append(f"| {r['blender']} | {name}, {n} suns, shadows: {label} | {drawn} | {shadowed} | "
                       f"{100 * e['error']:.2f}% | {100 * e['vs eevee world']:.2f}% | {e['mean']:.3f} | "
                       f"{r['seconds'][f'eevee_{n}_{key}']:.1f} |")
    return out


def cycles_rows(r):
    out = [f"| {r['blender']} | Cycles, World, another seed (noise floor) | {100 * r['cycles noise']:.2f}% | – | "
           f"{r['seconds']['cycles_world_b']:.1f} |"]
    for n in COUNTS:
        e = r[f"{n} all"]
        out.append(f"| {r['blender']} | Cycles, {n} suns | {100 * e['cycles error']:.2f}% | {e['cycles mean']:.3f} | "
                   f"{r['seconds'][f'cycles_{n}']:.1f} |")
    return out


def section(results, elapsed):
    legacy, nxt = results
    middle = COUNTS[len(COUNTS) // 2]
    lines = [
        "",
        "## Shadowed comparison (EEVEE)" + (" (QUICK SMOKE TEST, NOT A RESULT)" if QUICK else ""),
        "",
        f"Written by `bench/lights_eevee_benchmark.py` ({time.strftime('%Y-%m-%d')}, {elapsed:.0f} s). The scene of "
        f"the Cycles comparison above (128x96, film transparent) in EEVEE Legacy (Debian's Blender "
        f"{legacy['blender']}, headless under Xvfb) and EEVEE Next (the bpy {nxt['blender']} module, whose GPU "
        "context comes through EGL), both on Mesa's llvmpipe (OpenGL on the CPU: no GPU here), "
        f"{EEVEE_SAMPLES} EEVEE samples, beside Cycles in the same Blender (CPU, {CYCLES_SPP} samples, no "
        "denoising). Each rig is built by `penumbra.build_light_rig` in that Blender (region powers, Havran; "
        "World strength 0 for the rig renders). Error = RMS of the luminance difference / mean luminance of "
        "that Blender's Cycles World render (the truth: the sun's shadow, the sky's occlusion); `vs EEVEE World` "
        "the same against EEVEE's own World render; `mean` = mean luminance / the Cycles World's; render time "
        "on the shared 2-core machine.",
        "",
        "EEVEE lights a scene from the World through its light probe (an irradiance and a reflection map), "
        f"without any shadow: its World render is {100 * legacy['eevee world']['error']:.1f}% (Legacy) and "
        f"{100 * nxt['eevee world']['error']:.1f}% (Next) from the truth, the sphere's shadow missing. A rig's "
        "suns bring the shadows back where EEVEE lets them: EEVEE Legacy draws at most 128 lights and gives "
        "cascaded shadow maps to at most 8 suns. `all`: every sun asks for a shadow and EEVEE grants 8 of its "
        "choosing; `8 strongest`: the add-on's *Shadows for 8 Strongest* (`limit_shadows`) gives them to the 8 "
        "suns of most power and turns the others' off. EEVEE Next draws and shadows every sun.",
        "",
        "| Blender | lit by | suns drawn | suns shadowed | error vs Cycles World | vs EEVEE World | mean | "
        "render (s) |",
        "|---|---|---|---|---|---|---|---|",
    ] + rows(legacy) + rows(nxt) + [
        "",
        "The same rigs in Cycles (every sun drawn and shadowed):",
        "",
        "| Blender | lit by | error vs Cycles World | mean | render (s) |",
        "|---|---|---|---|---|",
    ] + cycles_rows(legacy) + cycles_rows(nxt) + [
        "",
        "Pictures (Blender 3.4): [Cycles, World](lights/eevee_cycles_world.png), "
        f"[EEVEE Legacy, World](lights/eevee_world.png), [EEVEE Legacy, {middle} suns, 8 strongest shadowed]"
        f"(lights/eevee_rig_{middle}.png); (bpy 4.5) [EEVEE Next, World](lights/eevee_next_world.png), "
        f"[EEVEE Next, {middle} suns](lights/eevee_next_rig_{middle}.png).",
    ]
    return "\n".join(lines) + "\n"


def run_blender(command, out, engine):
    res = subprocess.run(command + ["--render", out, engine], capture_output=True, text=True, timeout=5400,
                         env=dict(os.environ, GALLIVM_PERF="nopt", LP_NUM_THREADS="2"))
    line = [x for x in res.stdout.splitlines() if x.startswith("RESULT ")]
    if res.returncode != 0 or not line:
        print(res.stdout[-4000:], res.stderr[-4000:])
        sys.exit(f"the {engine} renders failed")
    return json.loads(line[0][len("RESULT "):])


def main():
    import shutil
    import tempfile
    from bench_doc import lock_path, locked, write_section  # the driver runs from bench/
    lock = lock_path(sys.argv)
    started = time.time()
    this = os.path.abspath(__file__)
    middle = COUNTS[len(COUNTS) // 2]
    results = []
    with locked(lock):
        for command, engine, pictures in (
                (["xvfb-run", "-a", "blender", "-b", "--factory-startup", "--python", this, "--"], LEGACY,
                 (("cycles_world", "eevee_cycles_world.png"), ("eevee_world", "eevee_world.png"),
                  (f"eevee_{middle}_limited", f"eevee_rig_{middle}.png"))),
                ([os.path.join(ROOT, ".venv", "bin", "python"), this], NEXT,
                 (("eevee_world", "eevee_next_world.png"), (f"eevee_{middle}_all", f"eevee_next_rig_{middle}.png")))):
            with tempfile.TemporaryDirectory(prefix="penumbra_eevee_") as out:
                results.append(run_blender(command, out, engine))
                print(json.dumps(results[-1], indent=1), flush=True)
                for name, picture in pictures:
                    shutil.copyfile(os.path.join(out, name + ".png"), os.path.join(PICTURES, picture))
    write_section(DOC, MARKER, section(results, time.time() - started), "\n## Shadowed comparison (Cycles)")
    print("wrote", DOC)


if __name__ == "__main__":
    if "--render" in sys.argv:
        i = sys.argv.index("--render")
        render_main(sys.argv[i + 1], sys.argv[i + 2])
    else:
        main()
