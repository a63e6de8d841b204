"""The first EEVEE Legacy render of a colour-map scene in a fresh Blender
3.4 (issue #25: compile time and peak resident memory, the plain ramp
against a Noise Filter preset), one method per process so each peak is its
own:

    xvfb-run -a blender -b --factory-startup --python-exit-code 1 --python \\
        bench/blender_scripts/colormap_eevee_first_render.py -- SCENE METHOD SAMPLES OUT.json

METHOD: plain, or a preset of filter_quality.QUALITIES baked on the scene
(colormap_render.SCENES at the benchmark's size, 192×108 for the planes,
EEVEE as colormap_eevee_render.py sets it up, llvmpipe with GALLIVM_PERF=nopt
and 2 threads). Writes {"first_render_s", "second_render_s", "peak_rss_kib",
"rss_before_render_kib", ...}: the compile time is the first render's
seconds less the second's (the shader is then cached)."""

import json
import os
import resource
import sys
import time

os.environ.setdefault("GALLIVM_PERF", "nopt")   # as colormap_eevee_render.py: llvmpipe without LLVM's optimizer
os.environ.setdefault("LP_NUM_THREADS", "2")

import bpy  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from bench.blender_scripts import colormap_render as harness  # noqa: E402
from bench.blender_scripts.colormap_eevee_render import Eevee  # noqa: E402


def build(runner, name, method, cfg, folder):
    """colormap_render.build with the preset chosen before the bake; the
    filtered ramp wired in unless `method` is plain."""
    scene = harness.new_scene(harness.scene_size(name, cfg), cfg["threads"])
    runner.configure(scene, cfg)
    builder, kwargs, _, _ = harness.SCENES[name]
    built = getattr(harness.colormap_scene, builder)(**kwargs)
    if method != "plain":
        scene.penumbra.colormap.filter_quality = method
        scene.penumbra.colormap.output_folder = folder
        if bpy.ops.penumbra.bake_colormap_lut() != {"FINISHED"}:
            raise RuntimeError(f"the bake at {method} failed")
    return scene, built


def main():
    name, method, samples, out_path = sys.argv[sys.argv.index("--") + 1:][:4]
    harness.penumbra.register()
    runner = Eevee()
    cfg = harness.config("eevee", quick=False, environment=False)
    folder = os.path.splitext(out_path)[0] + "_files"
    os.makedirs(folder, exist_ok=True)
    scene, _built = build(runner, name, method, cfg, folder)
    runner.set_samples(scene, int(samples))
    harness.update(scene)
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    seconds = []
    for i in range(2):
        started = time.perf_counter()
        harness.render(scene, os.path.join(folder, f"render_{i}.exr"))
        seconds.append(time.perf_counter() - started)
    with open(out_path, "w") as f:
        json.dump({"scene": name, "method": method, "samples": int(samples), "blender": bpy.app.version_string,
                   "size": [scene.render.resolution_x, scene.render.resolution_y],
                   "first_render_s": seconds[0], "second_render_s": seconds[1],
                   "peak_rss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
                   "rss_before_render_kib": rss_before, "load_average": os.getloadavg()}, f, indent=1)


main()
