"""Equal-time sweep of the Noise Filter's quality presets in Cycles (issue
#25), run by bench/colormap_benchmark.py (section "Equal time"):

    .venv/bin/python bench/blender_scripts/colormap_equal_time.py -- OUT.json

Per scene: the plain ramp at PENUMBRA_BENCH_ET_PLAIN_SPP (1,4,16,64,256) and
every preset at PENUMBRA_BENCH_ET_SPP (1,4,16,64), interleaved in this one
process after a warm-up render per method, PENUMBRA_BENCH_ET_REPEATS (3)
seeds, 2 threads; the reference is the plain ramp at PENUMBRA_BENCH_ET_REF
(2048) spp. Scenes: PENUMBRA_BENCH_ET_SCENES (plane), size factor
PENUMBRA_BENCH_ET_SCALE on 192×108 (0.5). See bench/helpers/colormap_equal_time.py."""

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
from penumbra.colormap import filter_quality  # noqa: E402

# The scenes of colormap_render.SCENES this sweep can build (planes: the
# helper's scene is the benchmark plane with these options).
PLANES = {"plane": {}, "constant": None, "detail_8_distortion": {"detail": 8.0, "distortion": 0.5},
          "grazing": {"camera_location": (0.0, -2.0, 0.6), "camera_rotation_degrees": (87.5, 0.0, 0.0)}}


def _ints(name, default):
    return [int(v) for v in os.environ.get(name, default).split(",") if v]


def main(out_path):
    scale = float(os.environ.get("PENUMBRA_BENCH_ET_SCALE", "0.5"))
    size = (round(192 * scale), round(108 * scale))
    repeats = int(os.environ.get("PENUMBRA_BENCH_ET_REPEATS", "3"))
    presets = [p for p in os.environ.get("PENUMBRA_BENCH_ET_PRESETS", ",".join(filter_quality.QUALITIES)).split(",")
               if p]
    counts = {equal_time.PLAIN: _ints("PENUMBRA_BENCH_ET_PLAIN_SPP", "1,4,16,64,256")}
    counts.update({p: _ints("PENUMBRA_BENCH_ET_SPP", "1,4,16,64") for p in presets})
    data = {"blender": bpy.app.version_string, "size": size, "repeats": repeats, "threads": 2,
            "reference_spp": int(os.environ.get("PENUMBRA_BENCH_ET_REF", "2048")), "scenes": {}}
    folder = os.path.splitext(out_path)[0] + "_renders"
    os.makedirs(folder, exist_ok=True)
    for name in os.environ.get("PENUMBRA_BENCH_ET_SCENES", "plane").split(","):
        options = PLANES[name]
        if options is None:     # the four-stop Constant ramp
            import colormap_scene
            options = {"interpolation": "CONSTANT", "stops": colormap_scene.CONSTANT_STOPS}
        scene, plane, material = equal_time.new_plane_scene(size, **options)
        materials = {equal_time.PLAIN: material}
        for preset in presets:
            materials[preset] = equal_time.bake_quality(scene, plane, material, preset,
                                                        os.path.join(folder, name, "lut"))
        renderer = equal_time.Renderer(scene, plane, materials, folder)
        reference = equal_time.reference_image(renderer, data["reference_spp"])
        load_before = os.getloadavg()
        started = time.perf_counter()
        results = equal_time.sweep(renderer, reference, counts, repeats)
        data["scenes"][name] = {
            "results": {m: {str(s): e for s, e in rows.items()} for m, rows in results.items()},
            "ratios": {p: {clock: {str(s): r for s, r in equal_time.equal_time_ratios(results, p, clock).items()}
                           for clock in ("wall", "cpu")} for p in presets},
            "load_average": [load_before, os.getloadavg()], "seconds": time.perf_counter() - started}
        with open(out_path, "w") as f:
            json.dump(data, f, indent=1)
        print(f"equal time: {name} done in {time.perf_counter() - started:.0f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1])
