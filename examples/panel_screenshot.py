#!/usr/bin/env python3
"""A screenshot of the Penumbra sidebar tab at its default width, taken in a
real Blender window: Debian's Blender 3.4 under Xvfb, each tool's section
open, on a scene with a skinned mesh (active), its armature and a World.

From a shell:

    xvfb-run -a -s "-screen 0 1280x1600x24 -dpi 72" blender --factory-startup \\
        --enable-event-simulate --python examples/panel_screenshot.py -- --output docs/panel.png

(--enable-event-simulate lets the script scroll to the Penumbra tab: Blender
3.4 has no Python setting for a sidebar's active tab; -dpi 72 makes the UI
scale 1.) Or from Python, without Blender, with examples/ on sys.path:

    import panel_screenshot; panel_screenshot.screenshot("docs/panel.png")

or `python examples/panel_screenshot.py --output docs/panel.png`.

Writes the sidebar, cropped from the window to the panels' height, as a PNG
(docs/panel.png by default). Needs `make build` first (the add-on is taken
from build/addon) and `xvfb-run` (scripts/install_deps.sh installs it)."""

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import traceback

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUTPUT = os.path.join(ROOT, "docs", "panel.png")
# Tall enough that the three open sections fit in the sidebar; at 72 dpi Blender's
# UI scale is 1, and the sidebar opens 220 px wide (Xvfb's own 75 dpi makes it 229).
SCREEN = "1280x1600x24 -dpi 72"


# --- Outside Blender: start it under Xvfb -------------------------------------

def command(output=DEFAULT_OUTPUT, blender="blender"):
    """The command line that writes the screenshot to `output`."""
    return ["xvfb-run", "-a", "-s", f"-screen 0 {SCREEN}", blender, "--factory-startup",
            "--enable-event-simulate", "--python", os.path.abspath(__file__), "--",
            "--output", os.path.abspath(output)]


def screenshot(output=DEFAULT_OUTPUT, log_path=None, timeout=300):
    """Runs command(output); Blender's own output goes to `log_path` (or is
    dropped). Returns `output`; raises RuntimeError if nothing was written."""
    for program in ("xvfb-run", "blender"):
        if shutil.which(program) is None:
            raise RuntimeError(f"panel screenshot: `{program}` is missing; run scripts/install_deps.sh")
    if os.path.exists(output):
        os.remove(output)
    with open(log_path or os.devnull, "w") as log:
        # In its own session, so that a timeout stops Xvfb and Blender with it.
        process = subprocess.Popen(command(output), cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                                   start_new_session=True)
        try:
            status = process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            status = f"no exit after {timeout} s"
    if status != 0 or not os.path.exists(output):
        where = f"; see {log_path}" if log_path else ""
        raise RuntimeError(f"panel screenshot: Blender exited with {status}, no {output}{where}")
    return output


# --- Inside Blender ------------------------------------------------------------

def _load_addon():
    """Registers the add-on from build/addon, with each tool's section open."""
    sys.path.insert(0, os.path.join(ROOT, "build", "addon"))
    import penumbra
    from penumbra import panels
    for section in panels.classes():
        if getattr(section, "bl_parent_id", "") == "PENUMBRA_PT_main":
            section.bl_options = set()  # the tool sections start closed; show them open
    penumbra.register()


def _build_scene():
    """The factory scene's Cube, skinned to a new armature and active; its World stays."""
    import bpy
    cube = bpy.data.objects["Cube"]
    rig = bpy.data.objects.new("Armature", bpy.data.armatures.new("Armature"))
    bpy.context.scene.collection.objects.link(rig)
    cube.modifiers.new("Armature", "ARMATURE").object = rig
    bpy.context.view_layer.objects.active = cube
    # The sidebar on its own background, so it can be cropped to its panels.
    bpy.context.preferences.system.use_region_overlap = False


def _view3d(window):
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return area, next(r for r in area.regions if r.type == "UI")


def _press(window, kind, x, y):
    window.event_simulate(type=kind, value="PRESS", x=x, y=y)
    window.event_simulate(type=kind, value="RELEASE", x=x, y=y)


def _open_sidebar(window):
    area, _ = _view3d(window)
    _press(window, "ESC", window.width // 2, window.height // 2)  # the splash screen
    area.spaces[0].show_region_ui = True


def _show_penumbra_tab(window):
    # The wheel over the tab strip steps through the tabs and stops at the
    # last, Penumbra's (add-on tabs come after Blender's own).
    _, region = _view3d(window)
    x, y = region.x + region.width - 8, region.y + region.height // 2
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    for _ in range(12):
        window.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y)


def _save_sidebar(window, output):
    """Screenshot of the window, cropped to the sidebar's panels, as PNG."""
    import bpy
    area, region = _view3d(window)
    with tempfile.TemporaryDirectory() as tmp:
        whole = os.path.join(tmp, "window.png")
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.screen.screenshot(filepath=whole)
        image = bpy.data.images.load(whole)
        pixels = _crop(image, region)
        bpy.data.images.remove(image)
    height, width = pixels.shape[:2]
    cropped = bpy.data.images.new("Penumbra sidebar", width, height, alpha=False)
    cropped.pixels.foreach_set(pixels.ravel())
    cropped.filepath_raw = output
    cropped.file_format = "PNG"
    os.makedirs(os.path.dirname(output), exist_ok=True)
    cropped.save()
    print(f"panel screenshot: {output} ({width}x{height}, sidebar {region.width} px wide)")


def _crop(image, region):
    """The region's pixels (rows bottom-up, as Blender stores them), from its
    top down to a little below the lowest panel."""
    import numpy as np
    pixels = np.empty(image.size[0] * image.size[1] * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(image.size[1], image.size[0], 4)
    sidebar = pixels[region.y:region.y + region.height, region.x:region.x + region.width].copy()
    sidebar[..., 3] = 1.0
    background = sidebar[4, 4, :3]  # above the region's bottom edge, below every panel
    # Rows holding anything but the background; the tab strip (the last unit) and the edge do not count.
    busy = np.abs(sidebar[:, :-24, :3] - background).max(axis=(1, 2)) > 0.02
    busy[:2] = False
    lowest = int(np.argmax(busy)) if busy.any() else 0
    return sidebar[max(lowest - 12, 0):]


def _in_blender(output):
    import bpy
    if bpy.app.background or not bpy.app.use_event_simulate:
        sys.exit("panel screenshot: needs a window and --enable-event-simulate: " + " ".join(command(output)))
    try:
        _load_addon()
        _build_scene()
    except Exception:
        # Quit as a user would; no screenshot is written, which screenshot()
        # reports, with this traceback in the log.
        traceback.print_exc()
        bpy.ops.wm.quit_blender()
        return
    steps = [_open_sidebar, _show_penumbra_tab, None, None, lambda w: _save_sidebar(w, output)]

    def step():
        try:
            action = steps.pop(0)
            if action is not None:
                action(bpy.context.window_manager.windows[0])
            if steps:
                return 0.5
            bpy.ops.wm.quit_blender()
        except Exception:
            traceback.print_exc()  # no screenshot: screenshot() reports it
            bpy.ops.wm.quit_blender()
        return None

    bpy.app.timers.register(step, first_interval=1.0)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output", default=DEFAULT_OUTPUT)
    parser.add_argument("--log", help="outside Blender: where Blender's output goes")
    args = parser.parse_args(argv)
    if "bpy" in sys.modules:  # run by Blender (--python)
        _in_blender(os.path.abspath(args.output))
    else:
        print(f"panel screenshot: {screenshot(args.output, args.log)}")


if __name__ == "__main__":
    main()
