"""The noise that drives a filtered ColorRamp, read as a linear combination of
Detail-0 octaves (bpy side):

    value = offset + Σ_i c_i · (Fac_i − 0.5)

Fac_i is a normalized Noise Texture at Detail 0 (Fac = 0.5·snoise + 0.5) with
Scale·lacunarity^i, evaluated at the noise's own, possibly distorted, position.
read_noise() turns a Noise Texture (Blender 3.4 and 4.x/5.x) or a Musgrave
Texture (3.x; 4.1 folded it into the Noise Texture's types) into a NoiseModel,
or raises NoiseNotDerivable naming the node and the setting that makes that
impossible. The model's maths is noise_maths.py; noise_nodes.py builds the
node arithmetic that rebuilds each octave, distortion included.

Blender's definitions (Cycles intern/cycles/kernel/svm/, tags v3.4.0 and
v4.5.0 and branch release/5.2 of blender/cycles; blenlib's noise.cc, which
geometry nodes use, is the same). s(p) is snoise (Perlin noise scaled to
about [−1, 1], noise.h), p = Vector·Scale (1D: W·Scale; 4D: (Vector, W)·Scale):

- Distortion d (noisetex.h, noise_texture_{1,2,3,4}d, every version): if
  d ≠ 0, component k of p moves by d·s(p + o_k) before the fractal is
  evaluated; o_k = random_float{,2,3,4}_offset(k), every component
  100 + 100·hash (Jenkins lookup3 on the float's bits: 1D hash_uint(seed),
  2D-4D hash_uint2(seed, component); util/hash.h).
- fBm (3.4 fractal_noise.h fractal_noise_*d; 4.x/5.x fractal_noise.h
  noise_fbm): Detail clamped to [0, 15], n = ⌊Detail⌋, f = Detail − n;
  octave i ≤ n is s(lacunarity^i·p) with amplitude r^i, octave n + 1 (if
  f ≠ 0) with f·r^(n+1). Normalized: 0.5 + 0.5·mix(Σ/M_n, Σ'/M_(n+1), f)
  (noise_maths.octave_weights). Unnormalized (4.x `normalize` off):
  Σ_(i≤n) r^i s_i + f r^(n+1) s_(n+1), so c_i = 2 r^i, offset 0. 3.4 clamps
  the Roughness r to [0, 1] and has lacunarity 2; 4.x clamps r to ≥ 0 only.
- Musgrave fBm (3.4 musgrave.h noise_musgrave_fBm_*d, svm_node_tex_musgrave):
  H = max(Dimension, 1e-5), lacunarity L = max(Lacunarity, 1e-5), Detail
  clamped to [0, 15], n = ⌊Detail⌋: Σ_(i<n) s_i L^(−H i) + f s_n L^(−H n)
  (n octaves, not n + 1; Detail 0 is 0 everywhere); no distortion.
- Multifractal, hybrid multifractal, hetero terrain (products of octaves) and
  ridged multifractal (|s|²) are nonlinear; only their one-octave settings
  are linear (see _one_octave_noise, _one_octave_musgrave)."""

import math

import bpy

from . import interface, noise_maths
from .noise_maths import NoiseModel
from .. import node_links

NOISE = "ShaderNodeTexNoise"
MUSGRAVE = "ShaderNodeTexMusgrave"
_LABELS = {NOISE: "Noise Texture", MUSGRAVE: "Musgrave Texture"}
# The inputs the filter takes as links (group inputs); any other input that
# shapes the value must be a number the model can read.
LINKABLE = ("Vector", "W", "Scale")
_FROM_IMAGE = "bake the lookup from an image of the colour map instead (Bake Filtered Colour Map > Image)"


class NoiseNotDerivable(Exception):
    """The noise's per-pixel mean and spread can't be derived from its
    settings; the message names the node and the setting."""


# ---- reading the node ------------------------------------------------------

def _label(node):
    return f"{_LABELS.get(node.bl_idname, node.bl_idname)} '{node.name}'"


def _link(socket, path):
    """The output socket that really drives `socket` (node_links.feed), or
    None; `path`: the groups the noise sits in."""
    return node_links.driver(socket, path) if socket is not None else None


def _wireable_link(node, identifier, path):
    """The driver of a Vector, Scale or W input, which the filter links into
    its own node group in the ramp's tree: None when nothing drives it (the
    texture's own Vector then means its implicit coordinates). Raises
    NoiseNotDerivable when the filter cannot link it: a driver inside a
    node group, or a Vector that is one constant point."""
    socket = interface.input_socket(node, identifier)
    if socket is None:
        return None
    fed = node_links.feed(socket, path)
    if fed.node is not None and fed.path:
        raise NoiseNotDerivable(
            f"{_label(node)}: its {socket.name} comes from '{fed.node.name}' inside the node group "
            f"'{fed.path[-1].name}', which the filter (beside the ramp) cannot link to; bring it in through "
            f"the group's inputs, or ungroup the nodes")
    if fed.node is None and identifier == "Vector" and fed.socket != socket:
        raise NoiseNotDerivable(
            f"{_label(node)}: its Vector is the unconnected input '{fed.socket.name}' of '{fed.socket.node.name}', "
            "one point for the whole surface, so the noise does not vary; connect texture coordinates to it")
    return fed.output


def _type_name(node, prop, value):
    try:
        return node.bl_rna.properties[prop].enum_items[value].name
    except (KeyError, AttributeError):
        return value


def _unused_inputs(noise_type):
    """Inputs a fractal type ignores (so a link into them is harmless)."""
    return {"FBM": {"Offset", "Gain"}, "MULTIFRACTAL": {"Offset", "Gain"},
            "HETERO_TERRAIN": {"Gain"}}.get(noise_type, set())


def _check_links(node, noise_type, path):
    linked = [s.name for s in node.inputs
              if s.enabled and s.identifier not in LINKABLE and s.identifier not in _unused_inputs(noise_type)
              and _link(s, path) is not None]
    if linked:
        names = " and ".join(linked)
        verb = "is" if len(linked) == 1 else "are"
        raise NoiseNotDerivable(
            f"{_label(node)}: {names} {verb} driven by a link, so the noise's octaves (and its per-pixel "
            f"mean and spread) change from point to point; set {'it' if len(linked) == 1 else 'them'} to a "
            f"number (only Vector, Scale and W may be linked), or {_FROM_IMAGE}")


def _check_texture_mapping(node):
    """Cycles applies a texture node's hidden Texture Mapping (set in the
    Properties editor) before the noise; the filter does not."""
    m = getattr(node, "texture_mapping", None)
    if m is None:
        return
    identity = (tuple(m.translation) == (0.0, 0.0, 0.0) and tuple(m.rotation) == (0.0, 0.0, 0.0) and
                tuple(m.scale) == (1.0, 1.0, 1.0) and not m.use_min and not m.use_max and
                (m.mapping_x, m.mapping_y, m.mapping_z) == ("X", "Y", "Z"))
    if not identity:
        raise NoiseNotDerivable(
            f"{_label(node)}: its Texture Mapping (Properties editor > Texture > Mapping) is not the identity "
            "and the filter does not apply it; reset it and use a Mapping node on the Vector instead")


def _value(node, identifier, path, default=0.0):
    """An undriven input's value: its own, or that of the input it stands for
    (a group node's input behind a Group Input; node_links.Feed.socket)."""
    socket = interface.input_socket(node, identifier)
    return float(node_links.feed(socket, path).socket.default_value) if socket is not None else default


def _nonlinear(node, type_label, detail, hint):
    return NoiseNotDerivable(
        f"{_label(node)}: type {type_label} is nonlinear in its octaves at Detail {detail:g}, so its per-pixel "
        f"mean and spread can't be derived; use fBm{hint}, or {_FROM_IMAGE}")


def read_noise(node, output=None, path=()):
    """The NoiseModel of a Noise or Musgrave Texture whose `output` (a socket
    or identifier; None: Fac) drives the ramp; `path`: the node groups it
    sits in, seen from the ramp's tree (node_links.Feed.path). Its inputs
    are read as Blender evaluates them (node_links.feed). Raises
    NoiseNotDerivable with a message naming the node and the setting when it
    can't be derived."""
    if node.bl_idname not in _LABELS:
        raise NoiseNotDerivable(f"'{node.name}' is a {node.bl_label} node, not a Noise or Musgrave Texture: its "
                                f"per-pixel mean and spread can't be derived; {_FROM_IMAGE}")
    identifier = getattr(output, "identifier", output)
    if identifier not in (None, "Fac"):
        raise NoiseNotDerivable(
            f"{_label(node)}: the ramp is driven by its {identifier} output (three noises at other offsets "
            "mixed by the colour conversion), which the filter does not model; drive the ramp with Fac")
    _check_texture_mapping(node)
    if node.bl_idname == MUSGRAVE:
        noise_type, dimensions = node.musgrave_type, node.musgrave_dimensions
    else:
        noise_type, dimensions = getattr(node, "noise_type", "FBM"), node.noise_dimensions
    type_label = _type_name(node, "musgrave_type" if node.bl_idname == MUSGRAVE else "noise_type", noise_type)
    if noise_type == "RIDGED_MULTIFRACTAL":  # (offset − |s|)² at any Detail
        raise NoiseNotDerivable(
            f"{_label(node)}: type {type_label} is nonlinear in its octaves (it squares |noise|), so its "
            f"per-pixel mean and spread can't be derived; use fBm, or {_FROM_IMAGE}")
    _check_links(node, noise_type, path)
    if node.bl_idname == MUSGRAVE:
        offset, coefficients, lacunarity = _musgrave_terms(node, noise_type, type_label, path)
        distortion = 0.0
    else:
        offset, coefficients, lacunarity = _noise_terms(node, noise_type, type_label, path)
        distortion = _value(node, "Distortion", path)
    scale_from, w_from = _wireable_link(node, "Scale", path), _wireable_link(node, "W", path)
    return NoiseModel(
        node_name=node.name, node_type=node.bl_idname, noise_type=noise_type, dimensions=dimensions,
        offset=float(offset), coefficients=tuple(float(c) for c in coefficients), lacunarity=float(lacunarity),
        distortion=distortion, scale=None if scale_from else _value(node, "Scale", path),
        w=None if w_from else _value(node, "W", path), vector_from=_wireable_link(node, "Vector", path),
        scale_from=scale_from, w_from=w_from)


def _noise_terms(node, noise_type, type_label, path):
    """(offset, c_i, lacunarity) of a Noise Texture (noise_fbm and friends)."""
    detail = min(max(_value(node, "Detail", path), 0.0), 15.0)
    roughness = _value(node, "Roughness", path)
    legacy = bpy.app.version < (4, 0, 0)
    roughness = min(max(roughness, 0.0), 1.0) if legacy else max(roughness, 0.0)
    lacunarity = _value(node, "Lacunarity", path, 2.0)
    if noise_type != "FBM":
        return _one_octave_noise(node, noise_type, type_label, detail, roughness, path) + (lacunarity,)
    if getattr(node, "normalize", True):
        return 0.5, noise_maths.octave_weights(detail, roughness, bpy.app.version), lacunarity
    n = int(math.floor(detail))
    f = detail - n
    coefficients = [2.0 * roughness ** i for i in range(n + 1)]
    if f > 0.0:
        coefficients.append(2.0 * f * roughness ** (n + 1))
    return 0.0, coefficients, lacunarity


def _one_octave_noise(node, noise_type, type_label, detail, roughness, path):
    """4.1+ multifractal, hybrid multifractal and hetero terrain multiply
    octaves together (fractal_noise.h); with Detail 0 or Roughness 0 only the
    first octave is left: 1 + s_0, and Offset + s_0 for the other two."""
    if detail > 0.0 and roughness > 0.0:
        raise _nonlinear(node, type_label, detail, " (or Detail 0 / Roughness 0 for a single octave)")
    base = 1.0 if noise_type == "MULTIFRACTAL" else _value(node, "Offset", path)
    return base, [2.0]


def _musgrave_terms(node, noise_type, type_label, path):
    """(offset, c_i, lacunarity) of a 3.x Musgrave Texture (musgrave.h)."""
    octaves = min(max(_value(node, "Detail", path), 0.0), 15.0)
    h = max(_value(node, "Dimension", path), 1e-5)
    lacunarity = max(_value(node, "Lacunarity", path), 1e-5)
    n = int(math.floor(octaves))
    f = octaves - n
    if noise_type != "FBM":
        return _one_octave_musgrave(node, noise_type, type_label, octaves, n, f, path) + (lacunarity,)
    coefficients = [2.0 * lacunarity ** (-h * i) for i in range(n)]
    if f > 0.0 or not coefficients:  # Detail 0: the value is 0 (one zero coefficient)
        coefficients.append(2.0 * f * lacunarity ** (-h * n))
    return 0.0, coefficients, lacunarity


def _one_octave_musgrave(node, noise_type, type_label, octaves, n, f, path):
    """3.x Musgrave types whose value is linear in the first octave s_0
    (musgrave.h; loops run i < ⌊Detail⌋, the fraction f adds a partial one):
    multifractal 1 + f·s_0 (Detail < 1) or 1 + s_0 (Detail 1); hybrid
    f·(s_0 + Offset) (Detail < 1) or s_0 + Offset (Detail 1); hetero terrain
    Offset + s_0 (Detail 0 or 1)."""
    base = _value(node, "Offset", path)
    if noise_type == "MULTIFRACTAL" and (n == 0 or (n == 1 and f == 0.0)):
        return 1.0, [2.0 * (f if n == 0 else 1.0)]
    if noise_type == "HYBRID_MULTIFRACTAL" and (n == 0 or (n == 1 and f == 0.0)):
        weight = f if n == 0 else 1.0
        return weight * base, [2.0 * weight]
    if noise_type == "HETERO_TERRAIN" and n <= 1 and f == 0.0:
        return base, [2.0]
    raise _nonlinear(node, type_label, octaves, " (or Detail 1 or less for a single octave)")
