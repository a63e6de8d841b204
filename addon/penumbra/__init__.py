# Penumbra: shadowed relighting of rigged meshes, light rigs from HDR video,
# and filtered colour-map lookups, for Blender 3.4 and 4.2+.
#
# Blender 3.4 reads `bl_info` below (legacy add-on); Blender 4.2+ reads
# blender_manifest.toml (extension). The compiled core, _penumbra, is loaded
# by native.py; if it cannot load, the add-on still registers and the panel
# says what is wrong instead of the add-on failing to enable.

bl_info = {
    "name": "Penumbra",
    "author": "Penumbra developers",
    "version": (0, 2, 0),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Sidebar > Penumbra",
    "description": "Shadowed relighting of rigged meshes, light rigs from HDR video, filtered colour maps",
    "category": "Lighting",
}

if "bpy" in locals():
    # Re-running the add-on's __init__ (F8 / script reload): reload submodules
    # so edits take effect, in dependency order.
    import importlib
    for _name in ("installed_copies", "native", "errors", "color", "compat", "core_settings", "world", "sidebar",
                  "visibility", "lights", "colormap", "properties", "preferences", "panels"):
        if _name in locals():
            importlib.reload(locals()[_name])

import atexit  # noqa: E402
import sys  # noqa: E402

import bpy  # noqa: E402

from . import installed_copies, native, color, visibility, lights, colormap, properties, preferences, panels  # noqa: E402

# Settings first (operators and panels refer to them), then each tool's
# operators and handlers, then the panels that draw them.
_modules = (properties, preferences, visibility, lights, colormap, panels)


_registered = False


def register():
    global _registered
    kept_preferences = installed_copies.take_over_other_copies(__package__)
    done = []
    try:
        for module in _modules:
            module.register()
            done.append(module)
    except Exception:
        # Leave nothing half-registered: a later register() must work, and
        # leftover callbacks would keep a bpy-module process from exiting.
        for module in reversed(done):
            module.unregister()
        raise
    _registered = True
    installed_copies.carry_preferences(__package__, kept_preferences)
    if _is_bpy_module():
        atexit.register(_unregister_at_exit)


def unregister():
    # Idempotent: at exit Blender may disable the add-on after our own
    # atexit handler (below) already has.
    global _registered
    atexit.unregister(_unregister_at_exit)
    if not _registered:
        return
    _registered = False
    for module in reversed(_modules):
        module.unregister()


# Why a batch script that registers the add-on must unregister it at exit:
# the bpy module (before Blender 5.0) shuts Blender down, and stops its audio
# thread, only when Python frees the `bpy` module object. Our properties'
# update callbacks live in Blender's own memory, and their globals reach
# `bpy`, so that object is never freed; Blender's exit then waits forever on
# the audio thread (GlobalState::~GlobalState). The Blender program avoids
# this by disabling add-ons on quit (bpy.utils._on_exit); a bpy-module
# process has no quit, so the add-on does the same from an atexit handler,
# which runs before Python tears its modules down. docs/packaging.md.
def _is_bpy_module():
    return not bpy.app.binary_path


def _unregister_at_exit():
    try:
        unregister()
    except Exception as error:  # never let exit fail; say why it may hang
        print(f"Penumbra: could not unregister at exit ({error})", file=sys.stderr)
