#!/usr/bin/env python3
"""Runs the C++ per-frame timing benchmark of the light-rig pipeline
(bench/cpp/lights_bench.cpp) and writes docs/lights-timing.md."""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    exe = os.path.join(ROOT, "build", "bench", "penumbra_lights_bench")
    if not os.path.exists(exe):
        sys.exit("build/bench/penumbra_lights_bench is missing; run `make build`")
    sys.exit(subprocess.run([exe, "/usr/share/blender/datafiles/studiolights/world/forest.exr",
                             os.path.join(ROOT, "docs", "lights-timing.md")], cwd=ROOT).returncode)


if __name__ == "__main__":
    main()
