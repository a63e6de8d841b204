"""The renders of bench/lights_eevee_benchmark.py inside one Blender (one
process, so EEVEE compiles its shaders once): Debian's 3.4 (EEVEE Legacy,
under Xvfb), the bpy 4.5 module (EEVEE Next through EGL) or the bpy 5.2
module (EEVEE Next after gpu.init()). Per scene of SCENES (a sphere on a
plane, bench/helpers/lights_render_scene.py, at WIDTH x HEIGHT): Cycles'
World render at two seeds (the reference, cached in CACHE per Blender), EEVEE's
World render (4.2+: without and with the World's sun extraction), and EEVEE
renders of the operator's default rig built for EEVEE at COUNTS suns (and at
GOAL2_COUNT with shadow_budget SHADOW_BUDGET). Prints one line "RESULT {json}":

    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/lights_eevee_render.py -- OUT CACHE MAP
    .venv313/bin/python bench/blender_scripts/lights_eevee_render.py OUT CACHE MAP

OUT: this Blender's renders (EXR and PNG); MAP: the benchmark's map with
two opposite sources (its scene "opposite")."""

import json
import math
import os
import shutil
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.lights_eevee import bundled_map, eevee_engine, light_by_map  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.helpers.metrics import LUMINANCE  # noqa: E402
from bench.lights_eevee_benchmark import (  # noqa: E402  (its settings)
    ANGLES, COUNTS, EEVEE_SAMPLES, GOAL2_COUNT, HEIGHT, MAX_REFERENCE_SPP, NOISE_LIMIT, REFERENCE_SPP, SCENES,
    SHADOW_BUDGET, THRESHOLDS, WIDTH)

NEXT = bpy.app.version >= (4, 2, 0)  # EEVEE Next, and the World's sun extraction


class Renderer:
    """Renders the scene to STEM.exr and STEM.png; luminance and seconds."""

    def __init__(self, scene, core):
        self.scene, self.core = scene, core

    def __call__(self, engine, stem, seed=1):
        self.scene.render.engine = engine
        self.scene.cycles.seed = seed
        started = time.perf_counter()
        bpy.ops.render.render()
        seconds = time.perf_counter() - started
        result = bpy.data.images["Render Result"]
        settings = self.scene.render.image_settings
        settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA"
        result.save_render(stem + ".exr")
        settings.file_format, settings.color_depth = "PNG", "8"
        result.save_render(stem + ".png")
        return self.read(stem), seconds

    def read(self, stem):
        return self.core.image.read(stem + ".exr") @ LUMINANCE


def start_blender():
    """The add-on registered and its compiled core, with a GPU context for
    EEVEE (bpy 5.x makes none in the background until asked)."""
    if bpy.app.version >= (5, 0, 0) and bpy.app.background:
        import gpu
        gpu.init()
    penumbra.register()
    return native.require()


def reference(render, cache, name, direct=False):
    """The mean of Cycles' World render at seeds 1 and 2, from CACHE when
    rendered before; samples double from REFERENCE_SPP while the two seeds
    differ by NOISE_LIMIT or more. `direct`: Cycles' direct light only (no
    bounce, as EEVEE at factory settings draws lamps), cached apart.
    Returns (luminance, facts)."""
    spp, kind = REFERENCE_SPP, "_direct" if direct else ""
    if direct:
        render.scene.cycles.max_bounces = 0
    while True:
        lumas, seconds = [], 0.0
        for seed in (1, 2):
            stem = os.path.join(cache, f"{name}_{WIDTH}x{HEIGHT}_{spp}spp{kind}_seed{seed}")
            if os.path.exists(stem + ".exr"):
                lumas.append(render.read(stem))
                continue
            # Adaptive sampling (on by default) stops at its noise threshold,
            # far short of `spp`: the seeds then differ by ~3% whatever `spp`.
            render.scene.cycles.samples, render.scene.cycles.use_adaptive_sampling = spp, False
            luma, took = render("CYCLES", stem, seed)
            lumas.append(luma)
            seconds += took
        noise = float(np.sqrt(np.mean((lumas[0] - lumas[1]) ** 2)) / np.mean(lumas[0]))
        if noise < NOISE_LIMIT or spp >= MAX_REFERENCE_SPP:
            picture = os.path.join(cache, f"{name}_{WIDTH}x{HEIGHT}_{spp}spp{kind}_seed1.png")
            return (lumas[0] + lumas[1]) / 2, {"spp": spp, "noise": noise, "seconds": seconds, "picture": picture}
        spp *= 2


def build_rig(strength, out, count, budget=0):
    """The operator's default rig for EEVEE of `count` suns, built from the
    World, which then gives no light (strength 0): the rig alone lights the
    scene, with whatever the operator set on its lights."""
    strength.default_value = 1.0
    r = bpy.ops.penumbra.build_light_rig(filepath="", count=count, target_renderer="EEVEE", shadow_budget=budget,
                                         json_path=os.path.join(out, "rig.json"))
    assert r == {"FINISHED"}, r
    strength.default_value = 0.0
    suns = [o for o in bpy.context.scene.objects if o.type == "LIGHT"]
    return {"suns": len(suns), "shadowed": sum(bool(o.data.use_shadow) for o in suns)}


def world_variants(world):
    """(key, setter) of EEVEE's World renders: alone, and (4.2+) with the
    World's sun extraction over THRESHOLDS x ANGLES, its shadow on."""
    def alone():
        if NEXT:
            world.sun_threshold = 0.0  # 0 turns the extraction off (its default, 10, is on)

    variants = [("world", alone)]
    for threshold in (THRESHOLDS if NEXT else ()):
        for angle in ANGLES:
            def extract(t=threshold, a=angle):
                world.sun_threshold, world.sun_angle, world.use_sun_shadow = t, math.radians(a), True
            variants.append((f"sun_t{threshold:g}_a{angle:g}", extract))
    return variants


def phase_jobs(phase, world, strength, out):
    """(key, setup) of a phase: 0, goal 2's renders (the World's, the rig of
    GOAL2_COUNT suns); 1, the shadow budget's; 2, goal 1's other counts. A
    rig's setup returns its suns and shadowed suns."""
    if phase == 0:
        return world_variants(world) + [(f"rig_{GOAL2_COUNT}", lambda: build_rig(strength, out, GOAL2_COUNT))]
    if phase == 1:
        return [(f"rig_{GOAL2_COUNT}_budget{SHADOW_BUDGET}", lambda: build_rig(strength, out, GOAL2_COUNT,
                                                                                SHADOW_BUDGET))]
    return [(f"rig_{n}", lambda n=n: build_rig(strength, out, n)) for n in COUNTS if n != GOAL2_COUNT]


def run_order():
    """(scene, phase) in the order rendered: goal 2 on every scene first, so
    that a run stopped at its time limit has it on all it can, each scene's
    shadow budget right after its all-shadowed rig (their render times
    compare under the same load); then goal 1's other counts."""
    return [(name, phase) for name in SCENES for phase in (0, 1)] + [(name, 2) for name in SCENES]


def left_by_a_stopped_run(stem, key):
    """What an earlier run of this Blender, stopped at its time limit, kept
    of a render (PENUMBRA_EEVEE_RESUME=1): its facts, or for a World render,
    whose time is not published, its PNG (written last); else None."""
    if os.environ.get("PENUMBRA_EEVEE_RESUME") != "1":
        return None
    if os.path.exists(stem + ".json"):
        with open(stem + ".json") as f:
            return json.load(f)
    return {"seconds": None} if not key.startswith("rig") and os.path.exists(stem + ".png") else None


def render_scene(name, phase, entries, paths, core, save):
    """The renders of one phase on scene `name`, into `entries` (saved after each)."""
    out, cache, map_path = paths
    scene, strength = sunrise_sphere_scene(REFERENCE_SPP, EEVEE_SAMPLES)
    light_by_map(scene, map_path)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    render = Renderer(scene, core)
    truth, facts = reference(render, cache, name)
    shutil.copyfile(facts.pop("picture"), os.path.join(out, f"{name}_reference.png"))
    mean = float(np.mean(truth))
    entries.setdefault("reference", dict(facts, mean=mean))
    for key, setup in phase_jobs(phase, scene.world, strength, out):
        stem = os.path.join(out, f"{name}_{key}")
        facts = left_by_a_stopped_run(stem, key)
        if facts is None:
            facts = setup() or {}
            luma, facts["seconds"] = render(eevee_engine(), stem)
            with open(stem + ".json", "w") as f:
                json.dump(facts, f)
        else:
            luma = render.read(stem)
        entries[key] = dict(facts, error=float(np.sqrt(np.mean((luma - truth) ** 2)) / mean),
                            mean=float(np.mean(luma)) / mean)
        print(name, key, entries[key], flush=True)
        save()


def warm_up(out, map_path):
    """An untimed EEVEE render of a rig: a resumed run's first timed render
    would otherwise include compiling EEVEE's shaders (a run from the start
    renders the World first, whose time is not published)."""
    scene, strength = sunrise_sphere_scene(REFERENCE_SPP, EEVEE_SAMPLES)
    light_by_map(scene, map_path)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    build_rig(strength, out, GOAL2_COUNT)
    scene.render.engine = eevee_engine()
    bpy.ops.render.render()


def main(result, out, cache, opposite):
    core = start_blender()
    started = time.time()
    result.update(engine="EEVEE Next" if NEXT else "EEVEE Legacy", load=[os.getloadavg()[0]],
                  scenes={name: {} for name in SCENES})

    def save():  # what the driver publishes if it stops this run at its time limit
        with open(os.path.join(out, "partial.json.tmp"), "w") as f:
            json.dump(dict(result, seconds=time.time() - started), f)
        os.replace(os.path.join(out, "partial.json.tmp"), os.path.join(out, "partial.json"))

    if os.environ.get("PENUMBRA_EEVEE_RESUME") == "1":
        warm_up(out, opposite if SCENES[0] == "opposite" else bundled_map(SCENES[0]))
    for name, phase in run_order():
        paths = (out, cache, opposite if name == "opposite" else bundled_map(name))
        render_scene(name, phase, result["scenes"][name], paths, core, save)
        result["load"].append(os.getloadavg()[0])
    result["seconds"] = time.time() - started


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1:][:3]
    report(lambda result: main(result, *args))
