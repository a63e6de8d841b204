"""The World's lighting as Blender renders it: the one reader of the World's
node tree, used by every tool (the visibility shading's SH lighting, the
light rig's source map). It says what the World is and hands over its
pixels; where no single rotated image says it, environment_radiance
evaluates the lit World on a latlong grid, as Blender's Environment Texture
looks its images up. It projects and samples nothing else.

The wiring it follows, as Blender evaluates it:
  active World Output (for the scene's render engine) → Surface ← Mix Shader
  and Add Shader nodes (Fac: its value, a Value node, or a Light Path's Is
  Camera Ray) ← Background nodes (Strength: its value or a Value node;
  Color: its value, an RGB node, or an Environment Texture) ← Vector ←
  Mapping / Vector Rotate nodes ← Texture Coordinate (Generated or Object)
  or nothing (the view direction).
On the way it follows links as Blender evaluates them (node_links.py):
through reroutes, muted nodes, node groups, never a muted link.

Conventions. Directions are Blender world directions (+Z up, from the scene
towards the light); the equirectangular convention is core/common/latlong.hpp.
For the World, Cycles' shading position is the view direction d itself, a
unit vector (shader_setup_from_background in kernel/geom/shader_data.h sets
P = D), and that is what Generated and Object (no object set) give.
Cycles looks the Environment Texture up at m = safe_normalize(v), v the
Vector input (svm_node_tex_environment, kernel/svm/image.h); a Mapping node
gives v = R·(s∘x) + t (POINT), R·(s∘x) (VECTOR), normalize(R·(x/s)) (NORMAL)
or (Rᵀ·(x − t))/s (TEXTURE), x/s = 0 where s = 0 (safe_divide), R = Rz·Ry·Rx
from the Euler XYZ Rotation (svm_mapping in kernel/svm/mapping_util.h,
euler_to_transform in util/transform.h; mathutils' Euler XYZ gives the same
matrix), and a Vector Rotate v = Q·(x − c) + c (kernel/svm/vector_rotate.h).
A chain of them is a DirectionLookup d ↦ m, in general not a rotation: a
Location makes m depend on where d points relative to it, a non-uniform
Scale bends directions towards an axis, a negative one mirrors. When it is a
rotation, m = L·d and what the map shows at m is seen at d = Lᵀ·m:
`world_from_map` = Lᵀ, the matrix the light rig applies to its lights and
the SH lighting rotates by (sh.rotate(c, world_from_map): L(d) =
E(world_from_mapᵀ·d)).

The lit World is Σ weight · strength · colour(lookup(d)) over the
Backgrounds that reach the output (`terms`): a Mix Shader weighs its first
Shader by 1 − Fac and its second by Fac, Fac clamped to [0, 1]
(svm_node_mix_closure, kernel/svm/closure.h), an Add Shader both by 1. Both
tools take the whole sum: the light rig resamples it onto a latlong map, the
SH lighting projects each term. The one-Background fields (kind, colour,
strength, image, world_from_map) describe the first image's term, for a
panel and for the rig's fast path (`rotated_image`).

What cannot be represented (a Sky Texture, a Strength from a Math node, a
Location driven by other nodes, a Fac from Is Diffuse Ray...) is not
silently replaced: it goes to `problems`, each naming the node and input,
what stands in, and how to fix it."""

import os

import numpy as np

from . import native, node_links
from .compat import uses_nodes


class WorldError(ValueError):
    """Bad World input the user can fix; the message says how."""


class WorldLighting:
    """What the World's node tree says, without pixels.

    kind            'black', 'uniform' or 'environment' (an image lights it)
    colour          (3,) scene-linear Background colour (uniform, or the stand-in)
    strength        Background strength times its weight in the mix, not
                    applied to anything here
    node, image     the Environment Texture node and its image ('environment')
    projection      the node's projection ('EQUIRECTANGULAR' or 'MIRROR_BALL')
    world_from_map  (3, 3) rotation: what the map shows at m lights from world_from_map·m
    terms           every Background that lights the scene, as BackgroundTerm;
                    the fields above are the one term (the first image's
                    when there are several)
    source          what was read ("environment 'sky.exr'", "uniform Background colour"...)
    notes           what a user may not expect but is read right (a branch
                    shown to the camera only)
    problems        what could not be read, each with its stand-in and its fix
    note            source, notes and problems in one line, for a panel or a report"""

    def __init__(self):
        self.kind = "black"
        self.colour = np.zeros(3)
        self.strength = 1.0
        self.node = None
        self.image = None
        self.projection = "EQUIRECTANGULAR"
        self.world_from_map = np.eye(3)
        self.terms = []
        self.source = ""
        self.notes = []
        self.problems = []

    @property
    def supported(self):
        """True when the lighting is the World's as Blender renders it."""
        return not self.problems

    @property
    def note(self):
        return "; ".join([self.source] + self.notes + self.problems)

    @property
    def rotated_image(self):
        """The one term when the World is a single image seen through a
        rotation (a light rig reads it straight from its file and turns its
        lights), else None."""
        if len(self.terms) == 1 and self.terms[0].kind == "environment" and self.terms[0].lookup.rotation is not None:
            return self.terms[0]
        return None


class BackgroundTerm:
    """One Background node's share of the World's light:
    weight · strength · colour, the colour a constant or an Environment
    Texture's image looked up at lookup(d).

    background      the Background node
    weight          the product of the Mix Shader shares on its way to the output
    strength        its Strength
    kind            'uniform' or 'environment'
    colour          (3,) scene-linear colour (uniform, or the stand-in)
    node, image     the Environment Texture and its image ('environment')
    projection      'EQUIRECTANGULAR' or 'MIRROR_BALL'
    interpolation   the texture's interpolation ('Closest' is looked up as
                    such, the others bilinearly)
    lookup          DirectionLookup: view direction → where the image is looked up
    source          what it is, for the note"""

    def __init__(self, background, weight):
        self.background = background
        self.weight = weight
        self.strength = 1.0
        self.kind = "uniform"
        self.colour = np.zeros(3)
        self.node = None
        self.image = None
        self.projection = "EQUIRECTANGULAR"
        self.interpolation = "Linear"
        self.lookup = DirectionLookup()
        self.source = "uniform Background colour"


class DirectionLookup:
    """Where an Environment Texture is looked up for the view direction d, as
    Cycles evaluates its Vector: steps x ↦ A·x + b (Mapping, Vector Rotate),
    some followed by a normalization (a NORMAL Mapping), applied to d in
    order, then m = safe_normalize(x), the texture's own (the core applies
    them: image/environment_lookup.hpp).

    steps          [(A, b, normalize)] in the order they act on d
    rotation_part  the product of the steps' rotations: m = rotation_part·d
                   when nothing warps
    warps          what makes it more than a rotation, one entry per node
                   input (the light rig then resamples the World, the SH
                   lighting projects the resampled term)"""

    def __init__(self):
        self.steps = []
        self.rotation_part = np.eye(3)
        self.warps = []

    @property
    def rotation(self):
        """R with m = R·d for every view direction d, or None when the lookup warps."""
        return None if self.warps else self.rotation_part

    def add_before(self, step, rotation, warps):
        """A node met walking back from the texture: it acts on the vector
        before the nodes met already."""
        self.steps.insert(0, step)
        self.rotation_part = self.rotation_part @ rotation
        self.warps.extend(warps)


def engine_target(engine):
    """The World Output `target` that serves a render engine ('CYCLES',
    'EEVEE'), or None for another engine (only 'ALL' outputs serve it)."""
    if engine == "CYCLES":
        return "CYCLES"
    if engine and engine.startswith("BLENDER_EEVEE"):
        return "EEVEE"
    return None


def _active_output(nodes, target):
    """The World Output Blender renders: among outputs for this engine or for
    all, an exact target match wins over 'ALL', then the active one, then the
    first (ntreeShaderOutputNode in source/blender/nodes/shader/node_shader_tree.cc)."""
    outputs = [n for n in nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.target in ("ALL", target)]
    exact = [n for n in outputs if n.target == target]
    return node_links.active_output(exact or outputs)


def feed(socket, path=()):
    """node_links.feed, a loop through node groups being a WorldError."""
    try:
        return node_links.feed(socket, path)
    except node_links.NodeTreeCycle as error:
        raise WorldError(f"the World's node tree: {error}") from None


def read_scene(scene):
    """read() of the scene's World for the scene's render engine."""
    return read(scene.world, scene.render.engine)


def read(world, engine=None):
    """The WorldLighting of a World as `engine` (scene.render.engine) renders
    it: every Background term with its lookup."""
    r = WorldLighting()
    if world is None:
        r.source = "no World: black"
        return r
    if not uses_nodes(world):  # always node-based from 5.0 (compat.py)
        r.kind, r.colour, r.source = "uniform", np.array(world.color[:3], dtype=np.float64), "World colour"
        return r
    output = _active_output(world.node_tree.nodes, engine_target(engine))
    if output is None:
        r.source = "no World Output: black"
        r.problems.append(f"the World '{world.name}' has no World Output node{_for_engine(engine)}: "
                          "add one and connect a Background node to its Surface")
        return _unconnected_environments(world, r)
    surface = feed(output.inputs["Surface"])
    if surface.node is None:
        r.source = "nothing feeds the World Output: black"
        r.problems.append(f"nothing (or only a muted node) is connected to the Surface of the World Output "
                          f"'{output.name}': connect a Background node to it")
        return _unconnected_environments(world, r)
    _read_shader(surface, 1.0, "the World output", r)
    _take_terms(r)
    return _unconnected_environments(world, r)


def _for_engine(engine):
    target = engine_target(engine)
    return f" for {'Cycles' if target == 'CYCLES' else 'EEVEE'} or All" if target else ""


# Shader inputs of the nodes that combine Backgrounds.
_SHADER_INPUTS = {"ShaderNodeMixShader": (1, 2), "ShaderNodeAddShader": (0, 1)}


def _read_shader(source, weight, where, r):
    """Adds the Backgrounds behind a shader Feed to r.terms, each with its
    weight: a Mix Shader passes 1 − Fac to its first Shader and Fac to its
    second, an Add Shader 1 to both. A branch of weight 0 adds no light and
    is not read (an unsupported node there changes nothing); an unconnected
    Shader input adds nothing either, as in Blender."""
    node = source.node
    if node is None:
        return
    if node.bl_idname == "ShaderNodeBackground":
        r.terms.append(_read_background(node, source.path, weight, r))
        return
    if node.bl_idname not in _SHADER_INPUTS:
        r.problems.append(f"{where} is fed by a {node.bl_label} node '{node.name}' (unsupported: it adds no light "
                          "here); feed it a Background node, or Mix or Add Shaders of Background nodes")
        return
    shares = (1.0, 1.0)
    if node.bl_idname == "ShaderNodeMixShader":
        fac = _mix_factor(node, source.path, r)
        shares = (1.0 - fac, fac)
    for index, share in zip(_SHADER_INPUTS[node.bl_idname], shares):
        if weight * share > 0.0:
            _read_shader(feed(node.inputs[index], source.path), weight * share,
                         f"Shader input {index} of '{node.name}'", r)


def _mix_factor(mix, path, r):
    """A Mix Shader's Fac for the light that reaches surfaces, in [0, 1].

    A Light Path's Is Camera Ray is 0 for every ray that lights something:
    Cycles evaluates the World for a light sample with no camera visibility
    (PATH_RAY_EMISSION, kernel/light/sample.h, kernel/integrator/shade_light.h)
    and for a bounce that escapes with the bounce's own (diffuse, glossy,
    transmission; kernel/integrator/shade_background.h); only camera rays
    that miss everything see 1. So the lights follow the first Shader and
    the second is what the camera shows (noted, not a problem). Is Diffuse
    Ray or Is Glossy Ray is 1 for a bounce but 0 for a light sample of the
    same direction, so what they light depends on Cycles' sampling: a
    problem, as is any other Fac driver."""
    socket = mix.inputs["Fac"]
    source = feed(socket, path)
    if source.node is None:
        fac = float(source.socket.default_value)
    elif source.node.bl_idname == "ShaderNodeValue":
        fac = float(source.output.default_value)
    elif source.node.bl_idname == "ShaderNodeLightPath" and source.output.identifier == "Is Camera Ray":
        r.notes.append(f"'{mix.name}' shows its second Shader to the camera only (Fac: Is Camera Ray of "
                       f"'{source.node.name}'); the light is its first Shader's")
        return 0.0
    else:
        what = (f"the {source.output.name} output of the Light Path node '{source.node.name}'"
                if source.node.bl_idname == "ShaderNodeLightPath" else f"a {source.node.bl_label} node "
                f"'{source.node.name}'")
        fac = float(socket.default_value)
        r.problems.append(f"the Fac of the Mix Shader '{mix.name}' comes from {what} (unsupported: its own value "
                          f"{fac:g} is used); use a value, a Value node or Light Path's Is Camera Ray")
    return min(max(fac, 0.0), 1.0)


def _read_background(background, path, weight, r):
    """The BackgroundTerm of a Background node: its Strength and Color."""
    term = BackgroundTerm(background, weight)
    term.strength = _float_input(background.inputs["Strength"], path, r, f"the Strength of '{background.name}'")
    colour = feed(background.inputs["Color"], path)
    if colour.node is None:
        term.colour = np.array(colour.socket.default_value[:3], dtype=np.float64)
        return term
    term.colour = np.array(background.inputs["Color"].default_value[:3], dtype=np.float64)
    source = colour.node
    if source.bl_idname == "ShaderNodeRGB":
        term.colour = np.array(colour.output.default_value[:3], dtype=np.float64)
        term.source = f"uniform colour of '{source.name}'"
    elif source.bl_idname == "ShaderNodeTexSky":
        r.problems.append("Sky Texture is not supported: the Background colour stands in")
    elif source.bl_idname != "ShaderNodeTexEnvironment":
        r.problems.append(f"Color comes from a {source.bl_label} node (unsupported: the Background colour "
                          "stands in); connect an Environment Texture, an RGB node or nothing")
    elif source.image is None:
        r.problems.append(f"the Environment Texture '{source.name}' has no image: open an image in it "
                          "(the Background colour stands in)")
    else:
        term.kind, term.node, term.image, term.projection = "environment", source, source.image, source.projection
        term.interpolation = source.interpolation
        term.source = f"environment '{source.image.name}'"
        term.lookup = _vector_lookup(source.inputs["Vector"], colour.path, r)
        if term.lookup.rotation is None:
            term.source += " (remapped)"
        elif not np.allclose(term.lookup.rotation, np.eye(3), atol=1e-9):
            term.source += " (rotated)"
    return term


def _take_terms(r):
    """The one-Background fields from r.terms: the one term, or the first
    image's when there are several."""
    terms = r.terms
    if not terms:
        r.source = "no Background reaches the World Output: black"
        return
    images = [t for t in terms if t.kind == "environment"]
    main = images[0] if images else terms[0]
    r.kind, r.colour, r.node, r.image, r.projection = main.kind, main.colour, main.node, main.image, main.projection
    r.strength = main.weight * main.strength
    r.world_from_map = main.lookup.rotation_part.T
    shares = [t.source if t.weight == 1.0 else f"{t.weight:g} × {t.source}" for t in terms]
    r.source = " + ".join(shares)


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
    with an image that are in its tree but do not light it (not wired to the
    active output, or only on a branch the camera sees): the likely reason."""
    if r.kind == "environment" or world.node_tree is None:
        return r
    for node in _environment_nodes(world.node_tree, set()):
        r.problems.append(f"the Environment Texture '{node.name}' (image '{node.image.name}') is not connected "
                          "to a Background that lights the scene from the active World Output: connect its Color to "
                          "that Background's Color")
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


def _mapping_step(node, path, r):
    """A Mapping node as a lookup step: ((A, b, normalize), its rotation,
    what makes it more than a rotation) (svm_mapping, kernel/svm/mapping_util.h).
    VECTOR and NORMAL ignore the Location, as Cycles does."""
    name = node.name
    rotation = _euler_xyz(_vector_input(node.inputs["Rotation"], path, r, f"the Rotation of '{name}'"))
    scale = _vector_input(node.inputs["Scale"], path, r, f"the Scale of '{name}'")
    location, warps = np.zeros(3), []
    if node.vector_type in {"POINT", "TEXTURE"}:
        location = _vector_input(node.inputs["Location"], path, r, f"the Location of '{name}'")
        if np.any(np.abs(location) > 1e-9):
            warps.append(f"the Location of '{name}'")
    if not (scale[0] > 0.0 and np.allclose(scale, scale[0], rtol=1e-6)):
        # A uniform positive scale only changes the length, which the lookup drops.
        warps.append(f"the Scale of '{name}'")
    inverse = np.divide(1.0, scale, out=np.zeros(3), where=scale != 0.0)  # safe_divide: x/0 = 0
    if node.vector_type == "TEXTURE":
        a = inverse[:, None] * rotation.T  # diag(1/s)·Rᵀ
        return (a, -a @ location, False), rotation.T, warps
    if node.vector_type == "NORMAL":
        return (rotation * inverse[None, :], np.zeros(3), True), rotation, warps
    return (rotation * scale[None, :], location, False), rotation, warps


_AXES = {"X_AXIS": (1.0, 0.0, 0.0), "Y_AXIS": (0.0, 1.0, 0.0), "Z_AXIS": (0.0, 0.0, 1.0)}


def _vector_rotate_step(node, path, r):
    """A Vector Rotate node as a lookup step, v = Q·(x − c) + c: ((A, b,
    normalize), Q, what makes it more than a rotation)
    (kernel/svm/vector_rotate.h)."""
    name = node.name
    center = _vector_input(node.inputs["Center"], path, r, f"the Center of '{name}'")
    if node.rotation_type == "EULER_XYZ":
        rotation = _euler_xyz(_vector_input(node.inputs["Rotation"], path, r, f"the Rotation of '{name}'"))
        rotation = rotation.T if node.invert else rotation
    else:
        if node.rotation_type in _AXES:
            axis = np.array(_AXES[node.rotation_type])
        else:
            axis = _vector_input(node.inputs["Axis"], path, r, f"the Axis of '{name}'")
        length = float(np.linalg.norm(axis))
        if length == 0.0:
            return (np.eye(3), np.zeros(3), False), np.eye(3), []  # Cycles leaves the vector as it is
        angle = _float_input(node.inputs["Angle"], path, r, f"the Angle of '{name}'")
        rotation = _axis_angle(axis / length, -angle if node.invert else angle)
    warps = []
    if np.any(np.abs(center) > 1e-9):
        warps.append(f"the Center of '{name}'")
    return (rotation, center - rotation @ center, False), rotation, warps


def _vector_lookup(socket, path, r):
    """The Environment Texture's DirectionLookup: the Mapping and Vector
    Rotate nodes behind its Vector input, walked back to the view direction."""
    lookup = DirectionLookup()
    source = feed(socket, path)
    while source.node is not None:
        node = source.node
        if node.bl_idname == "ShaderNodeMapping":
            lookup.add_before(*_mapping_step(node, source.path, r))
        elif node.bl_idname == "ShaderNodeVectorRotate":
            lookup.add_before(*_vector_rotate_step(node, source.path, r))
        elif node.bl_idname == "ShaderNodeTexCoord":
            # In a World, Generated and Object (no object set) are the view direction.
            if source.output.identifier == "Generated" or (source.output.identifier == "Object"
                                                           and node.object is None):
                return lookup
            r.problems.append(f"the environment's Vector comes from the {source.output.name} output of "
                              f"'{node.name}' (unsupported: the view direction stands in); use Generated")
            return lookup
        else:
            r.problems.append(f"the environment's Vector comes from a {node.bl_label} node '{node.name}' "
                              "(unsupported: ignored); use Mapping or Vector Rotate nodes after a Texture Coordinate")
            return lookup
        source = feed(node.inputs["Vector"], source.path)
    if source.socket != socket:
        # Only the texture's own Vector defaults to the view direction; any
        # other input's value is one constant vector.
        r.problems.append(f"the Vector input of '{source.socket.node.name}' is not connected, so the map is looked "
                          "up in one direction only (unsupported: the view direction stands in); connect a Texture "
                          "Coordinate's Generated output to it")
    return lookup


# The lit World on a grid ---------------------------------------------------------------

def environment_radiance(terms, values, width, supersampling=2):
    """(width/2, width, 3) float32: the lit World Σ weight·strength·value(m)
    over `terms`, on an equirectangular grid of world directions d
    (core/common/latlong.hpp), m = term.lookup(d). Each cell is the
    solid-angle-weighted mean of supersampling² point evaluations, as the core
    resamples a fisheye or a mirror ball. values[i]: term i's colour (3,) or
    its image's pixels (H, W, 3), row 0 = the top, all in the one linear
    space the result is in. Images are looked up as Blender's Environment
    Texture does (the core's image/environment_lookup.hpp)."""
    core_terms = []
    for term, value in zip(terms, values):
        core_term = {"scale": float(term.weight * term.strength)}
        if term.kind == "environment":
            core_term.update(pixels=np.asarray(value, dtype=np.float32), projection=term.projection,
                             closest=term.interpolation == "Closest", steps=term.lookup.steps)
        else:
            core_term["colour"] = np.asarray(value, dtype=np.float64)
        core_terms.append(core_term)
    return native.require().image.environment_radiance(core_terms, int(width), supersampling)


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
