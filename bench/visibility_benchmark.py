#!/usr/bin/env python3
"""Visibility baker benchmark (run by `make bench`, inside the bpy module):
accuracy of the ZH fit and of the linear pose model for lobes 1–4 and rays
64–1024 on the procedural character, the paper's figures 3 and 5 on this
data, bake throughput against raw Embree on the same mesh, the whole bake +
fit against Cycles' own AO bake of the same frames, and the run-time cost per
frame at 10k and 100k vertices. Writes docs/visibility-benchmark.md,
docs/visibility/benchmark.json and docs/visibility/errors.svg.

    .venv/bin/python bench/visibility_benchmark.py [--quick | --frame-change | --tail]

--tail: only the tail of pruning (its section rewritten in place).
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
import visibility_character  # noqa: E402
from bench.helpers import doc_section, visibility_frame_change  # noqa: E402
from bench.helpers.cycles_ao import cycles_ao  # noqa: E402
from bench.helpers.log import log  # noqa: E402
from bench.helpers.svg_plot import svg_plot  # noqa: E402
from bench.helpers.visibility_training import baked_sh, bake_frames, model_sh  # noqa: E402

QUICK = "--quick" in sys.argv
FRAME_CHANGE_ONLY = "--frame-change" in sys.argv  # only the run-time section (docs rewritten in place)
TAIL_ONLY = "--tail" in sys.argv
FRAMES = 48
TRAIN = list(range(2, FRAMES + 1, 2))     # 24 training poses
UNSEEN = list(range(1, FRAMES, 4))        # 12 poses never baked into the model
RAYS = [64, 128] if QUICK else [64, 128, 256, 512, 1024]
LOBES = [1, 2, 3, 4]
DETAIL = 1.5 if QUICK else 3.4            # 10k vertices
# Issue #27 item 6: the unseen AO error's worst case, pruned against unpruned.
TAIL_RAYS = [64] if QUICK else [64, 128, 256]
TAIL_GOAL, TAIL_BYTES_GOAL = 1.2, 1.1
# Bytes per vertex of the default model before the fit pruned the stored
# model on its own weights (docs/visibility-benchmark.md at 0.2.0: 1.34,
# 1.24 and 1.19 MB for 10352 vertices; 129.6 measured at 64 rays).
TAIL_BYTES_BEFORE = {64: 129.6, 128: 119.8, 256: 115.0}
TAIL_SECTION = "## The tail of pruning"


def raw_throughput(mesh, rays_per_vertex, threads, mode):
    """Raw Embree occlusion throughput on `mesh` (the baseline), measured by
    bench/cpp/visibility_throughput_bench.cpp in its own process."""
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for name, array, dtype in (("p.f32", mesh.positions, np.float32), ("n.f32", mesh.normals, np.float32),
                                   ("t.u32", mesh.triangles, np.uint32)):
            files.append(os.path.join(tmp, name))
            np.ascontiguousarray(array, dtype).tofile(files[-1])
        exe = os.path.join(ROOT, "build", "bench", "penumbra_visibility_throughput_bench")
        out = subprocess.run([exe, *files, str(rays_per_vertex), str(threads), mode],
                             capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def new_character(detail, frames=FRAMES):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    obj, rig = visibility_character.build(detail=detail, frames=frames)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj, rig


def per_frame_errors(model, unseen):
    return [model.evaluate(unseen.subset([i]))["ao_mean_abs"] for i in range(len(unseen))]


def sh_errors(predicted, truth):
    """Per (vertex, frame) RMS over the sphere, sqrt(|Δ|²/4π)."""
    return np.sqrt(((predicted - truth) ** 2).sum(axis=-1) / (4 * np.pi))


def frame_change_costs(detail, repeats=15):
    """One frame change of the character with Penumbra (2 lobes, order 4,
    Phong) against Blender's own frame change without it, alternated frame by
    frame in the same run (bench/visibility_frame_change.py); the model is baked
    from 4 frames at 16 rays: the run time's cost does not depend on how well
    the model was baked."""
    obj, rig = new_character(detail, frames=8)
    world = bpy.data.worlds.new("w")
    world.use_nodes = True
    bpy.context.scene.world = world
    path = os.path.join(bpy.app.tempdir or "/tmp", f"bench_frame_change_{detail}.pzh")
    bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=8, frame_step=2, rays=16, lobes=2, filepath=path)
    result = visibility_frame_change.frame_change_costs(obj, list(range(1, 9)), repeats)
    log(visibility_frame_change.summary(result))
    return result


def unseen_ao_errors(core, model, unseen):
    """|ΔAO| per (unseen frame, vertex), unclamped: the model's SH against the bake's."""
    predicted = np.stack([core.visibility.ambient_occlusion(f) for f in model_sh(model, unseen)])
    truth = np.stack([core.visibility.ambient_occlusion(f) for f in baked_sh(unseen)])
    return np.abs(predicted - truth)


def pruning_tail(core, influence, bakes):
    """The stored (pruned) model's unseen AO error tail against the unpruned
    model's (prune and constant tolerances 0), 2 lobes, per ray count of
    `bakes` ({rays: (training, unseen)})."""
    rows = []
    for rays, (train, unseen) in bakes.items():
        row = {"rays": rays, "samples": len(unseen) * unseen.vertex_count}
        for name, settings in (("pruned", {}), ("unpruned", {"prune_tolerance": 0.0, "constant_tolerance": 0.0})):
            model, report = core.visibility.fit_model(train, influence, lobes=2, **settings)
            err = unseen_ao_errors(core, model, unseen)
            row[name] = {"max": float(err.max()), "p9999": float(np.percentile(err, 99.99)),
                         "mean": float(err.mean()), "worst_vertex": int(err.argmax() % err.shape[1]),
                         "bytes_per_vertex": report["model_bytes"] / train.vertex_count}
        row["max_ratio"] = row["pruned"]["max"] / row["unpruned"]["max"]
        row["p9999_ratio"] = row["pruned"]["p9999"] / row["unpruned"]["p9999"]
        row["bytes_ratio"] = row["pruned"]["bytes_per_vertex"] / TAIL_BYTES_BEFORE[rays]
        row["met"] = row["max_ratio"] <= TAIL_GOAL and row["p9999_ratio"] <= TAIL_GOAL and row["bytes_ratio"] <= TAIL_BYTES_GOAL
        log("tail:", row)
        rows.append(row)
    return rows


def tail_section(rows, alone=False):
    """The "tail of pruning" section of docs/visibility-benchmark.md
    (`alone`: written by --tail, after the tables above)."""
    lines = [TAIL_SECTION, "",
             f"Issue #27 item 6. The unseen AO error per (vertex, unseen pose), unclamped (the model's SH against the "
             f"bake's; {rows[0]['samples']} samples per row), of the stored model (default tolerances) and of the "
             "unpruned one (prune and constant tolerances 0), 2 lobes. Goal: the stored model's maximum and 99.99th "
             f"percentile within {TAIL_GOAL}× the unpruned model's, at most {TAIL_BYTES_GOAL}× the bytes per vertex "
             "of the default model before this change (129.6, 119.8 and 115.0 at 64, 128 and 256 rays). Before, the "
             "stored model kept the pruning decided on the frames without the held-out ones, with those frames' "
             "weights, beside weights refitted on every frame: at 64 rays vertex 8882 reached 2.49 (99.99th "
             "percentile 1.15) against 0.57 (0.47) unpruned. Now the refit is pruned by the same rule on its own "
             "weights. Run alone: `.venv/bin/python bench/visibility_benchmark.py --tail`."
             + (" This section was rewritten alone: the tables above are from the last full run, before this "
                "change (their unseen AO maximum at 64 rays is the 2.49 above)." if alone else ""), "",
             "| rays | max (unpruned) | ratio | 99.99th pct (unpruned) | ratio | mean | worst vertex | bytes / vertex (unpruned) | vs before | goal |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for x in rows:
        p, u = x["pruned"], x["unpruned"]
        lines.append(f"| {x['rays']} | {p['max']:.3f} ({u['max']:.3f}) | {x['max_ratio']:.2f} | {p['p9999']:.3f} "
                     f"({u['p9999']:.3f}) | {x['p9999_ratio']:.2f} | {p['mean']:.4f} | {p['worst_vertex']} | "
                     f"{p['bytes_per_vertex']:.1f} ({u['bytes_per_vertex']:.1f}) | {x['bytes_ratio']:.2f} | "
                     + ("met" if x["met"] else "**not met**") + " |")
    return lines


def run_tail_only():
    """--tail: only the tail of pruning, its section rewritten in place in the docs."""
    penumbra.register()
    core = native.require()
    obj, rig = new_character(DETAIL)
    influence = armature_data.bone_influence(obj, rig)
    bakes = {rays: (bake_frames(obj, TRAIN, rays).training, bake_frames(obj, UNSEEN, rays).training)
             for rays in TAIL_RAYS}
    rows = pruning_tail(core, influence, bakes)
    penumbra.unregister()
    doc_section.write_section(os.path.join(DOCS, "visibility-benchmark.md"), TAIL_SECTION,
                              "\n".join(tail_section(rows, alone=True)) + "\n", after="## Lobes and rays")
    doc_section.update_json(os.path.join(DOCS, "visibility", "benchmark.json"), "tail", rows)
    log("wrote the tail section")


def frame_change_section(frame_change_results):
    """The "Run time per frame" section of docs/visibility-benchmark.md."""
    lines = ["## Run time per frame (handler, median)", "",
             visibility_frame_change.DESCRIPTION + " The realistic character's frame change at ~100k vertices is in "
             "[visibility-humanoid-benchmark.md](visibility-humanoid-benchmark.md). Run alone: `.venv/bin/python "
             "bench/visibility_benchmark.py --frame-change`.", ""]
    lines += visibility_frame_change.table(frame_change_results.values())
    big = max(frame_change_results.values(), key=lambda x: x["vertices"])
    lines += ["", f"Goal (issue #13): the whole frame change at ~100k vertices at most 4.5× Blender's own. Measured: "
              f"**{big['ratio']:.2f}×** at {big['vertices']} vertices — "
              + ("met." if big["ratio"] <= 4.5 else "**not met**.")
              + " Load average during the runs (2 cores): "
              + ", ".join(f"{x['load_average']:.1f}" for x in frame_change_results.values()) + "; "
              f"{big['repeats']} frame changes each way per size."]
    kernel = big.get("kernel_ns_per_vertex")
    if kernel:
        scalar = kernel.get("SCALAR")
        lines += ["", "The shading kernel alone on each SIMD target this CPU supports (one thread, 100k vertices, "
                  "2 lobes, order 4, Phong, float; `build/bench/penumbra_pose_shading_bench --quick`, right after "
                  "the frame changes): " + ", ".join(
                      f"{name} {ns:.0f} ns/vertex" + (f" ({scalar / ns:.1f}× the scalar one)" if scalar else "")
                      for name, ns in kernel.items())
                  + ". SSE4 is what the default x86-64-v2 build ran before the run-time dispatch."]
    lines += ["", visibility_frame_change.accuracy_line(frame_change_results.values())]
    return lines


def run_frame_change_only():
    """--frame-change: only the run-time section, rewritten in place in the docs."""
    penumbra.register()
    results = {"10k": frame_change_costs(3.4, repeats=21), "100k": frame_change_costs(11, repeats=21)}
    penumbra.unregister()
    results["100k"]["kernel_ns_per_vertex"] = visibility_frame_change.kernel_per_target()
    path = os.path.join(DOCS, "visibility-benchmark.md")
    with open(path) as f:
        text = f.read()
    heading = "## Run time per frame"
    before = text[:text.index(heading)] if heading in text else text + "\n"
    after = text[text.index(heading):]
    following = after.find("\n## ", 1)
    rest = after[following + 1:] if following >= 0 else ""
    with open(path + ".tmp", "w") as f:
        f.write(before + "\n".join(frame_change_section(results)) + "\n" + ("\n" + rest if rest else ""))
    os.replace(path + ".tmp", path)
    doc_section.update_json(os.path.join(DOCS, "visibility", "benchmark.json"), "frame_change", results)
    log("wrote the run-time section of", path)


def main():
    penumbra.register()
    core = native.require()
    results = {"blender": bpy.app.version_string, "cores": os.cpu_count(), "quick": QUICK}
    obj, rig = new_character(DETAIL)
    results["vertices"] = len(obj.data.vertices)
    log(f"character: {results['vertices']} vertices, {len(TRAIN)} training + {len(UNSEEN)} unseen frames")
    influence = armature_data.bone_influence(obj, rig)

    # Throughput on the rest pose: raw Embree vs the bake, same mesh, same run.
    bpy.context.scene.frame_set(1)
    frame = mesh_data.evaluated_mesh(obj, bpy.context.evaluated_depsgraph_get())
    raw_single = raw_throughput(frame, 128, 0, "single")
    raw_packet = raw_throughput(frame, 128, 0, "packet")
    raw_one_thread = raw_throughput(frame, 128, 1, "single")
    results["raw_embree"] = {"single": raw_single, "packet": raw_packet, "single_one_thread": raw_one_thread}
    log(f"raw Embree: {raw_single['rays_per_second'] / 1e6:.2f} M rays/s (rtcOccluded1, all threads), "
        f"{raw_packet['rays_per_second'] / 1e6:.2f} M (packets of {raw_packet['packet_width']}), "
        f"{raw_one_thread['rays_per_second'] / 1e6:.2f} M on one thread")

    # The C++ bake alone on the same rest-pose mesh, frame after frame with
    # nothing in between (no posing, no Python): its rays/s against raw Embree.
    sizes, loops = mesh_data.polygon_topology(obj.data)
    nb = core.visibility.reference_neighbours(len(obj.data.vertices), sizes, loops)
    static = {}
    for rays in (128, 512):
        ts = core.visibility.TrainingSet(len(obj.data.vertices), 0, ["a"], rays=rays)
        started = time.perf_counter()
        for k in range(4):
            stats = ts.bake_frame(k, frame.positions, frame.normals, frame.triangles, nb, np.eye(3)[None])
        static[rays] = 4 * stats["rays_cast"] / (time.perf_counter() - started)
    results["static_bake_rays_per_second"] = static
    log("C++ bake alone:", {k: f"{v / 1e6:.2f} M rays/s" for k, v in static.items()})

    # The operator's path at 128 rays on the training frames: sequential
    # (read a frame, then trace it) and pipelined (read the next frame while
    # tracing), with the time split, between two raw Embree measurements.
    # The baseline: raw Embree on the same 24 posed meshes (posed frames trace
    # slower than the rest pose: limbs close to the body), as many rays per
    # vertex as the bake traces (the upper half of 128), measured before and
    # after the bakes so that both see the same machine.
    posing = bake.BakeJob(bpy.context, obj, TRAIN[0], TRAIN[0], 1, 128, 1, 4, None)
    posed = [posing.gather(f)[1] for f in TRAIN]
    posing.restore_frame()

    def raw_posed():
        rays = seconds = 0.0
        for mesh in posed:
            r = raw_throughput(mesh, 64, 0, "single")
            rays += r["rays"]
            seconds += r["seconds"]
        return rays / seconds
    paths = {}
    raw_before = raw_posed()
    for name, pipelined in (("sequential", False), ("pipelined", True), ("sequential, again", False)):
        baked = bake_frames(obj, TRAIN, 128, overlap=pipelined)
        cast = baked.job.rays_cast
        paths[name] = dict(baked.job.seconds, job_setup=baked.setup_seconds, total=baked.seconds, rays_cast=cast,
                           rays_per_second=cast / baked.seconds)
    raw_after = raw_posed()
    # The faster of the two as the baseline: a load spike from other jobs
    # during one raw measurement must not flatter the bake.
    raw_mean = max(raw_before, raw_after)
    for x in paths.values():
        x["ratio_to_raw"] = x["rays_per_second"] / raw_mean
        x["cpp_ratio_to_raw"] = x["rays_cast"] / (x["setup"] + x["build"] + x["cast"]) / raw_mean
    results["bake_paths_128"] = {"raw_rays_per_second": raw_mean, "raw_before": raw_before, "raw_after": raw_after,
                                 "paths": paths}
    log("bake paths at 128 rays:", {k: f"{v['ratio_to_raw']:.2f} of raw" for k, v in paths.items()},
        f"raw on the posed frames {raw_before / 1e6:.2f} / {raw_after / 1e6:.2f} M rays/s")

    sweep, bakes = [], {}
    for rays in RAYS:
        train, seconds, _, job = bake_frames(obj, TRAIN, rays)
        cast, trace_seconds = job.rays_cast, job.seconds_trace
        unseen = bake_frames(obj, UNSEEN, rays).training
        bakes[rays] = (train, unseen)
        log(f"rays {rays}: bake {seconds:.1f} s, {cast / seconds / 1e6:.2f} M rays/s end to end, "
            f"{cast / trace_seconds / 1e6:.2f} M rays/s in the C++ bake")
        for lobes in (LOBES if rays == 256 or (QUICK and rays == RAYS[-1]) else [2]):
            started = time.perf_counter()
            model, report = core.visibility.fit_model(train, influence, lobes=lobes)
            fit_seconds = time.perf_counter() - started
            unseen_errors = model.evaluate(unseen)
            per_frame = per_frame_errors(model, unseen)
            row = {
                "rays": rays, "lobes": lobes, "bake_seconds": seconds, "bake_rays_per_second": cast / seconds,
                "trace_seconds": trace_seconds, "trace_rays_per_second": cast / trace_seconds,
                "fit_seconds": fit_seconds,
                "zh_fit_sh_rms": report["zh_fit"]["sh_rms"], "zh_fit_ao": report["zh_fit"]["ao_mean_abs"],
                "training_sh_rms": report["model_training"]["sh_rms"], "training_ao": report["model_training"]["ao_mean_abs"],
                "holdout_sh_rms": report["model_holdout"]["sh_rms"], "holdout_ao": report["model_holdout"]["ao_mean_abs"],
                "holdout_unpruned_sh_rms": report["model_holdout_unpruned"]["sh_rms"],
                "holdout_unpruned_ao": report["model_holdout_unpruned"]["ao_mean_abs"],
                "unseen_sh_rms": unseen_errors["sh_rms"], "unseen_ao": unseen_errors["ao_mean_abs"],
                "unseen_ao_max": unseen_errors["ao_max_abs"],
                "unseen_ao_per_frame_mean": float(np.mean(per_frame)), "unseen_ao_per_frame_std": float(np.std(per_frame)),
                "active_joints": [j["name"] for j in report["joints"] if j["active"]],
                "constant_vertices": report["constant_vertices"], "model_bytes": report["model_bytes"],
                "dense_bytes": report["dense_bytes"], "ridge_relative": report["ridge_relative"],
            }
            sweep.append(row)
            log(f"  lobes {lobes}: fit {fit_seconds:.1f} s, ZH {row['zh_fit_sh_rms']:.4f}, train {row['training_sh_rms']:.4f}, "
                f"held-out {row['holdout_sh_rms']:.4f}, unseen {row['unseen_sh_rms']:.4f} (AO {row['unseen_ao']:.4f}), "
                f"{row['model_bytes'] / 1e6:.2f} MB of {row['dense_bytes'] / 1e6:.2f} dense")
    results["sweep"] = sweep
    results["tail"] = pruning_tail(core, influence, {rays: bakes[rays] for rays in TAIL_RAYS})
    results["lobe_rays"] = 256 if not QUICK else RAYS[-1]
    # The direction set's own error: AO of each ray count against the largest.
    top = baked_sh(bakes[RAYS[-1]][1])
    top_ao = np.stack([core.visibility.ambient_occlusion(f) for f in top])
    results["ray_noise_ao"] = {
        r: float(np.abs(np.stack([core.visibility.ambient_occlusion(f) for f in baked_sh(bakes[r][1])]) - top_ao).mean())
        for r in RAYS}

    # Paper fig. 3: fit plain visibility then convolve, vs fit cosine-weighted visibility.
    fig_rays = results["lobe_rays"]
    train_plain, unseen_plain = bakes[fig_rays]
    train_cos = bake_weighted(obj, TRAIN, fig_rays, "cosine")
    unseen_cos = bake_weighted(obj, UNSEEN, fig_rays, "cosine")
    model_plain, _ = core.visibility.fit_model(train_plain, influence, lobes=2)
    model_cos, _ = core.visibility.fit_model(train_cos, influence, lobes=2)
    diffuse = np.asarray(core.sh.diffuse_operator(4))
    plain_pred = model_sh(model_plain, unseen_plain)
    cos_pred = model_sh(model_cos, unseen_cos)
    plain_true, cos_true = baked_sh(unseen_plain), baked_sh(unseen_cos)
    convolved = plain_pred @ diffuse.T
    green = sh_errors(plain_pred, plain_true)
    red = sh_errors(cos_pred, cos_true)
    blue = sh_errors(convolved, cos_true)
    scale_plain = np.sqrt((plain_true ** 2).sum(-1) / (4 * np.pi)).mean()
    scale_cos = np.sqrt((cos_true ** 2).sum(-1) / (4 * np.pi)).mean()
    results["figure3"] = {
        "plain_fit_vs_plain": [float(green.mean()), float(green.std()), float(green.mean() / scale_plain)],
        "cosine_fit_vs_cosine": [float(red.mean()), float(red.std()), float(red.mean() / scale_cos)],
        "convolved_plain_fit_vs_cosine": [float(blue.mean()), float(blue.std()), float(blue.mean() / scale_cos)],
        "note": "[mean, std, mean / mean signal RMS] of per-(vertex, unseen frame) RMS over the sphere",
    }
    log("figure 3:", results["figure3"])

    # Below-horizon rays: cast them vs count them as occluded.
    started = time.perf_counter()
    cast_set, cast_seconds, _, cast_job = bake_frames(obj, TRAIN[:6], fig_rays, below_horizon="cast")
    occl_set, occl_seconds, _, occl_job = bake_frames(obj, TRAIN[:6], fig_rays, below_horizon="occluded")
    cast_rays, occl_rays = cast_job.rays_cast, occl_job.rays_cast
    ao_cast = np.stack([core.visibility.ambient_occlusion(f) for f in baked_sh(cast_set)])
    ao_occl = np.stack([core.visibility.ambient_occlusion(f) for f in baked_sh(occl_set)])
    model_cast, rep_cast = core.visibility.fit_model(cast_set, influence, lobes=2, holdout_stride=0)
    model_occl, rep_occl = core.visibility.fit_model(occl_set, influence, lobes=2, holdout_stride=0)
    results["below_horizon"] = {
        "frames": 6, "cast_seconds": cast_seconds, "occluded_seconds": occl_seconds,
        "cast_rays_per_second": cast_rays / cast_seconds, "occluded_rays_per_second": occl_rays / occl_seconds,
        "ao_mean_abs_difference": float(np.abs(ao_cast - ao_occl).mean()),
        "ao_max_abs_difference": float(np.abs(ao_cast - ao_occl).max()),
        "zh_fit_sh_rms_cast": rep_cast["zh_fit"]["sh_rms"], "zh_fit_sh_rms_occluded": rep_occl["zh_fit"]["sh_rms"],
        "training_ao_cast": rep_cast["model_training"]["ao_mean_abs"],
        "training_ao_occluded": rep_occl["model_training"]["ao_mean_abs"],
    }
    log("below horizon:", results["below_horizon"])

    # The whole bake + fit at 128 rays vs Cycles' AO bake of the same frames at 128 samples.
    row128 = next(r for r in sweep if r["rays"] == 128 and r["lobes"] == 2)
    ours = row128["bake_seconds"] + row128["fit_seconds"]
    cycles_frames = TRAIN[:2] if QUICK else TRAIN[:3]
    cycles_ao_values, cycles_times = cycles_ao(obj, cycles_frames, 128)
    cycles_mean_ao = float(cycles_ao_values[:, -1].mean())
    per_frame = float(np.mean(cycles_times))
    results["cycles"] = {
        "frames_measured": len(cycles_frames), "seconds_per_frame": per_frame,
        "estimated_seconds_all_training_frames": per_frame * len(TRAIN),
        "ours_bake_plus_fit_seconds": ours, "ratio_ours_over_cycles": ours / (per_frame * len(TRAIN)),
        "cycles_mean_ao_last_frame": cycles_mean_ao,
    }
    log("cycles:", results["cycles"])

    # Run-time cost per frame.
    results["frame_change"] = {"10k": frame_change_costs(3.4)}
    if not QUICK:
        results["frame_change"]["100k"] = frame_change_costs(11)
    log("frame change:", results["frame_change"])
    penumbra.unregister()

    with open(os.path.join(DOCS, "visibility", "benchmark.json.tmp"), "w") as f:
        json.dump(results, f, indent=1)
    os.replace(os.path.join(DOCS, "visibility", "benchmark.json.tmp"), os.path.join(DOCS, "visibility", "benchmark.json"))
    svg_plot(results, os.path.join(DOCS, "visibility", "errors.svg"))
    write_markdown(results)


def bake_weighted(obj, frames, rays, weighting):
    """Like bake_frames, with cosine-weighted projection (fig. 3)."""
    core = native.require()
    job = bake.BakeJob(bpy.context, obj, frames[0], frames[0] + 1, 1, rays, 1, 4, None)
    training = core.visibility.TrainingSet(job.vertex_count, job.topology, job.bone_names, order=4, rays=rays,
                                           weighting=weighting)
    try:
        for frame in frames:
            _, mesh, rotations, occluders = job.gather(frame)
            training.bake_frame(float(frame), mesh.positions, mesh.normals, mesh.triangles, job.neighbours, rotations)
    finally:
        job.restore_frame()
    return training


def write_markdown(r):
    lines = ["# Visibility baker: measurements", "",
             f"Generated by `bench/visibility_benchmark.py` in Blender {r['blender']} (bpy module), "
             f"{r['cores']} cores, on the procedural character (`examples/scenes/visibility_character.py`) with "
             f"{r['vertices']} vertices: {len(TRAIN)} training frames (even frames of a {FRAMES}-frame action) "
             f"and {len(UNSEEN)} unseen poses (odd frames, never baked into the model). Errors: `sh` is the RMS "
             "over the sphere of the visibility error, sqrt(|Δv|²/4π) (1 = everything wrong); `AO` is the mean "
             "|Δ ambient occlusion| (the diffuse shade under a uniform unit World). Timings share the machine "
             "with whatever else ran; compare ratios within this run.", "",
             "## Lobes and rays", "",
             "`held-out` is the model exactly as stored (ridge, constant vertices, per-vertex pruning of joint directions) fitted "
             "without the held-out frames (every 4th training frame) and measured on them; `unpruned` is the plain "
             "ridge solution on the same frames. `unseen` is the stored model (all 24 frames) on the 12 poses never baked.", "",
             "| rays | lobes | bake s | Mrays/s end to end (C++ part) | fit s | ZH fit sh | train sh | held-out sh (unpruned) | held-out AO | unseen sh | unseen AO (max) | model MB | dense MB | constant vertices |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for x in r["sweep"]:
        lines.append(f"| {x['rays']} | {x['lobes']} | {x['bake_seconds']:.1f} | {x['bake_rays_per_second'] / 1e6:.2f} ({x['trace_rays_per_second'] / 1e6:.2f}) | "
                     f"{x['fit_seconds']:.1f} | {x['zh_fit_sh_rms']:.4f} | {x['training_sh_rms']:.4f} | "
                     f"{x['holdout_sh_rms']:.4f} ({x['holdout_unpruned_sh_rms']:.4f}) | {x['holdout_ao']:.4f} | "
                     f"{x['unseen_sh_rms']:.4f} | {x['unseen_ao']:.4f} ({x['unseen_ao_max']:.2f}) | "
                     f"{x['model_bytes'] / 1e6:.2f} | {x['dense_bytes'] / 1e6:.2f} | {x['constant_vertices']} |")
    lines += ["", "![errors](visibility/errors.svg)", "",
              "Error of the direction set itself (AO of each ray count against the largest, unseen frames): " +
              ", ".join(f"{k} rays {v:.4f}" for k, v in r["ray_noise_ao"].items()), "",
              *tail_section(r["tail"]), "",
              "## Paper figure 5: one vs two lobes (unseen poses, per-frame mean AO error ± std)", "",
              "| rays | lobes | mean | std |", "|---:|---:|---:|---:|"]
    for x in r["sweep"]:
        if x["rays"] == r["lobe_rays"]:
            lines.append(f"| {x['rays']} | {x['lobes']} | {x['unseen_ao_per_frame_mean']:.4f} | {x['unseen_ao_per_frame_std']:.4f} |")
    f3 = r["figure3"]
    lines += ["", "## Paper figure 3: plain vs cosine-weighted visibility (unseen poses, 2 lobes)", "",
              "| fit | compared with | mean sh error | std | mean / signal |", "|---|---|---:|---:|---:|",
              f"| plain visibility (green) | plain | {f3['plain_fit_vs_plain'][0]:.4f} | {f3['plain_fit_vs_plain'][1]:.4f} | {f3['plain_fit_vs_plain'][2]:.3f} |",
              f"| cosine-weighted (red) | cosine-weighted | {f3['cosine_fit_vs_cosine'][0]:.4f} | {f3['cosine_fit_vs_cosine'][1]:.4f} | {f3['cosine_fit_vs_cosine'][2]:.3f} |",
              f"| plain, then convolved with the clamped cosine (blue) | cosine-weighted | {f3['convolved_plain_fit_vs_cosine'][0]:.4f} | {f3['convolved_plain_fit_vs_cosine'][1]:.4f} | {f3['convolved_plain_fit_vs_cosine'][2]:.3f} |"]
    raw, b = r["raw_embree"], r["below_horizon"]
    bake128 = next(x for x in r["sweep"] if x["rays"] == 128 and x["lobes"] == 2)
    lines += ["", "## Throughput", "",
              "| what | M rays/s |", "|---|---:|",
              f"| raw Embree, rtcOccluded1, all threads | {raw['single']['rays_per_second'] / 1e6:.2f} |",
              f"| raw Embree, rtcOccluded1, one thread | {raw['single_one_thread']['rays_per_second'] / 1e6:.2f} |",
              f"| raw Embree, packets of {raw['packet']['packet_width']}, all threads | {raw['packet']['rays_per_second'] / 1e6:.2f} |",
              f"| the C++ bake at 128 rays (frames, BVH build, rays, projection) | {bake128['trace_rays_per_second'] / 1e6:.2f} |",
              f"| the bake at 128 rays end to end (plus posing the scene and reading the mesh in Python) | {bake128['bake_rays_per_second'] / 1e6:.2f} |",
              f"| the C++ bake alone on the rest pose, 128 rays (no posing in between) | {r['static_bake_rays_per_second'][128] / 1e6:.2f} |",
              f"| the C++ bake alone on the rest pose, 512 rays | {r['static_bake_rays_per_second'][512] / 1e6:.2f} |",
              "", f"C++ bake alone / raw single-ray Embree: **{r['static_bake_rays_per_second'][128] / raw['single']['rays_per_second']:.2f}** at 128 rays, "
              f"**{r['static_bake_rays_per_second'][512] / raw['single']['rays_per_second']:.2f}** at 512 (goal ≥ 0.7). "
              f"The pose-by-pose bake against this rest-pose baseline: "
              f"{bake128['trace_rays_per_second'] / raw['single']['rays_per_second']:.2f} at 128 rays "
              f"(C++ part), {bake128['bake_rays_per_second'] / raw['single']['rays_per_second']:.2f} end to end "
              "(the C++ column of the first table gives it per ray count); part of the gap is the poses themselves "
              "(limbs near the body trace slower), part Blender's posing between frames: the next section compares "
              "with raw Embree on the same posed meshes and splits the time. "
              "Rays per second count traced rays only (the upper hemisphere).", ""]
    bp = r["bake_paths_128"]
    paths = bp["paths"]
    lines += ["### Where the time of a bake goes (128 rays, the 24 training frames, as the operator bakes)", "",
              "Baseline: raw Embree (rtcOccluded1, all threads) on the same 24 posed meshes, 64 rays per vertex "
              "(what the bake traces of its 128: the upper hemisphere), measured just before and after the bakes: "
              f"{bp['raw_before'] / 1e6:.2f} and {bp['raw_after'] / 1e6:.2f} M rays/s; the ratios below divide by "
              "the faster of the two (a load spike from other jobs during one measurement must not flatter the "
              "bake; the rest pose alone traces faster, table above). "
              "Posing = `scene.frame_set` plus the depsgraph; reading = the evaluated mesh, topology check, "
              "bone rotations (Python, main thread); C++ = tangent frames and checks, Embree scene build "
              "(first frame) or update (later frames: new positions, recommit), casting with the SH projection. "
              "Sequential (what the operator does): read a frame, then trace it. Pipelined: the main thread poses "
              "and reads frame k + 1 while a worker traces frame k (the parts then add up to more than the total); "
              "on two cores it is slower, Blender's depsgraph threads taking the cores from the casting threads.", "",
              "| path | total s | posing s | reading s | C++ setup s | scene build/update s | casting + projection s | end-to-end / raw | C++ part / raw |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    baseline = max(bp["raw_before"], bp["raw_after"])
    for name, x in paths.items():
        x["ratio_to_raw"] = x["rays_per_second"] / baseline
        x["cpp_ratio_to_raw"] = x["rays_cast"] / (x["setup"] + x["build"] + x["cast"]) / baseline
        lines.append(f"| {name} | {x['total']:.2f} | {x['pose']:.2f} | {x['read']:.2f} | {x['setup']:.3f} | {x['build']:.3f} | "
                     f"{x['cast']:.2f} | **{x['ratio_to_raw']:.2f}** | {x['cpp_ratio_to_raw']:.2f} |")
    lines += ["",
              "Rays below the tangent plane (6 frames, "
              f"{r['lobe_rays']} rays): cast them {b['cast_seconds']:.1f} s ({b['cast_rays_per_second'] / 1e6:.2f} M rays/s), "
              f"count them as occluded {b['occluded_seconds']:.1f} s; mean |ΔAO| between the two "
              f"{b['ao_mean_abs_difference']:.4f} (max {b['ao_max_abs_difference']:.3f}); ZH fit sh error "
              f"{b['zh_fit_sh_rms_cast']:.4f} (cast) vs {b['zh_fit_sh_rms_occluded']:.4f} (occluded); model training AO "
              f"error {b['training_ao_cast']:.4f} vs {b['training_ao_occluded']:.4f}."]
    c = r["cycles"]
    lines += ["", "## Against Cycles' AO bake", "",
              f"Cycles `bpy.ops.object.bake(type='AO')` to a colour attribute, 128 samples, denoising off: "
              f"{c['seconds_per_frame']:.2f} s per frame (measured on {c['frames_measured']} frames), so "
              f"{c['estimated_seconds_all_training_frames']:.1f} s for the {len(TRAIN)} training frames. The whole "
              f"Penumbra bake + fit (128 rays, 2 lobes) of the same frames: {c['ours_bake_plus_fit_seconds']:.1f} s — "
              f"**{c['ratio_ours_over_cycles']:.3f}×** Cycles' time (goal ≤ 0.1)."]
    lines += [""] + frame_change_section(r["frame_change"])
    path = os.path.join(DOCS, "visibility-benchmark.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)
    log("wrote", path)


if __name__ == "__main__":
    if FRAME_CHANGE_ONLY:
        run_frame_change_only()
    elif TAIL_ONLY:
        run_tail_only()
    else:
        main()
