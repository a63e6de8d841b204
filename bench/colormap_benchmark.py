#!/usr/bin/env python3
"""Colour-map filtering measurements -> docs/colormap-benchmark.md (+ EXR/PNG
renders in docs/colormap/). Ratios are against baselines measured in the same
run: lookup build time against a brute-force sampled convolution, bilinear
error against table size, the paper's height fit against the exact table,
and Cycles renders against a 1024-spp ground truth (bench/colormap_render.py,
run in the bpy module)."""

import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "addon", "penumbra"))
import _penumbra as pen  # noqa: E402

DOCS = os.path.join(ROOT, "docs")
lines = ["# Colour-map filtering: measurements", "",
         "Written by `bench/colormap_benchmark.py` (`make bench BENCH=colormap`). Machine: shared 2-core CI box.", ""]


def timed(fn, repeat=3):
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def brute_force_lut(positions, colors, width, height, sigma_max, mean_min, mean_max, samples=2001):
    """Baseline: the convolution by a sampled sum (what the exact form replaces)."""
    z = np.linspace(-6, 6, samples)
    w = np.exp(-0.5 * z * z)
    w /= w.sum()
    means = np.linspace(mean_min, mean_max, width)
    out = np.empty((height, width, colors.shape[1]), np.float32)
    for y in range(height):
        s = sigma_max * y / (height - 1)
        v = means[:, None] + s * z[None, :]
        for c in range(colors.shape[1]):
            out[y, :, c] = (np.interp(v, positions, colors[:, c]) * w).sum(1)
    return out


def maps():
    rng = np.random.default_rng(11)
    stops = np.array([[0.3, 0.9, 0.1, 0.05, 1], [0.5, 0.05, 0.2, 0.9, 1], [0.52, 1, 1, 1, 1], [0.8, 0, 0, 0, 1]],
                     np.float32)
    out = {}
    for name, interp in (("ramp LINEAR (4 stops, exact)", "LINEAR"), ("ramp CONSTANT (4 stops, exact)", "CONSTANT"),
                         ("ramp B_SPLINE (1024 samples)", "B_SPLINE")):
        k = pen.colormap.ramp_to_knots(stops, interp, "RGB", "NEAR", sampling="exact", channels=3)
        out[name] = (k["positions"], k["colors"], k["interpolation"], k["max_sampling_error"])
    k = pen.colormap.ramp_to_knots(stops, "LINEAR", "RGB", "NEAR", sampling="cycles", channels=3)
    out["ramp as Cycles renders (256 entries)"] = (k["positions"], k["colors"], k["interpolation"], 0.0)
    out["random 256 samples"] = (np.linspace(0, 1, 256), rng.random((256, 3)), pen.colormap.MapInterpolation.LINEAR, 0.0)
    return out


def bench_build():
    out = ["## Building a 256 × 256 lookup", "",
           "| colour map | knots | exact (s) | sampled sum, 2001 taps (s) | speed-up | max |exact − sampled| | ramp sampling error |",
           "|---|---|---|---|---|---|---|"]
    for name, (p, c, interp, sampling_error) in maps().items():
        t_exact, lut = timed(lambda: pen.colormap.lut_knots(p, c, interp, 256, 256, 0.25, -0.25, 1.25))
        if interp == pen.colormap.MapInterpolation.LINEAR:
            t_brute, ref = timed(lambda: brute_force_lut(p, c, 256, 256, 0.25, -0.25, 1.25), repeat=1)
            diff = float(abs(ref - lut)[1:].max())
            out.append(f"| {name} | {len(p)} | {t_exact:.3f} | {t_brute:.2f} | {t_brute / t_exact:.0f}× | {diff:.1e} | {sampling_error:.1e} |")
        else:
            out.append(f"| {name} | {len(p)} | {t_exact:.3f} | – | – | – | {sampling_error:.1e} |")
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    lut = pen.colormap.lut(np.random.default_rng(1).random((256, 3)).astype(np.float32), 256, 256, 0.25, 0, 1)
    out += ["", f"Memory: the table itself is {lut.nbytes / 1024:.0f} KiB as float32 RGB "
            f"({lut.nbytes * 2 // 4 // 1024} KiB as half, 192 KiB as 8-bit RGB like the paper); peak RSS grew by "
            f"{max(0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss_before)} KiB building it "
            "(no buffers beyond the output). The exact build is threaded over rows (2 threads here).", ""]
    return out


def bench_accuracy():
    out = ["## Bilinear lookup error against the exact value", "",
           "RMS / max over 300 × 300 probes between texels (`colormap.lut_accuracy`), σ_max 0.25, means [−0.25, 1.25].", "",
           "| colour map | size | linear σ rows: RMS | max | quadratic σ rows: RMS | max |", "|---|---|---|---|---|---|"]
    for name, (p, c, interp, _) in maps().items():
        for size in (64, 256, 1024):
            row = [name, f"{size}²"]
            for spacing in ("linear", "quadratic"):
                lut = pen.colormap.lut_knots(p, c, interp, size, size, 0.25, -0.25, 1.25, sigma_spacing=spacing)
                a = pen.colormap.lut_accuracy(p, c, interp, lut, 0.25, -0.25, 1.25, spacing, 300)
                row += [f"{a['rms_error']:.1e}", f"{a['max_abs_error']:.1e}"]
            out.append("| " + " | ".join(row) + " |")
    out += ["", "The largest errors sit at σ ≈ 0 on the map's sharp features, where no table resolves "
            "a kink or step finer than a column; linear σ spacing is as good or better than quadratic for every "
            "map measured, so it is the default in the add-on as in the contract.", ""]
    return out


def bench_height():
    out = ["## Effective height distribution: the paper's fit (Eqs. 17–18) against the exact table", "",
           "| Λ(ω_o)+Λ(ω_i) | exact μ_d/σ_h | fit μ_d/σ_h | error | exact σ_d/σ_h | fit σ_d/σ_h | error |",
           "|---|---|---|---|---|---|---|"]
    for lam in (0.01, 0.05, 0.1, 0.3, 1, 3, 10, 100, 1e4):
        em, es = pen.colormap.effective_height(lam, "exact")
        fm, fs = pen.colormap.effective_height(lam, "fit")
        out.append(f"| {lam:g} | {em:.4f} | {fm:.4f} | {100 * (fm - em) / em:+.0f}% | {es:.4f} | {fs:.4f} | "
                   f"{100 * (fs - es) / es:+.1f}% |")
    out += ["", "The fit's mean is off by tens of percent for small Λ (it overshoots by 50–90 % below Λ = 0.1) and "
            "by a few percent around Λ ≈ 1–10; the add-on uses the exact table everywhere.", ""]
    out += ["## Slope filtering: closed-form Gaussian moments against brute-force integration", "",
            "Σ = [[0.16, 0.05], [0.05, 0.04]], s̄ = (0.05, −0.1), φ_o = 1.1; brute force: 801² grid over the normal itself.", "",
            "| θ_o | mean (closed form) | mean (numerical) | cov (closed form) | cov (numerical) |", "|---|---|---|---|---|"]
    for deg in (0, 45, 70, 85, 90):
        g = pen.colormap.slope_filtering(math.radians(deg), 1.1, [0.05, -0.1], [0.16, 0.05, 0.04])
        n = pen.colormap.slope_filtering(math.radians(deg), 1.1, [0.05, -0.1], [0.16, 0.05, 0.04], method="numerical")
        fmt = lambda v: "(" + ", ".join(f"{x:.4f}" for x in v) + ")"  # noqa: E731
        out.append(f"| {deg}° | {fmt(g[0])} | {fmt(n[0])} | {fmt(g[1])} | {fmt(n[1])} |")
    out.append("")
    return out


NOTE = ('Penumbra\'s node group here is the octave filter with footprint taps (docs/colormap.md, "Octave filter"): '
        'each octave of the noise is evaluated at 16 taps (2 along the footprint ellipse\'s minor axis × 8 along its '
        'major axis) around the centre of the sample\'s pixel; their average is the octave\'s pixel mean (shrunk '
        'towards 0.5 where the taps alias), the taps\' spread is the local within-pixel variance, and the measured '
        'octave table adds the variance the taps cannot see. At 1 spp Cycles 4.5 shades at the pixel centre (measured: '
        'the shading position of two seeds lies within 0.2 % of a pixel of it), so the 1-spp result is a '
        'deterministic filtered image. The cost is 16 × (Detail + 1) Noise evaluations per shading '
        'point: the 1-spp filtered render takes about as long as the 16-spp plain one at this size. Above 1 spp the '
        'filtered material gets worse again: the pixel filter (Blackman-Harris, ±1.5 px) sends about a quarter of the '
        'samples outside their pixel, where they snap to the neighbour\'s centre and add that neighbour\'s already '
        'filtered value (a second blur); the material is meant for 1 spp.')


def bench_render():
    out = ["## Cycles: plane receding to the horizon", ""]
    folder = tempfile.mkdtemp(prefix="penumbra-colormap-render-")
    py = os.path.join(ROOT, ".venv", "bin", "python")
    log_path = os.path.join(folder, "render.log")
    # stdin from /dev/null and output to a file: the bpy module hung here with
    # an inherited stdin and piped output.
    with open(log_path, "w") as log:
        proc = subprocess.run([py, os.path.join(ROOT, "bench", "colormap_render.py"), "--", folder], cwd=ROOT,
                              stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        return out + ["render failed:", "```", open(log_path).read()[-3000:], "```", ""]
    data = json.load(open(os.path.join(folder, "render_results.json")))
    out += [f"{data['size'][0]}×{data['size'][1]}, Noise Texture (Scale 2, Detail 4, Roughness 0.5, Object coordinates) "
            f"through a sharp two-stop ColorRamp into an Emission shader, Blender {data['blender']}. Ground truth: "
            f"the plain ramp at {data['gt_spp']} spp ({data['gt_seconds']:.1f} s).", "",
            "| method | spp | RMSE vs ground truth | RMSE / plain ramp at same spp | render time (s) |",
            "|---|---|---|---|---|"]
    plain = {r["spp"]: r["rmse"] for r in data["runs"] if r["method"] == "plain"}
    names = {"plain": "plain ColorRamp", "mean": "ramp of the filtered mean C(f̄)", "penumbra": "Penumbra Filtered Ramp"}
    for r in data["runs"]:
        out.append(f"| {names[r['method']]} | {r['spp']} | {r['rmse']:.4f} | {r['rmse'] / plain[r['spp']]:.2f} | "
                   f"{r['seconds']:.2f} |")
    best = {r["method"]: r for r in data["runs"] if r["spp"] == 1}
    verdict = "met" if best["penumbra"]["rmse"] < plain[16] else "NOT met"
    out += ["", f"Goal \"Penumbra at 1 spp beats the plain ramp at 16 spp\": **{verdict}** "
            f"({best['penumbra']['rmse']:.4f} vs {plain[16]:.4f}).", "", NOTE, ""]
    os.makedirs(os.path.join(DOCS, "colormap"), exist_ok=True)
    for name in ["ground_truth"] + [f"{m}_{s}spp" for m in ("plain", "mean", "penumbra") for s in (1, 16)]:
        image = pen.image.read(os.path.join(folder, name + ".exr"))
        srgb = np.where(image <= 0.0031308, 12.92 * image, 1.055 * np.power(np.clip(image, 0, None), 1 / 2.4) - 0.055)
        pen.image.write_png16(os.path.join(DOCS, "colormap", name + ".png"), np.clip(srgb, 0, 1).astype(np.float32),
                              "sRGB")
    out += ["Pictures (sRGB): " + ", ".join(f"[{n}](colormap/{n}.png)" for n in
                                            ["ground_truth", "plain_1spp", "penumbra_1spp", "mean_1spp",
                                             "plain_16spp", "penumbra_16spp"]), ""]
    return out


def bench_footprint():
    out = ["## Footprint node against the true pixel footprint", ""]
    folder = tempfile.mkdtemp(prefix="penumbra-colormap-footprint-")
    py = os.path.join(ROOT, ".venv", "bin", "python")
    log_path = os.path.join(folder, "footprint.log")
    with open(log_path, "w") as log:
        proc = subprocess.run([py, os.path.join(ROOT, "bench", "colormap_footprint.py"), "--", folder], cwd=ROOT,
                              stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        return out + ["footprint measurement failed:", "```", open(log_path).read()[-3000:], "```", ""]
    data = json.load(open(os.path.join(folder, "footprint_results.json")))
    out += [f"`bench/colormap_footprint.py`, Blender {data['blender']}: a {data['size'][0]}×{data['size'][1]} camera "
            "1.2 above the plane z = 0 (yawed 8°), pitched from 30° (looking down) to 88° (the horizon in view). The node "
            "group's outputs are rendered at each pixel's centre; the truth is computed in Python from the camera: "
            "√area = square root of the area of the pixel's four corners projected onto the plane; major/minor = "
            "singular values of the projected pixel's midpoint differences. Centre column, every third row; "
            "θ = angle between the view ray and the normal.", "",
            "| camera | row | θ | true √area | node Footprint | ratio | true major | node Major | ratio | "
            "true minor | node Minor | ratio |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    worst = {}
    for cam in data["cameras"]:
        name = f"{'ortho' if cam['orthographic'] else 'persp'} {cam['pitch']:g}°"
        for r in cam["rows"]:
            ratios = [r["node_footprint"] / r["sqrt_area"], r["node_major"] / r["major"], r["node_minor"] / r["minor"]]
            out.append(f"| {name} | {r['row']} | {r['view_angle']:.1f}° | {r['sqrt_area']:.4g} | "
                       f"{r['node_footprint']:.4g} | {ratios[0]:.3f} | {r['major']:.4g} | {r['node_major']:.4g} | "
                       f"{ratios[1]:.3f} | {r['minor']:.4g} | {r['node_minor']:.4g} | {ratios[2]:.3f} |")
            band = "θ < 85°" if r["view_angle"] < 85 else ("85° ≤ θ < 89°" if r["view_angle"] < 89 else "θ ≥ 89°")
            worst[band] = max(worst.get(band, 0.0), max(abs(x - 1.0) for x in ratios))
    out += ["", "Largest relative error: " + ", ".join(f"{k}: {100 * v:.1f} %" for k, v in sorted(worst.items())) +
            ". The node is the first-order (Jacobian) footprint at the pixel centre; it is exact for a plane up to the "
            "projection's curvature across the pixel, which only matters for pixels that reach the horizon (there the "
            "far edge of the pixel projects much further than the centre's derivative predicts, and the node "
            "underestimates the major axis).", ""]
    return out


def main():
    global lines
    for section in (bench_build, bench_accuracy, bench_height, bench_footprint, bench_render):
        print(f"colormap benchmark: {section.__name__}", flush=True)
        lines += section()
    path = os.path.join(DOCS, "colormap-benchmark.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
