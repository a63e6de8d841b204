"""Issue #26's goals judged against the light factory EEVEE can draw from
lamps: Cycles' direct light (no bounce), beside the issue's reference
(Cycles with default bounces). Renders, per scene of the EEVEE benchmark,
Cycles' World render with `max_bounces` 0 at two seeds (cached beside the
benchmark's references), then reads that benchmark's EEVEE renders of this
Blender (its World renders and rigs, kept in OUT) and measures each against
both references. The errors against the issue's reference must equal the
benchmark's published ones: that proves the renders read are those. Prints
"RESULT {json}":

    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/lights_eevee_direct.py -- OUT CACHE MAP
    .venv313/bin/python bench/blender_scripts/lights_eevee_direct.py OUT CACHE MAP

OUT: the EEVEE benchmark's renders of this Blender (build/bench/lights_eevee/<blender>);
CACHE and MAP as for bench/blender_scripts/lights_eevee_render.py."""

import json
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.blender_scripts.lights_eevee_render import Renderer, reference, start_blender  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.lights_eevee import bundled_map, light_by_map  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.lights_eevee_benchmark import EEVEE_SAMPLES, HEIGHT, REFERENCE_SPP, WIDTH, result_path  # noqa: E402


def against(luma, truth):
    """(error, mean) of a render against a reference: RMS of the luminance
    difference / the reference's mean, and the mean ratio."""
    mean = float(np.mean(truth))
    return float(np.sqrt(np.mean((luma - truth) ** 2)) / mean), float(np.mean(luma)) / mean


def scene_and_references(name, map_path, cache, core):
    """The benchmark's scene `name` lit by its map, its Renderer, and its two
    references: (strength, render, bounced, direct, the direct one's facts)."""
    scene, strength = sunrise_sphere_scene(REFERENCE_SPP, EEVEE_SAMPLES)
    light_by_map(scene, map_path)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    render = Renderer(scene, core)
    bounced, _ = reference(render, cache, name)
    direct, facts = reference(render, cache, name, direct=True)
    return strength, render, bounced, direct, facts


def measure_scene(name, keys, out, cache, map_path, core):
    _, render, bounced, direct, facts = scene_and_references(name, map_path, cache, core)
    entries = {"direct": {"spp": facts["spp"], "noise": facts["noise"], "seconds": facts["seconds"],
                          "mean": float(np.mean(direct)) / float(np.mean(bounced))}}
    for key in keys:
        luma = render.read(os.path.join(out, f"{name}_{key}"))
        (error, mean), (issue_error, _) = against(luma, direct), against(luma, bounced)
        entries[key] = {"error": error, "mean": mean, "error_against_issue_reference": issue_error}
        print(name, key, entries[key], flush=True)
    return entries


def main(result, out, cache, opposite):
    core = start_blender()
    started = time.time()
    tag = f"{bpy.app.version[0]}.{bpy.app.version[1]}"
    with open(result_path(tag)) as f:
        stored = json.load(f)["scenes"]  # which renders the benchmark made
    result.update(tag=tag, blender=bpy.app.version_string, scenes={}, load=[os.getloadavg()[0]])
    for name, entries in stored.items():
        keys = [k for k in entries if k != "reference"]
        map_path = opposite if name == "opposite" else bundled_map(name)
        result["scenes"][name] = measure_scene(name, keys, out, cache, map_path, core)
        result["load"].append(os.getloadavg()[0])
    result["seconds"] = time.time() - started


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1:][:3]
    report(lambda result: main(result, *args))
