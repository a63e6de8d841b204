"""The demo inside one Blender (run by examples/demo.py; works on its own too):

    blender -b --factory-startup --python examples/demo_blender.py -- --out out/blender-3.4
    .venv/bin/python examples/demo_blender.py --out out/bpy-4.5 [--quick]

Loads the add-on from build/addon the way any batch script can, then runs
each tool's part of the demo: examples/demo_<tool>.py defines
`run(out_folder, demo) -> dict` and reports each step through
`demo.step(...)`, which prints one line starting with STEP_PREFIX (the only
lines examples/demo.py shows; Blender's own output goes to its log). Writes
one contact sheet per tool (<tool>-sheet.png) and summary.json, with every
step, beside the pictures. --quick: smaller pictures and fewer samples,
every step still run (the test of the demo uses it)."""

import argparse
import importlib.util
import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "addon"))
sys.path.insert(0, os.path.join(ROOT, "examples"))

import penumbra  # noqa: E402
from demo import STEP_PREFIX  # noqa: E402  (examples/demo.py reads these lines)
from penumbra import color, native  # noqa: E402

TOOLS = ("visibility", "light_rig", "colormap")  # examples/demo_<tool>.py, in this order


class Demo:
    """What a tool's demo is given: where its sheet goes, whether to run
    small, and `step()` to report what it made."""

    def __init__(self, out, quick):
        self.out, self.quick = out, quick
        self.steps = []

    def step(self, name, made, error, seconds):
        """One finished step: what was made, its error against the reference
        (or "" when it has none) and the seconds it took."""
        entry = {"step": name, "made": made, "error": error, "seconds": round(seconds, 2)}
        self.steps.append(entry)
        print(STEP_PREFIX + json.dumps(entry, ensure_ascii=False), flush=True)

    def sheet_path(self, tool):
        return os.path.join(self.out, f"{tool}-sheet.png")


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--quick", action="store_true", help="small pictures, few samples, every step")
    parser.add_argument("--hdri", default="forest.exr", help="one of Blender's bundled studio-light worlds")
    parser.add_argument("--tools", default=",".join(TOOLS), help="which tools' demos to run, comma-separated")
    return parser.parse_args(argv)


def bundled_world(name):
    path = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", name)
    if not os.path.isfile(path):
        raise SystemExit(f"demo: Blender's bundled world '{name}' was not found")
    return path


def hdri_round_trip(out, hdri_name, demo):
    """Image I/O and colour management: a bundled HDRI in, EXR and PNG out."""
    started = time.perf_counter()
    core = native.require()
    source = bundled_world(hdri_name)
    config = color.blender_config()
    image = core.image.read(source)
    stem = os.path.splitext(hdri_name)[0]
    exr = os.path.join(out, f"{stem}_roundtrip.exr")
    core.image.write_exr(exr, image, half=True, colorspace=config.scene_linear)
    # A viewable picture: scene-linear to sRGB display, 16-bit PNG.
    display = config.convert(image, config.scene_linear, "sRGB")
    png = os.path.join(out, f"{stem}_srgb.png")
    core.image.write_png16(png, display, colorspace="sRGB")
    back = core.image.read(exr)
    error = float(abs(back - image).max())
    demo.step("image I/O", f"{os.path.basename(exr)}, {os.path.basename(png)}",
              f"max |Δ| {error:.2g} after half EXR", time.perf_counter() - started)
    return {"source": source, "size": [int(image.shape[1]), int(image.shape[0])], "exr": exr, "png": png,
            "max_abs_error_half_exr": error, "peak_radiance": float(image.max())}


def tool_demo(name):
    path = os.path.join(ROOT, "examples", f"demo_{name}.py")
    spec = importlib.util.spec_from_file_location(f"demo_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main():
    args = parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    demo = Demo(out, args.quick)
    started = time.perf_counter()
    penumbra.register()
    try:
        summary = {
            "blender": bpy.app.version_string,
            "quick": args.quick,
            "core": native.require().build_info(),
            "hdri_round_trip": hdri_round_trip(out, args.hdri, demo),
        }
        for name in [t for t in TOOLS if t in args.tools.split(",")]:
            tool_out = os.path.join(out, name)
            os.makedirs(tool_out, exist_ok=True)
            summary[name] = tool_demo(name).run(tool_out, demo)
    finally:
        penumbra.unregister()
    summary["steps"] = demo.steps
    summary["seconds"] = round(time.perf_counter() - started, 3)
    path = os.path.join(out, "summary.json")
    with open(path + ".tmp", "w") as f:
        json.dump(summary, f, indent=2, ensure_ascii=False)
    os.replace(path + ".tmp", path)
    print(f"demo ({bpy.app.version_string}): wrote {out}")


main()
