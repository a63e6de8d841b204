"""The shadowed comparison of bench/lights_benchmark.py, in the bpy module (a
fresh process): the sunrise scene (bench/helpers/lights_render_scene.py)
rendered with Cycles (CPU, no denoising) lit by the World, by the World again
with another seed (the noise floor), and by rigs of N suns (World strength
0). Prints one line "RESULT {json}" of relative RMSEs.

    .venv/bin/python bench/blender_scripts/lights_shadowed_render.py OUT COUNTS SAMPLES

COUNTS: comma-separated sun counts; renders go to the folder OUT."""

import json
import os
import sys
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.helpers.metrics import LUMINANCE  # noqa: E402


def main(out, counts, samples):
    penumbra.register()
    core = native.require()
    scene, strength = sunrise_sphere_scene(samples)
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"

    def render(name, seed):
        scene.cycles.seed = seed
        scene.render.filepath = os.path.join(out, name)
        bpy.ops.render.render(write_still=True)
        return core.image.read(scene.render.filepath + ".exr") @ LUMINANCE

    world_a = render("world_a", 1)
    world_b = render("world_b", 2)
    mean = float(np.mean(world_a))

    def rel(luma, reference=world_a):
        return float(np.sqrt(np.mean((luma - reference) ** 2)) / mean)

    result = {"noise": rel(world_b), "noise mean": float(np.mean(world_b)) / mean}
    for n in counts:
        strength.default_value = 1.0
        r = bpy.ops.penumbra.build_light_rig(filepath="", count=n, target_renderer="CYCLES",
                                             json_path=os.path.join(out, "rig.json"))
        assert r == {"FINISHED"}, r
        strength.default_value = 0.0
        rig_a = render(f"rig_{n}", 1)
        result[str(n)] = rel(rig_a)
        result[f"{n} mean"] = float(np.mean(rig_a)) / mean
        result[f"{n} noise"] = rel(render(f"rig_{n}_b", 2), rig_a)  # the rig render's own noise
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    try:
        main(sys.argv[1], [int(v) for v in sys.argv[2].split(",")], int(sys.argv[3]))
    except Exception:
        traceback.print_exc()
        sys.exit(1)
