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
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Sidebar > Penumbra",
    "description": "Shadowed relighting of rigged meshes, light rigs from HDR video, filtered colour maps",
    "category": "Lighting",
}

if "bpy" in locals():
    # Re-running the add-on's __init__ (F8 / script reload): reload submodules
    # so edits take effect, in dependency order.
    import importlib
    for _name in ("native", "color", "visibility", "lights", "colormap", "properties", "preferences", "panels"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy  # noqa: E402

from . import native, color, visibility, lights, colormap, properties, preferences, panels  # noqa: E402

# Settings first (operators and panels refer to them), then each tool's
# operators and handlers, then the panels that draw them.
_modules = (properties, preferences, visibility, lights, colormap, panels)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
