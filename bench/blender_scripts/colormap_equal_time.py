"""Equal-time sweep of the Noise Filter's quality presets in Cycles (issue
#25), run by bench/colormap_benchmark.py (section "Equal time"):

    .venv/bin/python bench/blender_scripts/colormap_equal_time.py -- OUT.json

Per scene: the plain ramp at PENUMBRA_BENCH_ET_PLAIN_SPP (1,4,16,64,256) and
every preset of PENUMBRA_BENCH_ET_PRESETS (all) at PENUMBRA_BENCH_ET_SPP
(1,4,16,64; PENUMBRA_BENCH_ET_SPP_<PRESET> for one preset's own), interleaved
in this one process after a warm-up render per method,
PENUMBRA_BENCH_ET_REPEATS (4) seeds, 2 threads; the reference is the plain
ramp at PENUMBRA_BENCH_ET_REF (2048) spp. Scenes: PENUMBRA_BENCH_ET_SCENES
(all of colormap_render.SCENES), their size factor times
PENUMBRA_BENCH_ET_SCALE on 192×108 (0.5); lit_plane and lit_torus are the
lit scene (colormap_equal_time.new_lit_scene). Errors over the whole image and
over the pixels at least 2 px from the background. PENUMBRA_BENCH_ET_RESUME=1
keeps the scenes an earlier run already wrote to OUT.json. See
bench/helpers/colormap_equal_time.py."""

import json
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import bpy  # noqa: E402
from bench.helpers import colormap_equal_time as equal_time  # noqa: E402
from bench.blender_scripts.colormap_render import SCENES, interior_mask  # noqa: E402
from penumbra.colormap import filter_quality  # noqa: E402


def _ints(name, default):
    return [int(v) for v in os.environ.get(name, default).split(",") if v]


def _counts(presets):
    """{method: [spp, ...]}: PENUMBRA_BENCH_ET_SPP for every preset unless
    PENUMBRA_BENCH_ET_SPP_<PRESET> gives its own."""
    counts = {equal_time.PLAIN: _ints("PENUMBRA_BENCH_ET_PLAIN_SPP", "1,4,16,64,256")}
    default = os.environ.get("PENUMBRA_BENCH_ET_SPP", "1,4,16,64")
    counts.update({p: _ints("PENUMBRA_BENCH_ET_SPP_" + p, default) for p in presets})
    return counts


def sweep_scene(name, scale, presets, counts, data, folder):
    """One scene's entry of the results: its renders, equal-time ratios over
    the whole image and away from silhouettes (colormap_render.interior_mask),
    load average and seconds."""
    if name.startswith("lit_"):     # issue #25's lit scene: lit_plane, lit_torus
        scene, obj, material = equal_time.new_lit_scene(name[len("lit_"):], scale)
    else:
        scene, obj, material = equal_time.new_bench_scene(name, scale)
    materials = {equal_time.PLAIN: material}
    for preset in presets:
        materials[preset] = equal_time.bake_quality(scene, obj, material, preset, os.path.join(folder, name, "lut"))
    renderer = equal_time.Renderer(scene, obj, materials, folder)
    reference = equal_time.reference_image(renderer, data["reference_spp"])
    mask = interior_mask(reference[..., :3])
    load_before = os.getloadavg()
    started = time.perf_counter()
    results = equal_time.sweep(renderer, reference, counts, data["repeats"], mask=mask)
    return {"size": [scene.render.resolution_x, scene.render.resolution_y],
            "interior_pixels": int(mask.sum()), "pixels": int(mask.size),
            "results": {m: {str(s): e for s, e in rows.items()} for m, rows in results.items()},
            "ratios": {p: {clock: {str(s): r for s, r in equal_time.equal_time_ratios(results, p, clock).items()}
                           for clock in ("wall", "cpu")} for p in presets},
            "ratios_interior": {p: {clock: {str(s): r for s, r in equal_time.equal_time_ratios(
                results, p, clock, "rmse_interior").items()} for clock in ("wall", "cpu")} for p in presets},
            "load_average": [load_before, os.getloadavg()], "seconds": time.perf_counter() - started}


def main(out_path):
    scale = float(os.environ.get("PENUMBRA_BENCH_ET_SCALE", "0.5"))
    repeats = int(os.environ.get("PENUMBRA_BENCH_ET_REPEATS", "4"))
    presets = [p for p in os.environ.get("PENUMBRA_BENCH_ET_PRESETS", ",".join(filter_quality.QUALITIES)).split(",")
               if p]
    counts = _counts(presets)
    data = {"blender": bpy.app.version_string, "size": [round(192 * scale), round(108 * scale)],
            "repeats": repeats, "threads": 2, "spp": counts,
            "reference_spp": int(os.environ.get("PENUMBRA_BENCH_ET_REF", "2048")), "scenes": {}}
    if os.path.isfile(out_path) and os.environ.get("PENUMBRA_BENCH_ET_RESUME", "0") not in ("", "0"):
        with open(out_path) as f:
            data["scenes"] = json.load(f).get("scenes", {})     # an interrupted run keeps its finished scenes
    folder = os.path.splitext(out_path)[0] + "_renders"
    os.makedirs(folder, exist_ok=True)
    for name in os.environ.get("PENUMBRA_BENCH_ET_SCENES", ",".join(SCENES)).split(","):
        if name in data["scenes"]:
            continue
        data["scenes"][name] = sweep_scene(name, scale, presets, counts, data, folder)
        with open(out_path + ".tmp", "w") as f:
            json.dump(data, f, indent=1)
        os.replace(out_path + ".tmp", out_path)
        print(f"equal time: {name} done in {data['scenes'][name]['seconds']:.0f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1])
