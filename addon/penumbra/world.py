"""The World's lighting as Blender renders it: the one reader of the World's
node tree, used by every tool (the visibility shading's SH lighting, the
light rig's source map). Nothing here projects or samples; it says what the
World is and hands over its pixels.

The wiring it follows, as Blender evaluates it:
  active World Output (for the scene's render engine) → Surface ← Background
  (Strength: its value or a Value node; Color: its value, an RGB node, or an
  Environment Texture) ← Vector ← Mapping / Vector Rotate nodes ← Texture
  Coordinate (Generated or Object) or nothing (the view direction).
On the way it passes through reroutes, muted nodes (their internal links),
muted links (as if absent), and node groups (a group node's output is its
active Group Output's input inside; a Group Input's output is the group
node's input outside), recursively.

Conventions. Directions are Blender world directions (+Z up, from the scene
towards the light); the equirectangular convention is core/common/latlong.hpp.
Cycles looks the Environment Texture up at m = normalize(v), v the Vector
input (intern/cycles/kernel/svm/image.h); a Mapping node gives
v = R·(s·x) + t (POINT), R·(s·x) (VECTOR), normalize(R·(x/s)) (NORMAL) or
Rᵀ·(x − t)/s (TEXTURE), R = Rz·Ry·Rx from the Euler XYZ Rotation
(intern/cycles/kernel/svm/mapping_util.h, euler_to_transform in
intern/cycles/util/transform.h; mathutils' Euler XYZ gives the same matrix).
A chain of such nodes gives m = L·d for the view direction d, so what the map
shows at m is seen at d = Lᵀ·m: `world_from_map` = Lᵀ, the matrix the light
rig applies to its lights and the SH lighting rotates by
(sh.rotate(c, world_from_map): L(d) = E(world_from_mapᵀ·d)).

What cannot be represented (a Sky Texture, a Strength from a Math node, a
Mapping location, a non-uniform scale...) is not silently replaced: it goes to
`problems`, each saying what stands in and how to fix it."""

import os

import numpy as np

from .compat import uses_nodes

# How far a walk may go (reroutes, groups) before the tree is declared cyclic.
_MAX_STEPS = 1000


class WorldError(ValueError):
    """Bad World input the user can fix; the message says how."""


class WorldLighting:
    """What the World's node tree says, without pixels.

    kind            'black', 'uniform' or 'environment'
    colour          (3,) scene-linear Background colour (uniform, or the stand-in)
    strength        Background strength, not applied to anything here
    node, image     the Environment Texture node and its image ('environment')
    projection      the node's projection ('EQUIRECTANGULAR' or 'MIRROR_BALL')
    world_from_map  (3, 3) rotation: what the map shows at m lights from world_from_map·m
    source          what was read ("environment 'sky.exr'", "uniform Background colour"...)
    problems        what could not be read, each with its stand-in and its fix
    note            source and problems in one line, for a panel or a report"""

    def __init__(self):
        self.kind = "black"
        self.colour = np.zeros(3)
        self.strength = 1.0
        self.node = None
        self.image = None
        self.projection = "EQUIRECTANGULAR"
        self.world_from_map = np.eye(3)
        self.source = ""
        self.problems = []

    @property
    def supported(self):
        """True when the lighting is the World's as Blender renders it."""
        return not self.problems

    @property
    def note(self):
        return "; ".join([self.source] + self.problems)


def engine_target(engine):
    """The World Output `target` that serves a render engine ('CYCLES',
    'EEVEE'), or None for another engine (only 'ALL' outputs serve it)."""
    if engine == "CYCLES":
        return "CYCLES"
    if engine and engine.startswith("BLENDER_EEVEE"):
        return "EEVEE"
    return None


def _active_output(nodes, idname, target):
    """The output node Blender renders: among outputs for this engine or for
    all, an exact target match wins over 'ALL', then the active one, then the
    first (ntreeShaderOutputNode in source/blender/nodes/shader/node_shader_tree.cc)."""
    outputs = [n for n in nodes if n.bl_idname == idname]
    if idname == "ShaderNodeOutputWorld":
        outputs = [n for n in outputs if n.target == "ALL" or n.target == target]
        exact = [n for n in outputs if n.target == target]
        outputs = exact or outputs
    return next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)


def _matching(sockets, socket):
    """The socket of `sockets` that is `socket`'s counterpart across a group
    boundary (same identifier; by position if none)."""
    for candidate in sockets:
        if candidate.identifier == socket.identifier:
            return candidate
    index = list(socket.node.outputs if socket.is_output else socket.node.inputs).index(socket)
    return sockets[index] if index < len(sockets) else None


class Feed:
    """What drives an input socket: `node` and its `output` socket, inside the
    groups `path` (outermost first). When nothing does, `node` is None and
    `socket` is the input whose own value Blender uses: a reroute or a muted
    node with nothing behind it is dropped with its links (Blender's
    localize(), node_shader_tree.cc), so that is the input it fed."""

    def __init__(self, node, output, socket, path):
        self.node, self.output, self.socket, self.path = node, output, socket, path


def feed(socket, path=()):
    """The Feed of an input socket, through reroutes, muted nodes and links,
    group nodes and Group Input nodes."""
    owner = socket  # the input whose value counts if the walk ends in nothing
    for _ in range(_MAX_STEPS):
        link = next((l for l in socket.links if l.is_valid and not l.is_muted), None)
        if link is None:
            return Feed(None, None, owner, path)
        node, output = link.from_node, link.from_socket
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
        elif node.mute:
            internal = next((l for l in node.internal_links if l.to_socket == output), None)
            if internal is None:
                return Feed(None, None, owner, path)
            socket = internal.from_socket
        elif node.bl_idname == "ShaderNodeGroup":
            inner = _active_output(node.node_tree.nodes, "NodeGroupOutput", None) if node.node_tree else None
            matched = _matching(inner.inputs, output) if inner else None
            if matched is None:
                return Feed(None, None, owner, path)
            socket = owner = matched
            path = path + (node,)
        elif node.bl_idname == "NodeGroupInput":
            matched = _matching(path[-1].inputs, output) if path else None
            if matched is None:
                return Feed(None, None, owner, path)
            socket = owner = matched
            path = path[:-1]
        else:
            return Feed(node, output, socket, path)
    raise WorldError("the World's node tree loops through its node groups: break the loop")


def read_scene(scene):
    """read() of the scene's World for the scene's render engine."""
    return read(scene.world, scene.render.engine)


def read(world, engine=None):
    """The WorldLighting of a World as `engine` (scene.render.engine) renders it."""
    r = WorldLighting()
    if world is None:
        r.source = "no World: black"
        return r
    if not uses_nodes(world):  # always node-based from 5.0 (compat.py)
        r.kind, r.colour, r.source = "uniform", np.array(world.color[:3], dtype=np.float64), "World colour"
        return r
    output = _active_output(world.node_tree.nodes, "ShaderNodeOutputWorld", engine_target(engine))
    if output is None:
        r.source = "no World Output: black"
        r.problems.append(f"the World '{world.name}' has no World Output node{_for_engine(engine)}: "
                          "add one and connect a Background node to its Surface")
        return _unconnected_environments(world, r)
    background = feed(output.inputs["Surface"])
    if background.node is None:
        r.source = "nothing feeds the World Output: black"
        r.problems.append(f"nothing (or only a muted node) is connected to the Surface of the World Output "
                          f"'{output.name}': connect a Background node to it")
        return _unconnected_environments(world, r)
    if background.node.bl_idname != "ShaderNodeBackground":
        r.source = "World output not fed by a Background node: black"
        r.problems.append(f"the World output is fed by a {background.node.bl_label} node (unsupported): "
                          "feed it a Background node")
        return _unconnected_environments(world, r)
    _read_background(background.node, background.path, r)
    return _unconnected_environments(world, r)


def _for_engine(engine):
    target = engine_target(engine)
    return f" for {'Cycles' if target == 'CYCLES' else 'EEVEE'} or All" if target else ""


def _read_background(background, path, r):
    """Strength and Color of the Background node at the output."""
    r.strength = _float_input(background.inputs["Strength"], path, r, "Strength")
    colour = feed(background.inputs["Color"], path)
    r.kind, r.source = "uniform", "uniform Background colour"
    if colour.node is None:
        r.colour = np.array(colour.socket.default_value[:3], dtype=np.float64)
        return
    r.colour = np.array(background.inputs["Color"].default_value[:3], dtype=np.float64)
    source = colour.node
    if source.bl_idname == "ShaderNodeRGB":
        r.colour = np.array(colour.output.default_value[:3], dtype=np.float64)
        r.source = f"uniform colour of '{source.name}'"
    elif source.bl_idname == "ShaderNodeTexSky":
        r.problems.append("Sky Texture is not supported: the Background colour stands in")
    elif source.bl_idname != "ShaderNodeTexEnvironment":
        r.problems.append(f"Color comes from a {source.bl_label} node (unsupported: the Background colour "
                          "stands in); connect an Environment Texture, an RGB node or nothing")
    elif source.image is None:
        r.problems.append(f"the Environment Texture '{source.name}' has no image: open an image in it "
                          "(the Background colour stands in)")
    else:
        r.kind, r.node, r.image, r.projection = "environment", source, source.image, source.projection
        r.source = f"environment '{source.image.name}'"
        lookup = _vector_lookup(source.inputs["Vector"], colour.path, r)
        r.world_from_map = lookup.T
        if not np.allclose(lookup, np.eye(3), atol=1e-9):
            r.source += " (rotated)"


def _float_input(socket, path, r, what):
    """A float input: its own value, or a Value node's; anything else is a
    problem and the socket's own value stands in."""
    source = feed(socket, path)
    if source.node is None:
        return float(source.socket.default_value)
    if source.node.bl_idname == "ShaderNodeValue":
        return float(source.output.default_value)
    r.problems.append(f"{what} comes from a {source.node.bl_label} node (unsupported: its own value is used)")
    return float(socket.default_value)


def _unconnected_environments(world, r):
    """When the World is not lit by an image, names the Environment Textures
    with an image that are in its tree but not wired to the active output:
    the likely reason."""
    if r.kind == "environment" or world.node_tree is None:
        return r
    for node in _environment_nodes(world.node_tree, set()):
        r.problems.append(f"the Environment Texture '{node.name}' (image '{node.image.name}') is not connected "
                          "to the Background at the active World Output: connect its Color to the Background's "
                          "Color")
    return r


def _environment_nodes(tree, seen):
    """Environment Textures with an image in a tree and the groups it uses."""
    found = []
    for node in tree.nodes:
        if node.bl_idname == "ShaderNodeTexEnvironment" and node.image is not None:
            found.append(node)
        elif node.bl_idname == "ShaderNodeGroup" and node.node_tree and node.node_tree.name not in seen:
            seen.add(node.node_tree.name)
            found.extend(_environment_nodes(node.node_tree, seen))
    return found


# The Environment Texture's Vector -----------------------------------------------

def _euler_xyz(euler):
    """Rz·Ry·Rx, as Cycles' euler_to_transform builds it."""
    x, y, z = (float(v) for v in euler)
    cx, cy, cz, sx, sy, sz = np.cos(x), np.cos(y), np.cos(z), np.sin(x), np.sin(y), np.sin(z)
    return np.array([[cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz],
                     [cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz],
                     [-sy, cy * sx, cy * cx]])


def _axis_angle(axis, angle):
    """Right-handed rotation by `angle` about a unit axis (Rodrigues; Cycles'
    rotate_around_axis)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _vector_input(socket, path, r, what):
    """A vector input's own value; one driven by a node is a problem (its own value is used)."""
    source = feed(socket, path)
    if source.node is not None:
        r.problems.append(f"{what} comes from a {source.node.bl_label} node (unsupported: its own value is used)")
    return np.array(source.socket.default_value[:3] if source.node is None else socket.default_value[:3],
                    dtype=np.float64)


def _mapping_lookup(node, path, r):
    """A Mapping node as m = A·x (up to length, which the lookup drops)."""
    rotation = _euler_xyz(_vector_input(node.inputs["Rotation"], path, r, f"the Rotation of '{node.name}'"))
    if node.vector_type in {"POINT", "TEXTURE"}:
        location = _vector_input(node.inputs["Location"], path, r, f"the Location of '{node.name}'")
        if np.any(np.abs(location) > 1e-9):
            r.problems.append(f"the Mapping node '{node.name}' has a Location, which moves the lookup off the "
                              "sphere (unsupported: ignored); set it to 0")
    scale = _vector_input(node.inputs["Scale"], path, r, f"the Scale of '{node.name}'")
    if not (scale[0] > 0.0 and np.allclose(scale, scale[0], rtol=1e-6)):
        r.problems.append(f"the Mapping node '{node.name}' has a Scale that is not the same positive number on "
                          "every axis, which distorts or mirrors the map (unsupported: ignored); set it to 1")
    return rotation.T if node.vector_type == "TEXTURE" else rotation


_AXES = {"X_AXIS": (1.0, 0.0, 0.0), "Y_AXIS": (0.0, 1.0, 0.0), "Z_AXIS": (0.0, 0.0, 1.0)}


def _vector_rotate_lookup(node, path, r):
    """A Vector Rotate node as m = A·x (intern/cycles/kernel/svm/vector_rotate.h)."""
    center = _vector_input(node.inputs["Center"], path, r, f"the Center of '{node.name}'")
    if np.any(np.abs(center) > 1e-9):
        r.problems.append(f"the Vector Rotate node '{node.name}' has a Center, which moves the lookup off the "
                          "sphere (unsupported: ignored); set it to 0")
    if node.rotation_type == "EULER_XYZ":
        rotation = _euler_xyz(_vector_input(node.inputs["Rotation"], path, r, f"the Rotation of '{node.name}'"))
        return rotation.T if node.invert else rotation
    if node.rotation_type in _AXES:
        axis = np.array(_AXES[node.rotation_type])
    else:
        axis = _vector_input(node.inputs["Axis"], path, r, f"the Axis of '{node.name}'")
    length = float(np.linalg.norm(axis))
    if length == 0.0:
        return np.eye(3)  # Cycles leaves the vector as it is
    angle = _float_input(node.inputs["Angle"], path, r, f"the Angle of '{node.name}'")
    return _axis_angle(axis / length, -angle if node.invert else angle)


def _vector_lookup(socket, path, r):
    """The Environment Texture's lookup m = L·d as the 3×3 L, composing the
    Mapping and Vector Rotate nodes behind its Vector input."""
    lookup = np.eye(3)
    source = feed(socket, path)
    while source.node is not None:
        node = source.node
        if node.bl_idname == "ShaderNodeMapping":
            lookup = lookup @ _mapping_lookup(node, source.path, r)
        elif node.bl_idname == "ShaderNodeVectorRotate":
            lookup = lookup @ _vector_rotate_lookup(node, source.path, r)
        elif node.bl_idname == "ShaderNodeTexCoord":
            # In a World, Generated and Object (no object set) are the view direction.
            if source.output.identifier == "Generated" or (source.output.identifier == "Object"
                                                           and node.object is None):
                return lookup
            r.problems.append(f"the environment's Vector comes from the {source.output.name} output of "
                              f"'{node.name}' (unsupported: the view direction stands in); use Generated")
            return lookup
        else:
            r.problems.append(f"the environment's Vector comes from a {node.bl_label} node (unsupported: "
                              "ignored); use Mapping or Vector Rotate nodes after a Texture Coordinate")
            return lookup
        source = feed(node.inputs["Vector"], source.path)
    if source.socket != socket:
        # Only the texture's own Vector defaults to the view direction; any
        # other input's value is one constant vector.
        r.problems.append(f"the Vector input of '{source.socket.node.name}' is not connected, so the map is looked "
                          "up in one direction only (unsupported: the view direction stands in); connect a Texture "
                          "Coordinate's Generated output to it")
    return lookup


# Pixels ------------------------------------------------------------------------------

def image_file(image):
    """Path of the file an image is read from (a file, sequence or movie),
    or None when Blender holds the only copy (packed or generated)."""
    import bpy
    if image.packed_file is None and image.source in {"FILE", "SEQUENCE", "MOVIE"}:
        return bpy.path.abspath(image.filepath, library=image.library)
    return None


def image_pixels(image, config=None, colorspace=""):
    """(H, W, 3) float32 pixels of an image as Blender holds them, row 0 = the
    top of the picture (Blender's rows are bottom-up), in Blender's
    scene-linear working space (color.working_space). A float image's pixels
    already are (Blender converts float buffers on load; 5.x whatever the
    image's colour space says); byte pixels hold the image's encoding and are
    converted with Blender's OCIO config (Non-Color and Raw are not).
    `colorspace`: the space the held pixels are in, instead. Raises
    WorldError when the image has no pixels."""
    width, height = image.size
    if width == 0 or height == 0:
        raise WorldError(f"the World's environment image '{image.name}' has no pixels: {unreadable(image)}")
    channels = image.channels
    pixels = np.empty(width * height * channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, channels)[::-1]
    if channels < 3:
        pixels = np.repeat(pixels[..., :1], 3, axis=2)
    pixels = np.ascontiguousarray(pixels[..., :3])
    space = colorspace or ("" if image.is_float else image.colorspace_settings.name)
    if space and space not in {"Non-Color", "Raw"}:
        from . import color
        pixels = color.to_working_space(config or color.blender_config(), pixels, space)
    return pixels


def unreadable(image):
    """Why an image has no pixels, and what to do."""
    import bpy
    if image.source in {"FILE", "SEQUENCE", "MOVIE"} and image.packed_file is None:
        path = bpy.path.abspath(image.filepath, library=image.library)
        if not os.path.isfile(path):
            return f"its file '{path}' is missing; point the image at an existing file"
        return (f"Blender could not read its file '{path}' (empty, zero-sized or damaged?); "
                "replace it with a readable image")
    return "the image is empty; fill it or choose another image"
