"""The demo inside one Blender (run by examples/demo.py; works on its own too):

    blender -b --factory-startup --python examples/demo_blender.py -- --out out/blender-3.4
    .venv/bin/python examples/demo_blender.py --out out/bpy-4.5

Loads the add-on from build/addon the way any batch script can, then runs
each tool's part of the demo: every examples/demo_<tool>.py defines
`run(out_folder) -> dict` and is run in name order. Writes summary.json
beside the pictures."""

import argparse
import glob
import importlib.util
import json
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "addon"))

import penumbra  # noqa: E402
from penumbra import color, native  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--hdri", default="forest.exr", help="one of Blender's bundled studio-light worlds")
    return parser.parse_args(argv)


def bundled_world(name):
    path = os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", name)
    if not os.path.isfile(path):
        raise SystemExit(f"demo: Blender's bundled world '{name}' was not found")
    return path


def hdri_round_trip(out, hdri_name):
    """Image I/O and colour management: a bundled HDRI in, EXR and PNG out."""
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
    return {
        "source": source,
        "size": [int(image.shape[1]), int(image.shape[0])],
        "exr": exr,
        "png": png,
        "max_abs_error_half_exr": float(abs(back - image).max()),
        "peak_radiance": float(image.max()),
    }


def tool_demos():
    for path in sorted(glob.glob(os.path.join(ROOT, "examples", "demo_*.py"))):
        name = os.path.splitext(os.path.basename(path))[0]
        if name == "demo_blender":
            continue
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield name[len("demo_"):], module


def main():
    args = parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    started = time.perf_counter()
    penumbra.register()
    try:
        summary = {
            "blender": bpy.app.version_string,
            "core": native.require().build_info(),
            "hdri_round_trip": hdri_round_trip(out, args.hdri),
        }
        for name, module in tool_demos():
            print(f"demo: {name}", flush=True)
            tool_out = os.path.join(out, name)
            os.makedirs(tool_out, exist_ok=True)
            summary[name] = module.run(tool_out)
    finally:
        penumbra.unregister()
    summary["seconds"] = round(time.perf_counter() - started, 3)
    path = os.path.join(out, "summary.json")
    with open(path + ".tmp", "w") as f:
        json.dump(summary, f, indent=2)
    os.replace(path + ".tmp", path)
    print(f"demo ({bpy.app.version_string}): wrote {out}")


main()
