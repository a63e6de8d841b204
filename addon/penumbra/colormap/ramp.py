"""Reading a ColorRamp node and finding what drives it (bpy side only)."""

import numpy as np


def ramp_stops(node):
    """(count, 5) float32: position, r, g, b, a of each stop (scene-linear)."""
    elements = node.color_ramp.elements
    stops = np.zeros((len(elements), 5), np.float32)
    for i, e in enumerate(elements):
        stops[i, 0] = e.position
        stops[i, 1:] = tuple(e.color)
    return stops


def ramp_modes(node):
    ramp = node.color_ramp
    return ramp.interpolation, ramp.color_mode, ramp.hue_interpolation


def driving_socket(node):
    """The output socket linked into the ramp's Fac input, or None."""
    links = node.inputs["Fac"].links  # "Fac" also finds 5.x's "Factor" (its identifier)
    return links[0].from_socket if links else None


def driving_noise(node):
    """The Noise (or 3.x Musgrave) Texture node that drives the ramp directly,
    or None. Any of its outputs counts: the bake then says whether that
    output's statistics can be derived (noise_model.read_noise)."""
    socket = driving_socket(node)
    if socket is None:
        return None
    source = socket.node
    if source.bl_idname in ("ShaderNodeTexNoise", "ShaderNodeTexMusgrave"):
        return source
    return None
