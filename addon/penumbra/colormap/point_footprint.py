"""The "Penumbra Point Footprint" group: Pixel Size, Orthographic ->
Footprint, Minor, Major: the footprint ellipse's axes from the view depth
and the angle between the view ray and the normal, for the one-evaluation
filter (point_filter.py). Eight nodes where "Penumbra Pixel Footprint"
(footprint.py) has about 150: measured in Cycles on the benchmark plane,
that group alone took longer per sample than the whole plain ramp."""

import bpy

from .footprint import HORIZON_REACH
from .node_builder import Builder, new_group
from .node_groups import POINT_FOOTPRINT


def point_footprint_group():
    """Minor = the pixel's width across the view ray at the point (Pixel
    Size times View Z Depth; orthographic: Pixel Size), Major = Minor / |N·I|
    (the width stretched along the surface by the view's slant, bounded at
    HORIZON_REACH times Minor), Footprint = √(Minor·Major). Off the optical
    axis the width along the image's radius is larger by 1/cos of the
    off-axis angle, which this leaves out (under 7 % inside a 50° lens)."""
    group = bpy.data.node_groups.get(POINT_FOOTPRINT)
    if group is not None:
        return group
    group, gin, gout = new_group(POINT_FOOTPRINT, [("Pixel Size", "NodeSocketFloat", 0.001),
                                                   ("Orthographic", "NodeSocketFloat", 0.0)],
                                 [("Footprint", "NodeSocketFloat"), ("Minor", "NodeSocketFloat"),
                                  ("Major", "NodeSocketFloat")])
    b = Builder(group)
    geometry = b.place(b.nodes.new("ShaderNodeNewGeometry"))
    camera = b.place(b.nodes.new("ShaderNodeCameraData"))
    orthographic = gin.outputs["Orthographic"]
    depth = b.math("MULTIPLY_ADD", camera.outputs["View Z Depth"], b.math("SUBTRACT", 1.0, orthographic),
                   orthographic)
    minor = b.math("MULTIPLY", depth, gin.outputs["Pixel Size"])
    slant = b.math("MAXIMUM", b.math("ABSOLUTE", b.vmath("DOT_PRODUCT", geometry.outputs["Normal"],
                                                           geometry.outputs["Incoming"])), 1.0 / HORIZON_REACH)
    major = b.math("DIVIDE", minor, slant)
    b.links.new(minor, gout.inputs["Minor"])
    b.links.new(major, gout.inputs["Major"])
    b.links.new(b.math("SQRT", b.math("MULTIPLY", minor, major)), gout.inputs["Footprint"])
    return group
