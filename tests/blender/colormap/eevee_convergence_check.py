"""The colour-map filter in EEVEE Legacy (Debian's Blender 3.4 under Xvfb):

    xvfb-run -a blender -b --factory-startup --python eevee_convergence_check.py

run by tests/python/colormap/test_eevee_convergence_in_blender.py. Prints one
line "RESULT {json}". On the benchmark plane (bench/blender_scripts/colormap_render.py's
scene "plane", 64×36):
  - lookup: the Filtered Ramp fed the raw noise and σ = 0 against the plain
    ramp, both at one sample (the same shading points): what is left is the
    lookup's own interpolation. A renderer that mipmaps the lookup blurs it.
  - convergence: plain and filtered at 1 and 64 samples against the plain
    ramp at REFERENCE_SAMPLES (EEVEE's own converged image: the same
    Blackman-Harris pixel filter, so no supersampling is needed)."""

import json
import os
import sys
import traceback

os.environ.setdefault("GALLIVM_PERF", "nopt")   # see bench/blender_scripts/colormap_eevee_render.py
os.environ.setdefault("LP_NUM_THREADS", "2")

import bpy  # noqa: E402
import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, ROOT)  # bench.blender_scripts
from bench.blender_scripts import colormap_eevee_render as eevee_bench  # noqa: E402
from bench.blender_scripts import colormap_render as harness  # noqa: E402

SIZE = (64, 36)
REFERENCE_SAMPLES = 512


def render(ctx, folder, name, samples):
    eevee_bench.Eevee().set_samples(ctx.scene, samples)
    harness.update(ctx.scene)
    path = os.path.join(folder, name + ".exr")
    harness.render(ctx.scene, path)
    return harness.read(path)


def lookup_at_zero_sigma(ctx, folder):
    """Max and RMS |filtered ramp at σ = 0 − plain ramp| at one sample."""
    tree = ctx.material.node_tree
    group = tree.nodes["Penumbra Filtered Ramp"]
    noise = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    harness.set_method(ctx, "plain")
    plain = render(ctx, folder, "lookup_plain", 1)
    harness.set_method(ctx, "penumbra")
    saved = [link.from_socket for link in group.inputs["Sigma"].links]
    for name in ("Sigma", "Mean", "Offsets", "Variances"):   # one Gaussian, σ = 0
        for link in list(group.inputs[name].links):
            tree.links.remove(link)
    group.inputs["Sigma"].default_value = 0.0
    tree.links.new(noise.outputs["Fac"], group.inputs["Mean"])
    looked_up = render(ctx, folder, "lookup_filtered", 1)
    tree.links.remove(group.inputs["Mean"].links[0])
    return {"max_abs": float(np.abs(looked_up - plain).max()), "rmse": harness.rmse(looked_up, plain),
            "sigma_was_linked": bool(saved)}


def main(folder):
    harness.penumbra.register()
    runner = eevee_bench.Eevee()
    cfg = harness.config("eevee", quick=True, environment=False)
    ctx = harness.build(runner, "plane", SIZE, cfg, folder)
    result = {"blender": bpy.app.version_string, "size": list(SIZE), "reference_samples": REFERENCE_SAMPLES}
    harness.set_method(ctx, "plain")
    reference = render(ctx, folder, "reference", REFERENCE_SAMPLES)
    errors = {}
    for method in harness.METHODS:
        harness.set_method(ctx, method)
        errors[method] = {str(n): harness.rmse(render(ctx, folder, f"{method}{n}", n), reference) for n in (1, 64)}
    result["rmse"] = errors
    result["driven"] = harness.driven_values(ctx.material)
    ctx = harness.build(runner, "plane", SIZE, cfg, os.path.join(folder, "lookup"))
    result["lookup"] = lookup_at_zero_sigma(ctx, folder)
    return result


if __name__ == "__main__":
    out = sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else bpy.app.tempdir
    try:
        report = main(out)
        report["ok"] = True
    except Exception:
        report = {"ok": False, "error": traceback.format_exc()}
    print("RESULT " + json.dumps(report), flush=True)
