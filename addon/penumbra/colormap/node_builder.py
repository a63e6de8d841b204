"""Writing node arithmetic into a shader node group: Builder
(b.math('MULTIPLY', a, 2.0), bilinear image lookups), new_group (a group
with its sockets, through interface.add_socket in 3.4 and 4.x) and
zero_after, which orders Cycles' evaluation. Used by every node group the
colour map makes."""

import bpy

from . import interface


class Builder:
    """Small helpers to write node arithmetic: math('MULTIPLY', a, 2.0)."""

    def __init__(self, group):
        self.group = group
        self.nodes = group.nodes
        self.links = group.links
        self.x = 0
        self.placed = 0

    def place(self, node):
        # A counter, not len(self.nodes): counting a node collection walks it,
        # and a Noise Filter has thousands of nodes.
        self.placed += 1
        node.location = (self.x, -200 * (self.placed % 6))
        self.x += 60
        return node

    def connect(self, value, socket):
        if isinstance(value, bpy.types.NodeSocket):
            self.links.new(value, socket)
        elif isinstance(value, (tuple, list)):
            socket.default_value = value
        else:
            socket.default_value = float(value)

    def math(self, op, a, b=0.0, c=None, clamp=False):
        node = self.place(self.nodes.new("ShaderNodeMath"))
        node.operation = op
        node.use_clamp = clamp
        self.connect(a, node.inputs[0])
        self.connect(b, node.inputs[1])
        if c is not None:
            self.connect(c, node.inputs[2])
        return node.outputs[0]

    def vmath(self, op, a, b=None):
        node = self.place(self.nodes.new("ShaderNodeVectorMath"))
        node.operation = op
        self.connect(a, node.inputs[0])
        if b is not None:
            self.connect(b, node.inputs[1])
        return node.outputs["Value"] if op in ("DOT_PRODUCT", "LENGTH", "DISTANCE") else node.outputs["Vector"]

    def vscale(self, vector, factor):
        node = self.place(self.nodes.new("ShaderNodeVectorMath"))
        node.operation = "SCALE"
        self.connect(vector, node.inputs[0])
        self.connect(factor, node.inputs["Scale"])
        return node.outputs["Vector"]

    def combine(self, x, y, z=0.0):
        node = self.place(self.nodes.new("ShaderNodeCombineXYZ"))
        self.connect(x, node.inputs[0])
        self.connect(y, node.inputs[1])
        self.connect(z, node.inputs[2])
        return node.outputs[0]

    def texel_fetch(self, image, u, v):
        node = self.place(self.nodes.new("ShaderNodeTexImage"))
        node.image = image
        # Closest: EEVEE samples every other interpolation with mipmaps and
        # anisotropic filtering, chosen from the screen-space derivatives of
        # the coordinates. A lookup indexed by noise jumps across the table
        # between neighbouring pixels, so the GPU picks a coarse mip level and
        # blurs the table (measured: the filter stopped converging in EEVEE,
        # 0.028 RMSE at 64 samples against the plain ramp's 0.013).
        node.interpolation = "Closest"
        node.extension = "EXTEND"   # a lookup must not wrap at its edges
        node.projection = "FLAT"
        self.links.new(self.combine(u, v), node.inputs["Vector"])
        return node

    def image(self, image, u, v, alpha=True):
        """(Color, Alpha) of `image` at (u, v) in [0, 1]², bilinear between
        the four nearest texel centres, fetched as Closest so that no
        renderer's mipmapping takes part (see texel_fetch). alpha=False: the
        tables that keep nothing there get no nodes for it (Alpha is None)."""
        width, height = image.size

        def corners(coordinate, count):
            x = self.math("MULTIPLY_ADD", coordinate, float(count), -0.5)
            base = self.math("FLOOR", x)
            first = self.math("MULTIPLY_ADD", base, 1.0 / count, 0.5 / count)
            return first, self.math("ADD", first, 1.0 / count), self.math("SUBTRACT", x, base)

        u0, u1, fu = corners(u, width)
        v0, v1, fv = corners(v, height)
        rows = []
        for row in (v0, v1):
            left, right = self.texel_fetch(image, u0, row), self.texel_fetch(image, u1, row)
            rows.append((self.lerp_vector(left.outputs["Color"], right.outputs["Color"], fu),
                         self.lerp(left.outputs["Alpha"], right.outputs["Alpha"], fu) if alpha else None))
        return (self.lerp_vector(rows[0][0], rows[1][0], fv),
                self.lerp(rows[0][1], rows[1][1], fv) if alpha else None)

    def lerp(self, a, b, t):
        return self.math("MULTIPLY_ADD", self.math("SUBTRACT", b, a), t, a)

    def lerp_vector(self, a, b, t):
        return self.vmath("ADD", a, self.vscale(self.vmath("SUBTRACT", b, a), t))

    def separate(self, color):
        node = self.place(self.nodes.new("ShaderNodeSeparateColor"))
        self.links.new(color, node.inputs[0])
        return node.outputs[0], node.outputs[1], node.outputs[2]

    def texel(self, fraction, count):
        """Texture coordinate of a fractional table index fraction·(count−1):
        texel centres sit at (i + 0.5) / count."""
        return self.math("MULTIPLY_ADD", fraction, (count - 1) / count, 0.5 / count)


def new_group(name, inputs, outputs):
    group = bpy.data.node_groups.new(name, "ShaderNodeTree")
    for sock_name, sock_type, default in inputs:
        interface.add_socket(group, sock_name, "INPUT", sock_type, default)
    for sock_name, sock_type in outputs:
        interface.add_socket(group, sock_name, "OUTPUT", sock_type)
    gin = group.nodes.new("NodeGroupInput")
    gin.location = (-400, 0)
    gout = group.nodes.new("NodeGroupOutput")
    gout.location = (1800, 0)
    return group, gin, gout


def zero_after(b, value):
    """A zero that Cycles can only compute once `value` is: min(|value|, 0)
    (fminf, so NaN gives 0 too). Cycles' SVM compiler emits, pass after pass,
    every node whose inputs are ready, so independent work (the 16 taps, the
    octave table's lookups) is evaluated level by level and all its values
    held at once on the 255-float SVM stack: 16 taps × 9 octaves, or 5
    octaves with Distortion, overflowed it and the shader rendered black.
    Chaining each tap (each lookup) after the previous one keeps one's values
    live at a time, for any Detail; EEVEE's GLSL does not care."""
    return b.math("MINIMUM", b.math("ABSOLUTE", value), 0.0)
