"""Measures the statistics of Blender's Noise Texture over a pixel footprint,
once, and writes addon/penumbra/colormap/noise_statistics.json. Run inside a
Blender (the noise is Blender's own, evaluated by geometry nodes, the same
noise code Cycles runs):

    blender -b --factory-startup --python scripts/colormap_measure_noise.py
    .venv/bin/python scripts/colormap_measure_noise.py

Model (docs/colormap.md, "Noise statistics"): a pixel's footprint on the
surface is an isotropic Gaussian of standard deviation s (noise-space units:
world units times the noise's Scale). Given the noise value f(x) at the
sample point, the values f(y) over the footprint are summarized by the best
Gaussian: mean f̂ = μ + ρ(s)(f(x) − μ) (linear regression on the centre
value) and standard deviation σ_f(s) (the residual RMS). Both are tabulated
against log2 s for each Detail and Roughness (Scale is factored out: the
noise is measured at Scale 1 and the footprint scaled instead; Distortion 0;
Lacunarity 2 in 4.x). Each table entry pools N footprints of M samples.

A second table, "octave", serves the octave-wise filter (docs/colormap.md,
"Octave filter"): for one octave (Detail 0, Scale 1) the fraction
q = E[within-footprint variance] / total variance over anisotropic Gaussian
footprints of standard deviations s (minor axis) and s·e (major axis), for
log2 e = 0 … 6. Each (D, r) entry also gets "within", the measured
within-footprint variance of the full noise (isotropic), against which the
octave model Σ w_i² V₀ q(2^i s) is checked."""

import json
import os
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [ROOT, os.path.join(ROOT, "addon")]  # bench.helpers; the add-on's source (no registration needed)
from bench.helpers.noise_points import noise_evaluator  # noqa: E402

DETAILS = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0]
ROUGHNESSES = [0.25, 0.5, 0.75, 1.0]
LOG2_FOOTPRINTS = np.linspace(-8.0, 4.0, 25)   # s from 1/256 to 16 noise units
CENTRES = 600
SAMPLES = 48
SEED = 20240611
LOG2_ELONGATIONS = np.arange(0.0, 7.0)          # major/minor axis ratio 1 … 64


def measure_octave(evaluate, noise, centres, unit_offsets, footprints):
    """q[e][s]: within-footprint variance of one octave (Detail 0) over a
    Gaussian footprint with standard deviations (s·2^e, s), divided by the
    octave's total variance (pooled over footprints of s >= 4, whose samples
    are practically independent)."""
    noise.inputs["Detail"].default_value = 0.0
    count, samples = unit_offsets.shape[:2]
    points = []
    for log2_e in LOG2_ELONGATIONS:
        for s in footprints:
            p = np.repeat(centres[:, None, :], samples, axis=1).copy()
            p[:, :, 0] += s * 2.0 ** log2_e * unit_offsets[:, :, 0]
            p[:, :, 1] += s * unit_offsets[:, :, 1]
            points.append(p.reshape(-1, 3))
    values = evaluate(np.concatenate(points)).reshape(len(LOG2_ELONGATIONS), len(footprints), count, samples)
    wide = values[0, footprints >= 4.0]
    total = float(wide.var())
    q = values.var(axis=3, ddof=1).mean(axis=2) / total
    print(f"octave: total variance {total:.5f}; q(s=1, e=1) {q[0, int(np.argmin(abs(np.log2(footprints))))]:.3f}",
          flush=True)
    return {"total_var": total, "q": q.tolist()}


def main():
    started = time.perf_counter()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    noise, evaluate = noise_evaluator()
    noise.noise_dimensions = "3D"
    noise.inputs["Scale"].default_value = 1.0
    noise.inputs["Distortion"].default_value = 0.0
    rng = np.random.default_rng(SEED)
    # The same footprints for every setting: centres spread over a large
    # region (away from the lattice's origin), Gaussian offsets in the plane.
    centres = np.column_stack([rng.uniform(10, 1010, CENTRES), rng.uniform(10, 1010, CENTRES),
                               np.full(CENTRES, 0.37)])
    unit_offsets = rng.normal(size=(CENTRES, SAMPLES, 2))
    footprints = 2.0 ** LOG2_FOOTPRINTS
    points = [centres]
    for s in footprints:
        p = np.repeat(centres[:, None, :], SAMPLES, axis=1).copy()
        p[:, :, :2] += s * unit_offsets
        points.append(p.reshape(-1, 3))
    points = np.concatenate(points)
    table = {}
    for detail in DETAILS:
        for roughness in ROUGHNESSES:
            noise.inputs["Detail"].default_value = detail
            noise.inputs["Roughness"].default_value = roughness
            values = evaluate(points)
            centre = values[:CENTRES]
            mu = float(values.mean())
            total = float(centre.std())
            rho, sigma, within = [], [], []
            for i in range(len(footprints)):
                f = values[CENTRES + i * CENTRES * SAMPLES: CENTRES + (i + 1) * CENTRES * SAMPLES].reshape(CENTRES, SAMPLES)
                x = np.repeat(centre[:, None], SAMPLES, axis=1)
                r = float(((x - mu) * (f - mu)).mean() / ((x - mu) ** 2).mean())
                residual = f - (mu + r * (x - mu))
                rho.append(r)
                sigma.append(float(np.sqrt((residual ** 2).mean())))
                within.append(float(f.var(axis=1, ddof=1).mean()))
            table[f"{detail:g}/{roughness:g}"] = {"mean": mu, "total_std": total, "rho": rho, "sigma": sigma,
                                                 "within": within,
                                                 "min": float(values.min()), "max": float(values.max())}
            print(f"detail {detail:g} roughness {roughness:g}: mean {mu:.4f} std {total:.4f} "
                  f"sigma(s=1) {sigma[int(np.argmin(abs(LOG2_FOOTPRINTS)))]:.4f}", flush=True)
    octave = measure_octave(evaluate, noise, centres, unit_offsets, footprints)
    version = f"{bpy.app.version[0]}.{bpy.app.version[1]}"
    path = os.path.join(ROOT, "addon", "penumbra", "colormap", "noise_statistics.json")
    data = json.load(open(path)) if os.path.exists(path) else {}
    data["about"] = __doc__.strip().splitlines()[0] + " See scripts/colormap_measure_noise.py."
    data["log2_footprint"] = LOG2_FOOTPRINTS.tolist()
    data["details"] = DETAILS
    data["roughnesses"] = ROUGHNESSES
    data["footprint_filter"] = "isotropic Gaussian, standard deviation s in noise units"
    data["log2_elongation"] = LOG2_ELONGATIONS.tolist()
    data.setdefault("blender", {})[version] = {"centres": CENTRES, "samples": SAMPLES, "seed": SEED,
                                               "seconds": round(time.perf_counter() - started, 1),
                                               "table": table, "octave": octave}
    with open(path + ".tmp", "w") as f:
        json.dump(data, f, indent=1)
    os.replace(path + ".tmp", path)
    print(f"wrote {path} for Blender {version} in {time.perf_counter() - started:.0f} s")


main()
