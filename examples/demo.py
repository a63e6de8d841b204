#!/usr/bin/env python3
"""Penumbra's main job, headless: runs examples/demo_blender.py inside the
three Blenders (Debian's `blender` 3.4, the bpy 4.5 module in .venv and the
bpy 5.2 module in .venv313) and writes everything under --out (default out/).
`make demo` calls this."""

import argparse
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "examples", "demo_blender.py")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=os.path.join(ROOT, "out"))
    args = parser.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)

    runs = []
    blender = shutil.which("blender")
    if not blender:
        sys.exit("demo: Debian's `blender` is missing; run scripts/install_deps.sh (make demo does)")
    runs.append(("blender-3.4", [blender, "-b", "--factory-startup", "--python-exit-code", "1",
                                 "--python", SCRIPT, "--", "--out", os.path.join(out, "blender-3.4")]))
    for name, venv in (("bpy-4.5", ".venv"), ("bpy-5.2", ".venv313")):
        runs.append((name, [os.path.join(ROOT, venv, "bin", "python"), SCRIPT, "--out", os.path.join(out, name)]))
    failed = []
    for name, command in runs:
        print(f"=== demo in {name} ===", flush=True)
        if subprocess.run(command, cwd=ROOT).returncode != 0:
            failed.append(name)
    if failed:
        sys.exit(f"demo failed in: {', '.join(failed)}")
    print(f"demo: outputs written under {out}")


if __name__ == "__main__":
    main()
