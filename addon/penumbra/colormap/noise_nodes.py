"""Node arithmetic that rebuilds a noise octave by octave (noise_maths.
NoiseModel): each octave a Detail-0 Noise Texture, at the position the
noise's Distortion moves it to, with the same float operations as Blender's
(noisetex.h). The Noise Filter and the tests that check the model against
Blender's own texture build with these."""

from collections import namedtuple

from . import interface


Coordinates = namedtuple("Coordinates", "vector w")
Coordinates.__doc__ = """Where the octaves are evaluated, in the noise's own units
(before Scale): Vector and W, each a socket or a constant."""


def configure_octave_node(noise_node, model):
    """Set a Noise Texture node up as one octave of `model`: its dimensions,
    fBm, normalized, Detail 0, Distortion 0, the noise's lacunarity (unused at
    Detail 0) and its W value where W is a constant. The caller links
    Vector (and W) and sets Scale = model scale · lacunarity^i."""
    noise_node.noise_dimensions = model.dimensions
    if hasattr(noise_node, "noise_type"):
        noise_node.noise_type = "FBM"
    if hasattr(noise_node, "normalize"):
        noise_node.normalize = True
    settings = {"Detail": 0.0, "Distortion": 0.0, "Lacunarity": model.lacunarity}
    if model.w is not None:
        settings["W"] = model.w
    for identifier, value in settings.items():
        socket = interface.input_socket(noise_node, identifier)
        if socket is not None:  # 3.4 has no Lacunarity
            socket.default_value = value
    return noise_node


def octave_fac(b, coordinates, scale, model):
    """A Detail-0 octave of `model` at `coordinates` with Scale `scale`
    (socket or number): its Fac output. `b` is a node_builder.Builder."""
    node = configure_octave_node(b.place(b.nodes.new("ShaderNodeTexNoise")), model)
    if model.uses_vector:
        b.connect(coordinates.vector, interface.input_socket(node, "Vector"))
    if model.uses_w:
        b.connect(coordinates.w, interface.input_socket(node, "W"))
    b.connect(scale, interface.input_socket(node, "Scale"))
    return node.outputs["Fac"]


def distorted_vector(b, vector, scale, model, w=None):
    """Coordinates(Vector', W') such that a Detail-0 Noise Texture there with
    Scale·lacunarity^i is octave i of the distorted noise:
    Vector' = Vector + d·(s_0, s_1, s_2)/Scale (W' = W + d·s_3/Scale in 4D,
    W + d·s_0/Scale in 1D), s_k = snoise(p + o_k), p = Vector·Scale. Each
    s_k is 2·Fac − 1 of a normalized Detail-0 Noise Texture at Scale 1 on
    p + o_k, the same float operations as Blender's (noisetex.h). `vector`,
    `scale` and `w` (None: the model's W) are sockets or constants."""
    w = model.w if w is None else w
    if model.distortion == 0.0:
        return Coordinates(vector, w)
    p = b.vscale(vector, scale) if model.uses_vector else None
    pw = b.math("MULTIPLY", w, scale) if model.uses_w else None
    signed = []
    for o in model.distortion_offsets():
        shifted = Coordinates(b.vmath("ADD", p, _padded(o[:3])) if p is not None else None,
                              b.math("ADD", pw, o[-1]) if pw is not None else None)
        signed.append(b.math("MULTIPLY_ADD", octave_fac(b, shifted, 1.0, model), 2.0, -1.0))
    step = b.math("DIVIDE", model.distortion, scale)
    vector_out, w_out = vector, w
    if model.uses_vector:
        moves = (signed[:3] + [0.0, 0.0])[:3]  # 2D: no move along z
        vector_out = b.vmath("ADD", vector, b.vscale(b.combine(*moves), step))
    if model.uses_w:
        w_out = b.math("MULTIPLY_ADD", signed[-1], step, w)
    return Coordinates(vector_out, w_out)


def _padded(values):
    return tuple(values) + (0.0,) * (3 - len(values))
