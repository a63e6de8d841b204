#!/usr/bin/env python3
"""GPU viewport preview frame costs (run by `make bench`): issue 27's goal
measurement, bench/helpers/gpu_preview_frames.py, in Debian's Blender 3.4 in a
window under Xvfb and in the bpy 5.2 module after gpu.init() (both Mesa's
llvmpipe). Writes docs/visibility-gpu-preview-benchmark.md.

    .venv/bin/python bench/visibility_gpu_preview_benchmark.py [--vertices 10000,100000,1000000]

The exactness of the GPU shading is a test, not a benchmark:
tests/python/visibility/test_gpu_model_in_blender.py.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench.helpers
from bench.helpers.result_line import only_result  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HELPER = os.path.join(ROOT, "bench", "helpers", "gpu_preview_frames.py")
SKINNING = os.path.join(ROOT, "bench", "helpers", "gpu_preview_skinning.py")
OUT = os.path.join(ROOT, "docs", "visibility-gpu-preview-benchmark.md")
GOAL = 1.5  # preview on ≤ 1.5 × Penumbra off, per frame change (issue 27)


def run(command, timeout=5400):
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    try:
        result = only_result(proc, tail=3000)
    except RuntimeError as failure:
        sys.exit(f"{command} gave no result: {failure}")
    if not result["ok"]:
        sys.exit(result["error"])
    return result


def goal_table(results):
    rows = ["| Blender | vertices | frame_set, Penumbra off (ms) | frame_set, preview on (ms) | + upload in the draw "
            "callback (ms) | on / off | goal ≤ 1.5× | preview's own CPU per frame (ms) | load average |",
            "|---|---:|---:|---:|---:|---:|---|---:|---:|"]
    for r in results:
        for s in r["sizes"]:
            rows.append(f"| {r['label']} | {s['vertices']} | {s['off_frame_set_ms']:.2f} | {s['on_frame_set_ms']:.2f} | "
                        f"{s['on_upload_ms']:.2f} | {s['ratio']:.2f}× | {'met' if s['ratio'] <= GOAL else 'missed'} | "
                        f"{s['preview_cpu_ms']:.2f} | {s.get('load_average', float('nan')):.1f} |")
    return "\n".join(rows)


def split_table(results):
    keys = ["pose_features", "read_positions", "pack", "upload"]
    rows = ["| Blender | vertices | " + " | ".join(keys) + " |", "|---|---:|" + "---:|" * len(keys)]
    for r in results:
        for s in r["sizes"]:
            rows.append(f"| {r['label']} | {s['vertices']} | " +
                        " | ".join(f"{s['split_ms'].get(k, float('nan')):.2f}" for k in keys) + " |")
    return "\n".join(rows)


def gpu_table(results):
    rows = ["| Blender | vertices | model on the GPU (bytes/vertex) | per-frame geometry (bytes/vertex) | load: file "
            "(s) | load: to the GPU (s) | draw 1280×720 (ms) | frame change + forced redraw, off / on (ms) | "
            "texture layout (width × height) | character build (s) |",
            "|---|---:|---:|---:|---:|---:|---:|---|---|---:|"]
    for r in results:
        for s in r["sizes"]:
            layout = ", ".join(f"{k} {w}×{h}" for k, (w, h) in s["texture_layout"].items())
            layout += f", frame_geometry {s['geometry_layout'][0]}×{s['geometry_layout'][1]}"
            redraw = (f"{s['off_frame_and_redraw_ms']:.0f} / {s['on_frame_and_redraw_ms']:.0f}"
                      if s["off_frame_and_redraw_ms"] is not None else "no window")
            rows.append(f"| {r['label']} | {s['vertices']} | {s['gpu_model_bytes_per_vertex']:.0f} | "
                        f"{s['gpu_frame_bytes_per_vertex']:.0f} | {s['load_file_s']:.2f} | {s['load_gpu_s']:.2f} | "
                        f"{s['draw_1280x720_ms']:.0f} | {redraw} | {layout} | {s['build_seconds']:.0f} |")
    return "\n".join(rows)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--vertices", default="10000,100000,1000000")
    # Frames of each state per size: at 1M a forced redraw takes seconds on llvmpipe.
    parser.add_argument("--frames", default="40,40,12")
    parser.add_argument("--skinning-vertices", default="100000")
    parser.add_argument("--measure", help="frames,skinning (the default without --from-results): what to run")
    parser.add_argument("--results", help="also write the measurements (JSON) here")
    parser.add_argument("--from-results", help="take what --measure does not run from these measurements")
    parser.add_argument("--blenders", default="3.4,5.2", help="which Blenders --measure runs in")
    args = parser.parse_args()
    results = {}
    if args.from_results:
        with open(args.from_results) as f:
            results = json.load(f)
        if isinstance(results, list):
            results = {"frames": results}
    parts = args.measure.split(",") if args.measure else ([] if args.from_results else ["frames", "skinning"])
    for part, runs in measure(args, parts).items():  # a Blender's new run replaces its old one
        kept = [r for r in results.get(part, []) if r["label"] not in {n["label"] for n in runs}]
        results[part] = sorted(kept + runs, key=lambda r: r["label"])
    if args.results:
        with open(args.results, "w") as f:
            json.dump(results, f)
    write_page(results)


def measure(args, parts):
    """{part: [3.4's result, 5.2's result]} for each part asked."""
    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    python313 = os.path.join(ROOT, ".venv313", "bin", "python")
    if not (blender and xvfb and os.path.exists(python313)):
        sys.exit("needs Debian's blender, xvfb-run and .venv313 (scripts/install_deps.sh)")
    helpers = {"frames": (HELPER, ["--vertices", args.vertices, "--frames", args.frames]),
               "skinning": (SKINNING, ["--vertices", args.skinning_vertices])}
    blenders = args.blenders.split(",")
    out = {}
    for part in parts:
        helper, options = helpers[part]
        out[part] = []
        if "3.4" in blenders:
            out[part].append(dict(run([xvfb, "-a", "-s", "-screen 0 1280x1024x24", blender, "-p", "0", "0", "1280",
                                       "800", "--factory-startup", "--python", helper, "--"] + options),
                                  label="3.4, Xvfb"))
        if "5.2" in blenders:
            out[part].append(dict(run([python313, helper, "--gpu-init"] + options), label="5.2, gpu.init()"))
    return out


def frames_run(result):
    """'40 of each at 9948 and 97556 vertices, 12 at 989212', from one Blender's sizes."""
    by_count = {}
    for size in result["sizes"]:
        by_count.setdefault(size["frames"], []).append(str(size["vertices"]))
    return ", ".join(f"{count} of each at {' and '.join(v)} vertices" for count, v in by_count.items())


def texture_limit(results):
    """What the size limit does to the layout: the tallest texture against it, and where it runs out."""
    size = max((s for r in results for s in r["sizes"]), key=lambda s: s["vertices"])
    name, (width, height) = max(size["texture_layout"].items(), key=lambda item: item[1][1])
    limit = results[0]["max_texture_size"]
    reach = size["vertices"] * limit / height
    return (f"Every texture is {width} texels wide (`model_shader.texture_width`: the limit here is {limit}), "
            f"the height follows. At {size['vertices']} vertices the tallest, {name}, is {height} rows of the "
            f"{limit} allowed ({100.0 * height / limit:.0f} %), so the limit forces nothing up to 1M: at this width "
            f"it would be reached near {reach / 1e6:.1f}M vertices (the GPU preview then says so in "
            f"`gpu_preview_status`); textures {limit} wide would reach {limit // width}× further.")


def skinning_section(results):
    """Issue 27 item 1's choice, from bench/helpers/gpu_preview_skinning.py's runs."""
    if not results:
        return "Not run here (`--measure skinning`)."
    rows = ["| Blender | vertices | read the evaluated positions + upload them (ms) | pack the bone matrices + "
            "upload them (ms) | draw 1280×720: evaluated / skinned (ms) | per-vertex shading + readback: evaluated "
            "/ skinned (ms) | max \\|skinned − evaluated\\| | load average |",
            "|---|---:|---:|---:|---|---|---:|---:|"]
    for r in results:
        rows.append(f"| {r['label']} | {r['vertices']} | {r['read_positions_ms']:.2f} + {r['upload_positions_ms']:.2f} | "
                    f"{r['pack_bones_ms']:.3f} + {r['upload_bones_ms']:.3f} ({r['bones']} bones) | "
                    f"{r['draw_evaluated_ms']:.0f} / {r['draw_skinned_ms']:.0f} | "
                    f"{r['readback_evaluated_ms']:.0f} / {r['readback_skinned_ms']:.0f} | "
                    f"{r['max_abs_skinned_vs_evaluated']:.1e} | {r['load_average']:.1f} |")
    saved = max(r["read_positions_ms"] + r["upload_positions_ms"] - r["pack_bones_ms"] - r["upload_bones_ms"]
                for r in results)
    slower = min(r["draw_skinned_ms"] / r["draw_evaluated_ms"] for r in results)
    per_bone = max(r["pack_bones_ms"] / r["bones"] for r in results)
    return "\n".join(rows) + f"""

A prototype (bench/helpers/gpu_preview_skinning.py, not in the add-on): the preview's model shader with its
one position fetch replaced by linear-blend skinning of the rest position (4 bones a vertex, the normalized
vertex-group weights in a texture, {results[0]['skin_bytes_per_vertex']} more bytes a vertex with the rest
positions; the bone matrices in a uniform block). It shades what the evaluated mesh shades (the last column),
so the two routes are compared on the same output. The character has {results[0]['bones']} deforming bones;
packing takes up to {1000.0 * per_bone:.0f} µs a bone, so the humanoid's 31 would take about
{31 * per_bone:.1f} ms.

**The choice: upload the evaluated mesh.** Skinning in the shader would save at most {saved:.2f} ms of CPU a
frame here (reading and uploading the positions, less packing the bones; with the humanoid's 31 bones the
packing alone costs about as much), and nothing of Blender's own frame change: the preview never changes the
object's modifiers, so `scene.frame_set` still evaluates the Armature modifier for Blender's drawing. On the
GPU it costs more
than it saves: every position the shader reads is skinned, not only the vertex's own but its reference
neighbour's and every corner of its faces (the normals, by Blender's rule), so the draw takes {slower:.1f}×
as long or more. It would also need the Armature modifier's exact rule (preserve volume, envelopes, several
armatures) and a fallback for every other deform and shape key, which the evaluated mesh gives for free.
"""


def write_page(everything):
    results = everything["frames"]
    renderer = results[0]["renderer"]
    sizes = sorted({s["vertices"] for r in results for s in r["sizes"]})
    untried = "" if max(sizes) >= 900000 else (
        " Not run here: 1,000,000 vertices (`--vertices 10000,100000,1000000`).")
    text = f"""# GPU preview benchmark

Generated by `bench/visibility_gpu_preview_benchmark.py` (`make bench BENCH=gpu_preview`); do not edit.

Blender {results[0]['blender']} in a window under Xvfb and the bpy {results[1]['blender']} module after
`gpu.init()`, both on {renderer}, on a shared 2-core machine. The procedural character at each size with a
synthetic model in the stored layout (order 4, 2 lobes, 1–3 joint blocks a vertex of 3 directions each:
the per-frame cost depends on the layout, not on the weights' values). `live_update` off. Frames alternate
between Penumbra off and the preview on, {frames_run(results[0])} (medians); in the window a
forced redraw follows each frame change and is allowed to finish before the next one. The GPU preview's
shading against the CPU's: tests/python/visibility/test_gpu_model_in_blender.py (max |difference| under
1e-5 over every BRDF × order 1–8 × 1–4 lobes, under 1e-4 on the ~100k-vertex humanoid at a pose its bake
skipped). Sizes run: {", ".join(str(v) for v in sizes)} vertices.{untried}
Past 300k vertices the character is built at a 16th of the size in bmesh and subdivided twice
(Catmull–Clark, its weights interpolated; bench/helpers/gpu_preview_scene.py): bmesh alone takes minutes at 1M.
The ratio is the median over frames of (frame_set + upload) with the preview on, over the median
frame_set with Penumbra off; other jobs shared the machine, so single medians move by ~20 %.

## Frame change (issue 27 goal: on ≤ 1.5× off)

"On" is `scene.frame_set` with the preview on (its handler: the pose's features, the evaluated mesh's
positions, packing) plus the draw callback's upload (one texture, two uniform blocks); the
GL draw itself is excluded. "Preview's own CPU" is the handler's work plus the upload.

{goal_table(results)}

## The preview's CPU per frame, by step (ms)

{split_table(results)}

## GPU memory, load, draw

The model's textures: model_weights RGBA16F (the stored binary16 weights, rows padded to whole texels),
model_bias, model_blocks, model_layout and model_corners RGBA32F, model_loops R32F (the polygons, from which
the shader takes the vertex normals); per frame frame_geometry R32F (the positions).
{texture_limit(results)}

{gpu_table(results)}

## Skin in the shader, or upload the evaluated mesh (issue 27 item 1)

{skinning_section(everything.get("skinning"))}
"""
    tmp = OUT + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, OUT)
    print(text)


if __name__ == "__main__":
    main()
