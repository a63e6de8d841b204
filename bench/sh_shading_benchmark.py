#!/usr/bin/env python3
"""Pose shading speed: runs build/bench/penumbra_pose_shading_bench (C++,
sh/pose_shading.hpp) and writes its table, with the machine it ran on, to
docs/sh-shading-benchmark.md. `--quick` for a short smoke run (not written)."""

import datetime
import os
import platform
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
EXE = os.path.join(BUILD, "bench", "penumbra_pose_shading_bench")
OUT = os.path.join(ROOT, "docs", "sh-shading-benchmark.md")


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def build_flags():
    """-march the core was built with (CMakeLists.txt: PENUMBRA_NATIVE)."""
    try:
        with open(os.path.join(BUILD, "CMakeCache.txt")) as f:
            native = re.search(r"^PENUMBRA_NATIVE:BOOL=(\w+)", f.read(), re.M)
        return "-march=native" if native and native.group(1).upper() in ("ON", "TRUE", "1") else "-march=x86-64-v2"
    except OSError:
        return "unknown"


def main():
    quick = "--quick" in sys.argv
    if not os.path.exists(EXE):
        sys.exit(f"{EXE} is missing: run `make build` first")
    load_before = os.getloadavg()[0]
    result = subprocess.run([EXE] + (["--quick"] if quick else []), capture_output=True, text=True, check=True)
    table = result.stdout.strip()
    print(table)
    if quick:
        return
    text = f"""# Pose shading benchmark

Written by `bench/sh_shading_benchmark.py` (`make bench BENCH=pose_shading`), which runs
`bench/cpp/pose_shading_bench.cpp`. What is measured and why: docs/sh-engine.md.

- machine: {cpu_model()}, {os.cpu_count()} hardware threads; load average {load_before:.2f} when it started
  (the development machine is shared, so multi-thread rows are the noisiest)
- build: Release, {build_flags()}; {datetime.date.today().isoformat()}
- one pose = every vertex shaded once; ns/vertex = median wall time / vertices
- **stream**: a loop over the same vertices that reads every input value the shader reads
  and writes the same float32 RGB output, with the same thread count, in the same run
  (the memory-bandwidth floor); **× stream** = how far above that floor the shader is
- inputs: random unit-ish normals, tangents, lobes (order-many bands each), positions;
  Phong exponent 32, local viewer; `reference` = the straightforward path of
  `tests/cpp/sh/pose_shading_reference.hpp` (full Ivanic–Ruedenberg rotation of the RGB
  lighting into every vertex's frame), single thread, float64

{table}
"""
    tmp = OUT + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, OUT)
    print(f"wrote {os.path.relpath(OUT, ROOT)}")


if __name__ == "__main__":
    main()
