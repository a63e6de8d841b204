"""The one line a script run inside Blender hands back to the process that
started it (`RESULT {json}`, which result_line reads), whatever happens,
and a window's Blender quit afterwards as a user would (it would stay open
after the script)."""

import json
import traceback

import bpy

from bench.helpers.result_line import PREFIX


def report(body):
    """Runs body(result) on a dict that already names the Blender; prints
    it with ok true, or ok false and the traceback."""
    result = {"blender": bpy.app.version_string, "background": bool(bpy.app.background)}
    try:
        body(result)
        result["ok"] = True
    except Exception:
        result["ok"] = False
        result["error"] = traceback.format_exc()
    print(PREFIX + json.dumps(result), flush=True)
    if not bpy.app.background:
        bpy.ops.wm.quit_blender()
