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
    """A _penumbra.color.Config for Blender's own config."""
    from . import native
    return native.require().color.Config(blender_config_path())


def working_space(config):
    """Name of the colour space Blender calls scene linear: the space of
    render results, light and World colours, ColorRamp stops and float image
    buffers. Blender 5.0 made it a setting of each .blend file, the working
    space (Render Properties > Color Management > Working Space;
    bpy.data.colorspace.working_space, changed with
    bpy.ops.wm.set_working_color_space): Linear Rec.709 by default, or Linear
    Rec.2020 or ACEScg, while the config's scene_linear role stays Linear
    Rec.709. Before 5.0 it is always the config's scene_linear role."""
    name = file_working_space()
    if name and config.has_colorspace(name):
        return name
    return config.scene_linear


def file_working_space():
    """The open file's working space setting (Blender 5.0+), else None."""
    if bpy.app.version >= (5, 0, 0):
        return bpy.data.colorspace.working_space
    return None


def to_working_space(config, pixels, from_space):
    """(H, W, 3) float32 pixels in `from_space` converted to Blender's
    scene-linear working space (working_space); unchanged when they are
    already in it. The core's to_scene_linear converts to the config's
    scene_linear role, which is the working space only in a file that uses
    the default one."""
    target = working_space(config)
    if from_space == target:
        return pixels
    return config.convert(pixels, from_space, target)
