"""Where Blender keeps its OpenColorIO config, so Penumbra converts colour with
the same names and transforms the user sees in Blender's colour menus."""

import os

import bpy


def blender_config_path():
    """Path of the config.ocio this Blender uses ($OCIO wins, as in Blender)."""
    env = os.environ.get("OCIO")
    if env and os.path.isfile(env):
        return env
    datafiles = bpy.utils.system_resource("DATAFILES")
    path = os.path.join(datafiles, "colormanagement", "config.ocio") if datafiles else ""
    if os.path.isfile(path):
        return path
    raise RuntimeError(
        "Blender's OpenColorIO config (datafiles/colormanagement/config.ocio) was not found; "
        "set $OCIO to a config file"
    )


def blender_config():
    """A _penumbra.ColorConfig for Blender's own config."""
    from . import native
    return native.require().ColorConfig(blender_config_path())
