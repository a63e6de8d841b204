"""Reading a ColorRamp node and finding what drives it (bpy side only)."""

import bpy
import numpy as np

from .. import node_links

# Entries of the table a renderer evaluates a ColorRamp through (measured by
# tests/blender/colormap/test_ramp_table.py): Cycles in Blender 3.x samples
# 256 at i/255 (RAMP_TABLE_SIZE); EEVEE in every version, and Cycles in 4.5
# and 5.2, Blender's colour-band table of 257 at i/256. In constant mode the
# steps sit on those entries, so a lookup built from the wrong table moves
# every step by up to one entry: a colour bias that no sample count removes.
CYCLES_3X_TABLE_SIZE = 256
COLORBAND_TABLE_SIZE = 257


def ramp_stops(node):
    """(count, 5) float32: position, r, g, b, a of each stop (scene-linear)."""
    elements = node.color_ramp.elements
    stops = np.zeros((len(elements), 5), np.float32)
    for i, e in enumerate(elements):
        stops[i, 0] = e.position
        stops[i, 1:] = tuple(e.color)
    return stops


def renderer_table_size(scene):
    """The ramp table size of the scene's render engine (see above). Cycles
    4.0-4.4 were not measured; they are taken to be like 4.5."""
    if scene.render.engine == "CYCLES" and bpy.app.version < (4, 0, 0):
        return CYCLES_3X_TABLE_SIZE
    return COLORBAND_TABLE_SIZE


def ramp_modes(node):
    ramp = node.color_ramp
    return ramp.interpolation, ramp.color_mode, ramp.hue_interpolation


def driving(node):
    """node_links.Feed of the ramp's Fac: what really drives it, through
    reroutes, muted nodes and node groups, never a muted link."""
    return node_links.feed(node.inputs["Fac"])  # "Fac" also finds 5.x's "Factor" (its identifier)


def driving_socket(node):
    """The output socket that really drives the ramp's Fac, or None; inside a
    node group when driving(node).path says so."""
    return driving(node).output


def fac_source_in_tree(node):
    """The socket of the ramp's own tree to link in place of its Fac, or None
    (node_links.source_in_tree)."""
    return node_links.source_in_tree(node.inputs["Fac"])


def driving_noise(node):
    """The Noise (or 3.x Musgrave) Texture node that drives the ramp, or None.
    Any of its outputs counts: the bake then says whether that output's
    statistics can be derived (noise_model.read_noise)."""
    source = driving(node).node
    if source is not None and source.bl_idname in ("ShaderNodeTexNoise", "ShaderNodeTexMusgrave"):
        return source
    return None
