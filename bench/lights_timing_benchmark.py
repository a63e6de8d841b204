#!/usr/bin/env python3
"""Runs the C++ per-frame timing benchmark of the light-rig pipeline
(bench/cpp/lights_bench.cpp) and writes docs/lights-timing-benchmark.md, then the
angular-region culling section (brute-force irradiance against the region
table, `penumbra_lights_bench --regions`), then measures a 16384x8192 map: time and peak RSS of the streamed read against reading the
whole file first (one process each), and of bpy.ops.penumbra.build_light_rig
in the bpy module. The 16k EXR is made from a bundled HDRI (bilinear
upsampling) in a temporary folder and deleted afterwards.

--only-regions re-runs just the culling section, --only-16k just the 16k
one; each replaces its own section of the existing file."""

import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORLD = "/usr/share/blender/datafiles/studiolights/world/forest.exr"
OUT = os.path.join(ROOT, "docs", "lights-timing-benchmark.md")

# Runs inside the bpy module (a fresh process): operator on the 16k file.
BPY_SCRIPT = r"""
import os, resource, sys, time, traceback
sys.path.insert(0, sys.argv[1])
import bpy
import penumbra
penumbra.register()
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t0 = time.perf_counter()
if sys.argv[3] == "run":
  try:
    r = bpy.ops.penumbra.build_light_rig(filepath=sys.argv[2], count=64, frame_start=1, frame_end=1,
                                         json_path=sys.argv[2] + ".json")
    assert r == {"FINISHED"}, r
    coll = bpy.context.scene.penumbra.light_rig.collection
    assert len([o for o in coll.objects if o.type == "LIGHT"]) == 64
  except Exception:
    traceback.print_exc()
    sys.exit(1)
t = time.perf_counter() - t0
print("RESULT", t * 1000, base, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
penumbra.unregister()
"""


def run_16k(exe, tmp):
    path = os.path.join(tmp, "map16k.exr")
    t0 = time.perf_counter()
    subprocess.run([exe, "--make-16k", WORLD, path], check=True)
    make_s = time.perf_counter() - t0
    size_mb = os.path.getsize(path) / 2**20
    rows = {}
    for mode in ("whole", "stream"):
        out = subprocess.run([exe, "--read-16k", path, mode], check=True, capture_output=True, text=True).stdout
        read_ms, total_ms, rss, active = out.split()
        rows[mode] = (float(read_ms), float(total_ms), float(rss), int(active))
        print(mode, rows[mode])
    bpy_row = None
    python = os.path.join(ROOT, ".venv", "bin", "python")
    if os.path.exists(python):
        script = os.path.join(tmp, "bpy_16k.py")
        with open(script, "w") as f:
            f.write(BPY_SCRIPT)
        addon = os.path.join(ROOT, "build", "addon")
        res = subprocess.run([python, script, addon, path, "run"], capture_output=True, text=True, timeout=300)
        line = [x for x in res.stdout.splitlines() if x.startswith("RESULT")]
        if res.returncode == 0 and line:
            ms, base, peak = (float(v) for v in line[0].split()[1:])
            bpy_row = (ms, base, peak)
            print("bpy", bpy_row)
        else:
            print(res.stdout[-2000:], res.stderr[-2000:])
    whole, stream = rows["whole"], rows["stream"]
    md = [
        "",
        "## A 16384x8192 map",
        "",
        f"`{os.path.basename(WORLD)}` upsampled (bilinear) to 16384x8192, half-float ZIP EXR ({size_mb:.0f} MB on disk, "
        f"made in {make_s:.0f} s, deleted afterwards). One process per row, so each peak RSS (resident memory, "
        "getrusage) is its own. Working map 2048x1024; rig = 64 lights, region powers, Havran. `stream` is what the "
        "add-on does (`lights/map_reader.hpp`: read_scanlines band by band, reduce as the rows arrive); `whole` "
        "reads the file into memory with core/image first (the previous behaviour). Machine: 2 cores, shared.",
        "",
        "| read | working map (ms) | map + rig (ms) | peak RSS (MB) | ratio RSS vs whole | ratio time vs whole |",
        "|---|---|---|---|---|---|",
        f"| whole (baseline) | {whole[0]:.0f} | {whole[1]:.0f} | {whole[2]:.0f} | 1.00x | 1.00x |",
        f"| stream | {stream[0]:.0f} | {stream[1]:.0f} | {stream[2]:.0f} | {stream[2] / whole[2]:.3f}x "
        f"| {stream[1] / whole[1]:.2f}x |",
        "",
        "The float RGB image alone would be 16384 x 8192 x 3 x 4 B = 1536 MB (and read_image briefly holds the "
        "file's channels as well).",
    ]
    if bpy_row is not None:
        ms, base, peak = bpy_row
        md += ["",
               f"`bpy.ops.penumbra.build_light_rig` on the same file in the bpy 4.5 module (one frame, 64 lights): "
               f"{ms / 1000:.1f} s; peak RSS {peak:.0f} MB, of which {base:.0f} MB is bpy with the add-on "
               f"registered before the operator runs (the operator adds {peak - base:.0f} MB)."]
    return "\n".join(md) + "\n"


def replace_section(text, marker, section):
    """Replaces the section starting at `marker` (up to the next "## " heading)
    with `section`, or appends it when absent."""
    if marker in text:
        start = text.index(marker)
        end = text.find("\n## ", start + len(marker))
        end = len(text) if end < 0 else end
        return text[:start].rstrip("\n") + "\n" + section + text[end:]
    return text.rstrip("\n") + "\n" + section


def main():
    exe = os.path.join(ROOT, "build", "bench", "penumbra_lights_bench")
    if not os.path.exists(exe):
        sys.exit("build/bench/penumbra_lights_bench is missing; run `make build`")
    only_regions, only_16k = "--only-regions" in sys.argv, "--only-16k" in sys.argv
    if not only_regions and not only_16k:
        rc = subprocess.run([exe, WORLD, OUT], cwd=ROOT).returncode
        if rc:
            sys.exit(rc)
    if not only_16k:
        regions = subprocess.run([exe, "--regions", WORLD], check=True, capture_output=True, text=True).stdout
        print(regions)
        with open(OUT) as f:
            text = f.read()
        with open(OUT, "w") as f:
            f.write(replace_section(text, "\n## Angular-region culling", regions))
    if not only_regions:
        tmp = tempfile.mkdtemp(prefix="penumbra_lights_16k_")
        try:
            section = run_16k(exe, tmp)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        with open(OUT) as f:
            text = f.read()
        with open(OUT, "w") as f:
            f.write(replace_section(text, "\n## A 16384x8192 map", section))
    print("wrote", OUT)


if __name__ == "__main__":
    main()
