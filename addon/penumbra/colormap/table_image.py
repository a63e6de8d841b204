"""Small float tables that node groups sample (lookups of noise statistics,
the microsurface table), written as EXR files and loaded as images."""

import os
import tempfile

import bpy
import numpy as np


def default_folder():
    return os.path.join(bpy.app.tempdir or tempfile.gettempdir(), "penumbra_luts")


def relative_to_blend(image):
    """Stores `image`'s path relative to the saved .blend ("//..."), as
    Blender's file browser does by default, so a project folder moved or
    copied with its lookups keeps them. An unsaved file keeps the absolute
    path (Blender remaps it when the file is first saved)."""
    if bpy.data.filepath and not image.filepath.startswith("//"):
        try:
            image.filepath = bpy.path.relpath(image.filepath)
        except ValueError:   # another drive (Windows): no relative path exists
            pass


def table_image(name, pixels, folder=None):
    """A small float table (rows bottom-up as Blender stores them) written as
    EXR by the core and loaded 'Non-Color', so it survives saving the .blend
    (a generated image would come back blank)."""
    from .. import native
    folder = folder or default_folder()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, bpy.path.clean_name(name) + ".exr")
    native.require().image.write_exr(path, np.ascontiguousarray(pixels[::-1], dtype=np.float32), half=False,
                                     colorspace="Non-Color")
    image = bpy.data.images.get(name)
    if image is not None and os.path.normpath(bpy.path.abspath(image.filepath)) == path:
        image.reload()
    else:
        if image is not None:
            image.name = name + " (old)"
        image = bpy.data.images.load(path, check_existing=False)
        image.name = name
        relative_to_blend(image)
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    return image
