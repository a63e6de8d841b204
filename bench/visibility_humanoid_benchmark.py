#!/usr/bin/env python3
"""Visibility baker on the realistic character (issue #13 items 3 and 4), inside
the bpy module: the humanoid of examples/scenes/visibility_humanoid.py (CMU
motion capture, automatic weights, hands) baked at 128 rays, fitted with 2
lobes at SH order 4, and compared on held-out frames with Cycles' own AO bake
of the same frames (128 samples, denoising off), beside

  * the floor: a per-frame bake of the held-out frames at the same 128 rays;
  * the ceiling: the pose-ignoring model (the training frames' mean visibility).

Also, in the same run: bake + fit time against Cycles' time on the training
frames (alternated, with the load average beside each), where the bake's and
the fit's time goes, ways of casting the bake's rays against each other
(bench/cpp/visibility_bake_bench.cpp: single rays, fast or robust traversal,
coherent packets), the fit's cost as active joints and frames grow, and bytes
per vertex against error for the pruning tolerances. Then the run time at
production scale: the same character at ~100k vertices (detail 10), baked
and fitted as the operator does, its frame change against Blender's own
(bench/visibility_frame_change.py) with the model's held-out error beside it.
Writes docs/visibility-humanoid-benchmark.md,
docs/visibility/humanoid-benchmark.json and docs/visibility/humanoid-fit-cost.svg.

    .venv/bin/python bench/visibility_humanoid_benchmark.py [--quick | --frame-change | --held-out-frames]

--frame-change: only the ~100k-vertex run-time section, rewritten in place.
--held-out-frames: only the per-frame held-out error of both splits, rewritten in place.
"""

import json
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.paths import DOCS, ROOT, use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402
from penumbra.visibility import armature_data, bake, mesh_data  # noqa: E402
import visibility_humanoid  # noqa: E402
from bench.helpers import doc_section, pose_extrapolation, visibility_frame_change  # noqa: E402
from bench.helpers.cycles_ao import cycles_ao  # noqa: E402
from bench.helpers.log import log  # noqa: E402
from bench.helpers.svg_plot import figure  # noqa: E402
from bench.helpers.visibility_criteria import GOAL, frame_ao, held_out_errors, over_per_frame  # noqa: E402
from bench.helpers.visibility_training import baked_sh, bake_frames, model_sh  # noqa: E402

QUICK = "--quick" in sys.argv
FRAME_CHANGE_ONLY = "--frame-change" in sys.argv
HELD_OUT_FRAMES_ONLY = "--held-out-frames" in sys.argv
HELD_OUT_FRAMES_SECTION = "## Every held-out frame"
# The run time at production scale: ~100k vertices (2.5k with --quick).
FRAME_CHANGE_DETAIL = 0.25 if QUICK else 10.0
FRAME_CHANGE_SECTION = "## Frame change at production scale"
# 9.9k vertices at detail 1 (the mocap character had 9,264), 64
# frames of the capture at 24 fps: every 4th held out (16), 48 train.
DETAIL = 0.5 if QUICK else 1.0
FRAMES = 32 if QUICK else 64
HELD_OUT = list(range(4, FRAMES + 1, 4))
TRAIN = [f for f in range(1, FRAMES + 1) if f not in HELD_OUT]
RAYS, LOBES, ORDER, CYCLES_SAMPLES = 128, 2, 4, 128
PRUNE_TOLERANCES = [0.0, 0.003, 0.005, 0.01, 0.03, 0.1]
FEATURE_TOLERANCES = [0.0, 0.01, 0.03, 0.1]
# Bake + fit against Cycles: ROUNDS times a whole bake + fit of the training
# frames, each followed by Cycles on the next 1/ROUNDS of them, so that both
# sides see the same stretches of a shared machine's load.
ROUNDS = 2 if QUICK else 3
CASTING_FRAMES = 4 if QUICK else 8
CASTING_MODES = ["single:robust", "single", "coherent", "coherent:same"]
# Issue #27 item 7: every held-out frame within GOAL of its per-frame bake,
# for frames interleaved with training and for a contiguous block after it.
SPLITS = {"every 4th frame": HELD_OUT, f"the last {FRAMES // 4} frames": list(range(FRAMES - FRAMES // 4 + 1, FRAMES + 1))}


def new_humanoid(detail=DETAIL, frames=FRAMES):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.perf_counter()
    obj, rig = visibility_humanoid.build(detail=detail, frames=frames)
    seconds = time.perf_counter() - started
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    # Cycles' AO reaches world.light_settings.distance; Penumbra's rays are
    # unbounded: a distance far beyond the 1.5 m figure makes them the same.
    world = bpy.data.worlds.new("bench")
    world.light_settings.distance = 1000.0
    bpy.context.scene.world = world
    return obj, rig, seconds


def load():
    return round(os.getloadavg()[0], 2)


def fit(core, training, influence, **settings):
    started = time.perf_counter()
    model, report = core.visibility.fit_model(training, influence, lobes=LOBES, **settings)
    return model, report, time.perf_counter() - started


def timed_rounds(core, obj, influence):
    """ROUNDS × (bake + fit of TRAIN, then Cycles on the next slice of TRAIN).
    Returns the first round's training set, model and report, and the rounds."""
    rounds, first = [], None
    slices = [TRAIN[r::ROUNDS] for r in range(ROUNDS)]
    for r in range(ROUNDS):
        load_before = load()
        training, bake_seconds, _, job = bake_frames(obj, TRAIN, RAYS, ORDER)
        model, report, fit_seconds = fit(core, training, influence)
        load_between = load()
        _, cycles_seconds = cycles_ao(obj, slices[r], CYCLES_SAMPLES)
        rounds.append({"bake_seconds": bake_seconds, "fit_seconds": fit_seconds,
                       "fit_zh_seconds": report["seconds_zh_fit"], "fit_linear_seconds": report["seconds_linear"],
                       "bake_breakdown": dict(job.seconds, rays_cast=job.rays_cast), "cycles_frames": len(slices[r]),
                       "cycles_seconds": float(np.sum(cycles_seconds)),
                       "load": [load_before, load_between, load()]})
        log("round", r, rounds[-1])
        if first is None:
            first = (training, model, report)
    return first, rounds


def accuracy(core, obj, influence, results):
    """The model, the floor and the ceiling against Cycles on the held-out frames; bake + fit vs Cycles' time."""
    (training, model, report), rounds = timed_rounds(core, obj, influence)
    held_out, held_out_seconds, _, _ = bake_frames(obj, HELD_OUT, RAYS, ORDER)
    cycles_held, cycles_held_seconds = cycles_ao(obj, HELD_OUT, CYCLES_SAMPLES)
    errors = held_out_errors(core, model_sh(model, held_out), training, held_out, cycles_held)
    cycles_seconds = sum(r["cycles_seconds"] for r in rounds)
    penumbra_seconds = [r["bake_seconds"] + r["fit_seconds"] for r in rounds]
    mean = {key: float(np.mean([r[key] for r in rounds]))
            for key in ("bake_seconds", "fit_seconds", "fit_zh_seconds", "fit_linear_seconds")}
    breakdown = {key: float(np.mean([r["bake_breakdown"][key] for r in rounds])) for key in rounds[0]["bake_breakdown"]}
    results["accuracy"] = {
        "active_joints": list(model.joints), **mean, "rounds": rounds,
        "held_out_bake_seconds": held_out_seconds, "bake_breakdown": breakdown,
        "cycles_training_seconds": cycles_seconds, "cycles_held_out_seconds": float(np.sum(cycles_held_seconds)),
        "ratio_bake_fit_over_cycles": float(np.mean(penumbra_seconds)) / cycles_seconds,
        # Each round's bake + fit against its own Cycles slice scaled to every training frame.
        "round_ratios": [p / (r["cycles_seconds"] * len(TRAIN) / r["cycles_frames"])
                         for p, r in zip(penumbra_seconds, rounds)],
        "errors_vs_cycles": errors,
        "ratio_model_over_per_frame": over_per_frame(errors),
        "model_bytes": report["model_bytes"], "dense_bytes": report["dense_bytes"],
        "constant_vertices": report["constant_vertices"], "ridge_relative": report["ridge_relative"],
        "holdout_ao": report["model_holdout"]["ao_mean_abs"], "mean_cycles_ao": float(cycles_held.mean()),
    }
    log("accuracy:", {k: v for k, v in results["accuracy"].items() if k not in ("active_joints", "rounds")})
    return training, held_out, cycles_held


def held_out_frames(core, obj, influence):
    """Per split (SPLITS): the model fitted on the other frames (every choice
    made by the fit on those alone) against Cycles on each held-out frame,
    over the per-frame bake's error on that frame, with the pose-ignoring
    model's beside it. One bake of every frame, Cycles once per held-out frame."""
    everything = bake_frames(obj, list(range(1, FRAMES + 1)), RAYS, ORDER).training
    numbers = [int(f) for f in everything.frame_numbers]
    cycles_frames = sorted(set().union(*SPLITS.values()))
    cycles_all, _ = cycles_ao(obj, cycles_frames, CYCLES_SAMPLES)
    out = []
    for name, held in SPLITS.items():
        training = everything.subset([i for i, f in enumerate(numbers) if f not in held])
        held_set = everything.subset([i for i, f in enumerate(numbers) if f in held])
        model, report, seconds = fit(core, training, influence)
        reference = cycles_all[:, [cycles_frames.index(f) for f in held]]
        truth, mean = frame_ao(core, baked_sh(held_set)), frame_ao(core, baked_sh(training).mean(axis=0)[None])
        model_error = np.abs(frame_ao(core, model_sh(model, held_set)) - reference).mean(axis=0)
        bake_error = np.abs(truth - reference).mean(axis=0)
        ignoring_error = np.abs(mean - reference).mean(axis=0)
        ratios = model_error / bake_error
        # How new each held-out pose is: its largest joint angle from the
        # nearest training pose (over the model's joints).
        joints = [everything.bone_names.index(j) for j in model.joints]
        rotations = np.stack([everything.bone_rotations(i)[joints] for i in range(len(everything))])
        train_rows = [i for i, f in enumerate(numbers) if f not in held]
        novelty = []
        for f in held:
            cos = (np.einsum("tjik,jik->tj", rotations[train_rows], rotations[numbers.index(f)]) - 1) / 2
            novelty.append(float(np.degrees(np.arccos(np.clip(cos, -1, 1))).max(axis=1).min()))
        held_rows = [numbers.index(f) for f in held]
        alternatives = pose_extrapolation.alternatives(
            core, model, rotations[train_rows].astype(np.float64), rotations[held_rows].astype(np.float64),
            baked_sh(training), reference, bake_error)
        log("held-out frames, alternatives:", alternatives)
        out.append({"split": name, "frames": held, "training_frames": len(training),
                    "ratios": ratios.tolist(), "novelty_degrees": novelty, "pose_ignoring_ratios": (ignoring_error / bake_error).tolist(),
                    "mean_ratio": float(model_error.mean() / bake_error.mean()), "worst_ratio": float(ratios.max()),
                    "worst_frame": held[int(ratios.argmax())], "ridge_relative": report["ridge_relative"],
                    "bytes_per_vertex": report["model_bytes"] / training.vertex_count, "fit_seconds": seconds,
                    "alternatives": alternatives})
        log("held-out frames:", out[-1])
    return out


def held_out_frames_lines(rows, alone=False):
    """The "Every held-out frame" section (`alone`: written by --held-out-frames)."""
    lines = [HELD_OUT_FRAMES_SECTION, "",
             "Issue #27 item 7. Per held-out frame: the model's mean |ΔAO| against Cycles over the per-frame bake's "
             "on that frame (the floor); goal: every frame within "
             f"{GOAL:g}×. Two splits of the {FRAMES} frames: the one above (every 4th frame held out, between "
             "training frames) and a contiguous block after the training frames (new motion). Every choice of "
             "the fit (active joints, feature directions, ridge, pruning, constants) is made on the training "
             "frames alone (the ridge on every 4th of them). `mean` is the mean error over the frames' mean; the "
             "pose-ignoring model (the training frames' mean) is the ceiling. Per frame, in brackets: how new the "
             "pose is, its largest joint angle from the nearest training pose. Run alone: `.venv/bin/python "
             "bench/visibility_humanoid_benchmark.py --held-out-frames`."
             + (" This section was rewritten alone: the others are from the last full run, before the fit pruned "
                "the stored model on its own weights (CHANGELOG)." if alone else ""), "",
             "| held out | training frames | mean | worst frame | worst | frames past the goal | pose-ignoring: mean of frames | ρ | bytes / vertex | goal |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for x in rows:
        past = sum(r > GOAL for r in x["ratios"])
        lines.append(f"| {x['split']} | {x['training_frames']} | {x['mean_ratio']:.2f} | {x['worst_frame']} | "
                     f"{x['worst_ratio']:.2f} | {past} of {len(x['ratios'])} | "
                     f"{float(np.mean(x['pose_ignoring_ratios'])):.2f} | {x['ridge_relative']:.2g} | "
                     f"{x['bytes_per_vertex']:.0f} | {verdict(x['worst_ratio'] <= GOAL)} |")
    lines.append("")
    for x in rows:
        lines.append(f"Per frame, {x['split']}: " + ", ".join(
            f"{f} {r:.2f} ({a:.0f}°)" for f, r, a in zip(x["frames"], x["ratios"], x["novelty_degrees"])) + ".")
        lines.append("")
    lines += alternatives_lines(rows)
    lines += ["What was tried, outside this benchmark on the same bake (2026-11-29, numbers as worst frame, every "
              "4th / last 16): the ridge forced from ρ = 1e-5 to 0.3 (best 1.69 at the chosen 0.0018 / 2.82 at "
              "0.01; a larger ρ raises every frame of the interleaved split); a ridge per vertex chosen by its "
              "own error on every 4th training frame (1.66 / 3.22); rotation vectors instead of R − I (1.76 / "
              "3.13); feature tolerance 0.3 (1.74 / 2.97); joint tolerance 10° (1.69 / 2.88); no pruning "
              "(1.66 / 3.11); pruning tolerance 0.03 (2.02 / 2.96); axis prior 0.1 and 10 (1.78 / 2.91, "
              "1.69 / 2.90); 3 lobes (1.74 / 2.85). None meets the goal. The lobes are not the limit: fitted on "
              "the held-out frames themselves (in sample) the model is within 1.02× of the per-frame bake on "
              "every frame of both splits. Even a ridge per vertex chosen on the held-out frames (an oracle the "
              "fit may not use) leaves the last 16 frames at 2.59. In the last 16 frames the error grows with how far the held-out "
              "pose is from every training pose, as a linear model's extrapolation does.", "",
              "Keeping the model inside its training poses does not help either (the table above; also tried on "
              "the same bake, worst frame every 4th / last 16: a soft clamp, tanh-shaped beyond the range with "
              "0.1 to 0.5 of the range's width, 1.69 / 2.85 to 2.88; the hard clamp widened by 0.1 of the range, "
              "1.69 / 2.86; each vertex's lobe parameters clamped to their range over the training poses, 1.71 / "
              "2.86, or their bands alone, 1.71 / 2.86; the pose moved all the way to the nearest training pose, "
              "1.97 / 3.34, and that frame's own bake, 2.01 / 3.59). The last 16 frames do leave the training "
              "range: 26 % of their joint coordinates (along the principal directions each joint moves along) lie outside it, "
              "by a median 0.39 of the range's width and up to 120× on a direction the training frames barely "
              "moved; their nearest training pose is 0.17 to 2.0 away in R − I (Frobenius, all joints), where "
              "training poses are a median 0.44 from each other. Whether the model follows that motion or is "
              "held back from it, it has no data on how the visibility changes along it: clamped, shrunk or "
              "blended, no way moves the block's mean or worst frame by more than 3 %, nor the interleaved "
              "split's by more than 6 %. What the block split needs is training "
              "frames that cover the motion (bake the range the shot uses), not a different treatment of the "
              "same 48 frames. The interleaved split's 3 frames past 1.5× (1.60, 1.61, 1.69) are poses 11° "
              "to 18° from their nearest training pose; the clamp takes one of them under (2 of 16 past) and "
              "raises the worst.", "",
              "Nor do two other forms of the model, fitted in numpy on the same training frames' ZH lobes "
              "(`fit_zh_lobes` from each vertex's mean, as the fit does) with ρ chosen on every 4th training "
              "frame (worst frame every 4th / last 16): each vertex's ridge over only the joints whose bone passes "
              "within 0.6, 0.4 or 0.25 m of it at rest (8.2, 5.8 and 4.2 joints per vertex instead of 24) gives "
              "1.78 / 3.06, 1.86 / 3.23 and 2.10 / 3.19, against 1.66 / 3.11 for the same numpy ridge over every "
              "joint; a model linear in the SH coefficients themselves instead of lobe parameters gives mean 1.16, "
              "worst 1.65 / mean 2.05, worst 3.32. Interpolating that ridge's residuals over the training poses "
              "on top (a Gaussian kernel over their R − I, as pose-space deformation does for shapes; its width "
              "and noise chosen on every 4th training frame) brings the interleaved split to mean 1.18, worst "
              "1.56 (from 1.23, 1.66) and leaves the block at mean 2.04, worst 3.11, for a model that would also "
              "store every training frame's residual per vertex.", "",
              "Nor does baking poses the motion did not hold (2026-11-29, the same bake and fit; poses made from "
              "the split's training frames alone, keyed after the shot and baked with them; worst frame every 4th "
              "/ last 16, against 1.69 / 2.88 in the same run): each joint's rotation taken from an independent "
              "training frame, no rotation new (48 poses: 2.24 / 2.94; 16: 2.23 / 2.85); each joint pushed 1 to "
              "2 times its distance from its mean training rotation (48: 2.91 / 3.27; 16: 2.58 / 2.96); each "
              "training pose's joints turned about random axes by up to 5°, 15° or 30° (16 poses: 2.32 / 2.89; "
              "48: 2.90 / 3.28 and 3.21 / 3.90). Every kind makes both splits worse, even joints only "
              "recombined: the visibility is not a sum of one term per joint over poses the motion does not "
              "hold, and a linear model fits the real motion through its joints' correlations. Covering more of "
              "the pose space costs more on the shot's own poses than it gains on new ones.", ""]
    return lines


def alternatives_lines(rows):
    """Ways of keeping the model from extrapolating (bench/helpers/pose_extrapolation.py), per split."""
    if not all("alternatives" in x for x in rows):
        return []
    lines = ["Ways of keeping the model inside what it was trained on, applied to the same fitted model in this "
             "run, each using the training frames alone (`bench/helpers/pose_extrapolation.py`; the features "
             "moved are R − I, evaluated as I + φ'). Per split: mean, worst frame, frames past the goal.", "",
             "| way | " + " | ".join(x["split"] for x in rows) + " |", "|---|" + "---:|" * len(rows)]
    for k, way in enumerate(rows[0]["alternatives"]):
        lines.append(f"| {way['name']} | " + " | ".join(
            f"{x['alternatives'][k]['mean']:.2f}, {x['alternatives'][k]['worst']:.2f}, {x['alternatives'][k]['past']} "
            f"of {len(x['ratios'])}" for x in rows) + " |")
    return lines + [""]


def run_held_out_frames_only():
    """--held-out-frames: only that section, rewritten in place (and in the JSON)."""
    penumbra.register()
    core = native.require()
    obj, rig, _ = new_humanoid()
    rows = held_out_frames(core, obj, armature_data.bone_influence(obj, rig))
    penumbra.unregister()
    doc_section.write_section(os.path.join(DOCS, "visibility-humanoid-benchmark.md"), HELD_OUT_FRAMES_SECTION,
                              "\n".join(held_out_frames_lines(rows, alone=True)), after="## Held-out frames against Cycles")
    doc_section.update_json(os.path.join(DOCS, "visibility", "humanoid-benchmark.json"), "held_out_frames", rows)
    log("wrote the held-out frames section")


def casting(obj, results):
    """Ways of casting the bake's rays on the first CASTING_FRAMES training frames, in their own process
    (bench/cpp/visibility_bake_bench.cpp): CPU seconds, and whether each bakes the first mode's visibility."""
    import subprocess
    import tempfile
    job = bake.BakeJob(bpy.context, obj, TRAIN[0], TRAIN[0], 1, RAYS, 1, ORDER, None)
    with tempfile.TemporaryDirectory() as folder:
        np.asarray(job.neighbours, np.uint32).tofile(os.path.join(folder, "neighbours.u32"))
        for k, frame in enumerate(TRAIN[:CASTING_FRAMES]):
            bpy.context.scene.frame_set(frame)
            mesh = mesh_data.evaluated_mesh(obj, bpy.context.evaluated_depsgraph_get())
            for kind, array, dtype in (("p", mesh.positions, np.float32), ("n", mesh.normals, np.float32),
                                       ("t", mesh.triangles, np.uint32)):
                np.ascontiguousarray(array, dtype).tofile(os.path.join(folder, f"{kind}{k:03d}.{'u32' if kind == 't' else 'f32'}"))
        job.restore_frame()
        exe = os.path.join(ROOT, "build", "bench", "penumbra_visibility_bake_bench")
        load_before = load()
        out = subprocess.run([exe, folder, str(CASTING_FRAMES), str(RAYS), "2", *CASTING_MODES],
                             capture_output=True, text=True, check=True).stdout
    runs = [json.loads(line) for line in out.splitlines() if line.strip()]
    results["casting"] = {"frames": CASTING_FRAMES, "runs": runs, "load": [load_before, load()]}
    log("casting:", runs)


def fit_cost(core, training, influence, active, results):
    """Fit seconds as active joints grow (the others marked as deforming nothing) and as frames grow."""
    rows = []
    counts = sorted({max(1, len(active) // 4), len(active) // 2, 3 * len(active) // 4, len(active)})
    for n in counts:
        keep = set(active[:n])
        limited = [x if name in keep else (False, False) for name, x in zip(training.bone_names, influence)]
        model, report, seconds = fit(core, training, limited)
        rows.append({"joints": len(model.joints), "frames": len(training), "seconds": seconds,
                     "zh_seconds": report["seconds_zh_fit"], "linear_seconds": report["seconds_linear"]})
        log("fit cost:", rows[-1])
    for n in sorted({len(training) // 4, len(training) // 2}):
        subset = training.subset(list(range(n)))
        model, report, seconds = fit(core, subset, influence)
        rows.append({"joints": len(model.joints), "frames": n, "seconds": seconds,
                     "zh_seconds": report["seconds_zh_fit"], "linear_seconds": report["seconds_linear"]})
        log("fit cost:", rows[-1])
    results["fit_cost"] = rows


def size_against_error(core, training, held_out, cycles_held, influence, results):
    """Bytes per vertex against held-out error for the per-vertex pruning
    tolerance, and for the joints' feature directions (FitSettings::
    feature_tolerance) at the default pruning."""
    truth = baked_sh(held_out)
    truth_ao = frame_ao(core, truth)

    def row(**settings):
        model, report, seconds = fit(core, training, influence, **settings)
        predicted = model_sh(model, held_out)
        ao = frame_ao(core, predicted)
        sh_rms = float(np.sqrt(((predicted - truth) ** 2).sum(axis=-1) / (4 * np.pi)).mean())
        x = {**settings, "bytes_per_vertex": report["model_bytes"] / training.vertex_count,
             "model_bytes": report["model_bytes"], "constant_vertices": report["constant_vertices"],
             "joints_per_vertex": float(model.joints_per_vertex().mean()),
             "directions_per_vertex": report["stored_directions"] / training.vertex_count,
             "joint_directions": sum(j["feature_directions"] for j in report["joints"] if j["active"]),
             "held_out_sh_rms": sh_rms, "held_out_ao_vs_bake": float(np.abs(ao - truth_ao).mean()),
             "held_out_ao_vs_cycles": float(np.abs(ao - cycles_held).mean()), "fit_seconds": seconds}
        log("size:", x)
        return x

    results["size"] = [row(prune_tolerance=t, constant_tolerance=t) for t in PRUNE_TOLERANCES]
    results["directions"] = [row(feature_tolerance=t) for t in FEATURE_TOLERANCES]


def plot(results, path):
    rows = results["fit_cost"]
    frames_all = results["training_frames"]
    by_joints = sorted((r for r in rows if r["frames"] == frames_all), key=lambda r: r["joints"])
    by_frames = sorted([r for r in rows if r["frames"] != frames_all] + [by_joints[-1]], key=lambda r: r["frames"])
    panels = []
    for title, xlabel, key, series_rows in (("fit s vs active joints", "active joints", "joints", by_joints),
                                            ("fit s vs training frames", "frames", "frames", by_frames)):
        xs = [r[key] for r in series_rows]
        panels.append({"title": title, "xlabel": xlabel, "xs": xs, "series": [
            {"name": name, "xs": xs, "ys": [r[field] for r in series_rows], "colour": colour}
            for name, field, colour in (("whole fit", "seconds", "#222222"), ("ZH lobes", "zh_seconds", "#1f77b4"),
                                        ("linear model", "linear_seconds", "#d62728"))]})
    figure(panels, path, caption=f"Fit cost on the humanoid ({results['vertices']} vertices, {RAYS} rays, "
                                 f"{LOBES} lobes, order {ORDER})")


def main():
    penumbra.register()
    core = native.require()
    results = {"blender": bpy.app.version_string, "cores": os.cpu_count(), "quick": QUICK}
    obj, rig, build_seconds = new_humanoid()
    results.update(vertices=len(obj.data.vertices), bones=len(rig.data.bones), build_seconds=build_seconds,
                   training_frames=len(TRAIN), held_out_frames=len(HELD_OUT), detail=DETAIL, frames=FRAMES)
    log(f"humanoid: {results['vertices']} vertices, {results['bones']} bones, built in {build_seconds:.1f} s; "
        f"{len(TRAIN)} training + {len(HELD_OUT)} held-out frames")
    influence = armature_data.bone_influence(obj, rig)
    training, held_out, cycles_held = accuracy(core, obj, influence, results)
    results["held_out_frames"] = held_out_frames(core, obj, influence)
    casting(obj, results)
    fit_cost(core, training, influence, results["accuracy"]["active_joints"], results)
    size_against_error(core, training, held_out, cycles_held, influence, results)
    frame_change_at_scale(results)
    penumbra.unregister()

    folder = os.path.join(DOCS, "visibility")
    with open(os.path.join(folder, "humanoid-benchmark.json.tmp"), "w") as f:
        json.dump(results, f, indent=1)
    os.replace(os.path.join(folder, "humanoid-benchmark.json.tmp"), os.path.join(folder, "humanoid-benchmark.json"))
    plot(results, os.path.join(folder, "humanoid-fit-cost.svg"))
    write_markdown(results)


def frame_change_at_scale(results):
    """The humanoid at FRAME_CHANGE_DETAIL baked over every frame by the operator
    (RAYS rays, LOBES lobes, the defaults otherwise: what a user gets), then
    its frame change against Blender's own, alternated over the frames."""
    obj, rig, build_seconds = new_humanoid(FRAME_CHANGE_DETAIL)
    bpy.context.scene.world.use_nodes = True   # its grey background lights the shading
    path = os.path.join(bpy.app.tempdir or "/tmp", "bench_humanoid_frame_change.pzh")
    started = time.perf_counter()
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=FRAMES, frame_step=1, rays=RAYS, lobes=LOBES,
                                              filepath=path)
    bake_seconds = time.perf_counter() - started
    if result != {"FINISHED"}:
        raise RuntimeError(f"the bake at {FRAME_CHANGE_DETAIL} did not finish: {result}")
    costs = visibility_frame_change.frame_change_costs(obj, list(range(1, FRAMES + 1)))
    summary = dict(native.require().visibility.PoseModel.load(path).summary)
    costs.update(build_seconds=build_seconds, bake_fit_seconds=bake_seconds, model_bytes=os.path.getsize(path),
                 holdout_ao=summary["holdout_ao_mean_abs"], holdout_frames=int(summary["holdout_frames"]),
                 training_frames=int(summary["frames"]), active_joints=int(summary["active_joints"]),
                 constant_vertices=int(summary["constant_vertices"]))
    log(visibility_frame_change.summary(costs))
    log("at scale:", {k: costs[k] for k in ("build_seconds", "bake_fit_seconds", "model_bytes", "holdout_ao")})
    results["frame_change"] = costs
    return costs


def frame_change_lines(r):
    x = r["frame_change"]
    a = r.get("accuracy")
    lines = [FRAME_CHANGE_SECTION, "",
             f"The same humanoid at detail {FRAME_CHANGE_DETAIL:g}: {x['vertices']} vertices (its weights made at "
             "10k vertices and subdivided, as a base mesh's painted weights are), baked by "
             f"`bpy.ops.penumbra.bake_visibility` over all {x['training_frames']} frames at {RAYS} rays, {LOBES} lobes, "
             f"order {ORDER} and every other setting at its default ({x['active_joints']} active joints, "
             f"{x['constant_vertices']} constant vertices, model {x['model_bytes'] / 1e6:.1f} MB; bake + fit "
             f"{x['bake_fit_seconds']:.0f} s). " + visibility_frame_change.DESCRIPTION + " Run alone: `.venv/bin/python "
             "bench/visibility_humanoid_benchmark.py --frame-change`.", ""]
    lines += visibility_frame_change.table([x], "held-out mean abs ΔAO", lambda x: f"{x['holdout_ao']:.4f}")
    lines += ["", f"Goal (issue #13): the whole frame change at ~100k vertices at most 4.5× Blender's own. Measured: "
              f"**{x['ratio']:.2f}×** at {x['vertices']} vertices — {verdict(x['ratio'] <= 4.5)}. "
              f"{x['repeats']} frame changes each way; load average {x['load_average']:.1f} (2 cores).", "",
              "Error beside it: the held-out mean |ΔAO| is the stored model's recipe (the same settings, fitted "
              f"without every 4th frame, {x['holdout_frames']} of them) against the per-frame bake of those frames "
              "at the same rays (the fit report's `model_holdout`)."
              + (f" On the 10k-vertex character above the same error is {a['holdout_ao']:.4f} against the bake and "
                 f"{a['errors_vs_cycles']['model']['mean_abs']:.4f} against Cycles' AO bake."
                 if a else ""),
              "", visibility_frame_change.accuracy_line([x])]
    return lines


def run_frame_change_only():
    """--frame-change: only the production-scale section, rewritten in place."""
    penumbra.register()
    results = {}
    frame_change_at_scale(results)
    penumbra.unregister()
    path = os.path.join(DOCS, "visibility-humanoid-benchmark.md")
    json_path = os.path.join(DOCS, "visibility", "humanoid-benchmark.json")
    stored = json.load(open(json_path)) if os.path.exists(json_path) else {}
    stored["frame_change"] = results["frame_change"]
    doc_section.write_section(path, FRAME_CHANGE_SECTION, "\n".join(frame_change_lines(stored)) + "\n")
    with open(json_path + ".tmp", "w") as f:
        json.dump(stored, f, indent=1)
    os.replace(json_path + ".tmp", json_path)
    log("wrote the run-time section of", path)


def verdict(ok):
    return "**met**" if ok else "**not met**"


def write_markdown(r):
    a = r["accuracy"]
    e = a["errors_vs_cycles"]
    lines = ["# Visibility baker on the realistic character", "",
             f"Generated by `bench/visibility_humanoid_benchmark.py`{' --quick' if r['quick'] else ''} in Blender "
             f"{r['blender']} (bpy module), {r['cores']} cores. The character is "
             f"`examples/scenes/visibility_humanoid.py` at detail {r['detail']:g}: {r['vertices']} vertices, "
             f"{r['bones']} bones, automatic (bone-heat) weights, hands with finger bones, driven by CMU motion "
             f"capture 01_01 from Debian's assimp-testmodels ({r['frames']} frames at 24 fps from capture frame "
             f"{visibility_humanoid.DEFAULT_START}). Every 4th frame is held out ({r['held_out_frames']} frames, never "
             f"baked into the model); the other {r['training_frames']} train it. Bake at {RAYS} rays, "
             f"{LOBES} lobes, SH order {ORDER}; {len(a['active_joints'])} active joints. Cycles: "
             f"`bpy.ops.object.bake(type='AO')` to a point colour attribute, {CYCLES_SAMPLES} samples, denoising "
             "off, CPU, in the same run. Timings share a 2-core machine with other jobs; compare ratios within "
             "this run.", "",
             "## Held-out frames against Cycles' AO bake", "",
             "AO is the diffuse shade under a uniform unit World (`ambient_occlusion` of the SH visibility); "
             "Cycles' AO bake is the reference. Mean |ΔAO| and correlation over every (vertex, held-out frame).", "",
             "| what | mean abs difference vs Cycles | correlation |", "|---|---:|---:|",
             f"| pose model (the stored model, trained on the {r['training_frames']} frames) | "
             f"{e['model']['mean_abs']:.4f} | {e['model']['correlation']:.4f} |",
             f"| per-frame bake of the held-out frames at {RAYS} rays (the floor) | "
             f"{e['per_frame']['mean_abs']:.4f} | {e['per_frame']['correlation']:.4f} |",
             f"| pose-ignoring model: mean of the training frames (the ceiling) | "
             f"{e['pose_ignoring']['mean_abs']:.4f} | {e['pose_ignoring']['correlation']:.4f} |",
             "", f"Pose model against the per-frame bake itself: mean |ΔAO| "
             f"{e['model_vs_per_frame']['mean_abs']:.4f}, correlation {e['model_vs_per_frame']['correlation']:.4f}. "
             f"Mean Cycles AO {a['mean_cycles_ao']:.3f}.", "",
             f"Held-out error / per-frame bake's: **{a['ratio_model_over_per_frame']:.2f}** (goal ≤ {GOAL:g}: "
             f"{verdict(a['ratio_model_over_per_frame'] <= GOAL)}).", "",
             *held_out_frames_lines(r["held_out_frames"]),
             "## Bake + fit against Cycles' time", ""] + timing_lines(r) + casting_lines(r)
    lines += fit_cost_lines(r) + size_lines(r) + [""] + frame_change_lines(r)
    path = os.path.join(DOCS, "visibility-humanoid-benchmark.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)
    log("wrote", path)


def timing_lines(r):
    a = r["accuracy"]
    b = a["bake_breakdown"]
    lines = [f"{ROUNDS} rounds, alternated: Penumbra's bake of the {r['training_frames']} training frames as the "
             "operator bakes them, then the fit, then Cycles' AO bake of the next slice of the same frames (one in "
             f"{ROUNDS}, interleaved); the ratio is the mean bake + fit over Cycles' time for all of them. "
             "1-minute load average before the bake, before Cycles and after.", "",
             "| round | bake s | fit s (ZH, linear) | Cycles s (frames) | round's ratio | load |",
             "|---:|---:|---:|---:|---:|---|"]
    for k, (x, ratio) in enumerate(zip(a["rounds"], a["round_ratios"])):
        lines.append(f"| {k + 1} | {x['bake_seconds']:.1f} | {x['fit_seconds']:.1f} ({x['fit_zh_seconds']:.1f}, "
                     f"{x['fit_linear_seconds']:.1f}) | {x['cycles_seconds']:.1f} ({x['cycles_frames']}) | "
                     f"{ratio:.3f} | {', '.join(f'{v:.1f}' for v in x['load'])} |")
    lines += ["", f"Mean bake {a['bake_seconds']:.1f} s (posing {b['pose']:.1f} s, reading the mesh {b['read']:.1f} s, "
              f"C++ setup {b['setup']:.1f} s, Embree scene {b['build']:.1f} s, casting and projection "
              f"{b['cast']:.1f} s, {b['rays_cast'] / max(b['cast'], 1e-9) / 1e6:.1f} M rays/s while casting), "
              f"fit {a['fit_seconds']:.1f} s (ZH lobes {a['fit_zh_seconds']:.1f} s, linear model "
              f"{a['fit_linear_seconds']:.1f} s). Cycles' AO bake of the same frames: "
              f"{a['cycles_training_seconds']:.1f} s. Ratio **{a['ratio_bake_fit_over_cycles']:.3f}×** "
              f"(goal ≤ 0.05: {verdict(a['ratio_bake_fit_over_cycles'] <= 0.05)}), held-out error beside it: "
              f"{a['errors_vs_cycles']['model']['mean_abs']:.4f} mean |ΔAO| against Cycles, "
              f"{a['ratio_model_over_per_frame']:.2f}× the per-frame bake's.", ""]
    return lines


def casting_lines(r):
    c = r["casting"]
    what = {"single:robust": "single rays (rtcOccluded1), robust traversal (the bake before)",
            "single": "single rays, fast traversal (the bake's default)",
            "coherent": "coherent packets: one ray of each of 16 neighbouring vertices (Morton order), rays paired "
                        "by direction",
            "coherent:same": "coherent packets, every lane given its leader's direction (the coherence bound; "
                             "wrong visibility)"}
    lines = ["### Casting the rays", "",
             f"`bench/cpp/visibility_bake_bench.cpp` on the first {c['frames']} training frames, in its own process, "
             "modes alternated twice; CPU seconds (steadier than wall time on a shared machine, load "
             f"{c['load'][0]:.1f} → {c['load'][1]:.1f}) and the (vertex, frame) pairs whose SH differs from the "
             "first mode's.", "",
             "| casting | CPU s (runs) | differing (vertex, frame) pairs |", "|---|---:|---:|"]
    for mode in CASTING_MODES:
        runs = [x for x in c["runs"] if x["mode"] == mode]
        cpu = " / ".join(f"{x['cpu_seconds']:.2f}" for x in runs)
        lines.append(f"| {what[mode]} | {cpu} | {runs[-1]['vertex_frames_differing']} |")
    return lines + [""]


def fit_cost_lines(r):
    lines = ["## The fit's cost as joints and frames grow", "",
             "The same training set fitted with fewer active joints (the others marked as deforming nothing) and "
             "on its first frames only.", "",
             "| active joints | frames | fit s | ZH lobes s | linear model s |", "|---:|---:|---:|---:|---:|"]
    for x in r["fit_cost"]:
        lines.append(f"| {x['joints']} | {x['frames']} | {x['seconds']:.2f} | {x['zh_seconds']:.2f} | "
                     f"{x['linear_seconds']:.2f} |")
    return lines + ["", "![fit cost](visibility/humanoid-fit-cost.svg)", ""]


def size_lines(r):
    lines = ["## Model size against error", "",
             "Per-vertex pruning by measured contribution: a vertex whose lobe parameters vary by less than the "
             "tolerance (RMS over the training frames) stores a constant; for the others, joint directions whose "
             "contribution (their part of the prediction over the training frames) is smallest are dropped, a "
             "joint's last direction first, while the dropped part stays under the tolerance. Here one tolerance "
             "sets both (0.01 is the default). Errors on the held-out frames: against the per-frame bake (sh RMS "
             "over the sphere, AO) and against Cycles. The weights are binary16 (docs/visibility.md, \"Model "
             "files\").", "",
             "| tolerance | bytes / vertex | MB | constant vertices | joints / vertex | directions / vertex | "
             "held-out sh | held-out AO vs bake | held-out AO vs Cycles |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for x in r["size"]:
        lines.append(f"| {x['prune_tolerance']:g} | {x['bytes_per_vertex']:.0f} | {x['model_bytes'] / 1e6:.2f} | "
                     f"{x['constant_vertices']} | {x['joints_per_vertex']:.2f} | {x['directions_per_vertex']:.2f} | "
                     f"{x['held_out_sh_rms']:.4f} | {x['held_out_ao_vs_bake']:.4f} | {x['held_out_ao_vs_cycles']:.4f} |")
    lines += ["", "The joints' feature directions (`feature_tolerance`: a direction is kept when its singular value "
              "over the training frames is at least that fraction of the joint's largest; 0.03 is the default), "
              "at the default pruning:", "",
              "| feature tolerance | directions (all joints) | bytes / vertex | directions / vertex | held-out sh | "
              "held-out AO vs bake | held-out AO vs Cycles |", "|---:|---:|---:|---:|---:|---:|---:|"]
    for x in r["directions"]:
        lines.append(f"| {x['feature_tolerance']:g} | {x['joint_directions']} | {x['bytes_per_vertex']:.0f} | "
                     f"{x['directions_per_vertex']:.2f} | {x['held_out_sh_rms']:.4f} | {x['held_out_ao_vs_bake']:.4f} | "
                     f"{x['held_out_ao_vs_cycles']:.4f} |")
    return lines + [""]


if __name__ == "__main__":
    if FRAME_CHANGE_ONLY:
        run_frame_change_only()
    elif HELD_OUT_FRAMES_ONLY:
        run_held_out_frames_only()
    else:
        main()
