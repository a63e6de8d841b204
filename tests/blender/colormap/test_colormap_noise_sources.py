"""The noise model (colormap/noise_model.py) against Blender's own textures:
each derivable Noise / Musgrave setting is rebuilt as offset + Σ c_i (Fac_i −
0.5) from Detail-0 octave nodes on the model's distorted coordinates, in a
geometry node tree beside the original node, and compared at 500 random
points; each setting that can't be derived raises NoiseNotDerivable naming
the node and the setting. The cases differ per Blender (Musgrave Texture in
3.x, Noise types and Normalize in 4.1+), chosen here by version, not skipped."""

import bpy
import numpy as np
import pytest

from penumbra.colormap import interface, node_builder, noise_maths, noise_model, noise_nodes

LEGACY = bpy.app.version < (4, 1, 0)  # Musgrave Texture; no Noise types, Lacunarity or Normalize

# (id, node type, dimensions, node properties, input values, links: "W"/"Scale")
_NOISE_CASES = [
    ("distortion-0.3", "ShaderNodeTexNoise", "3D", {}, {"Detail": 3.5, "Roughness": 0.6, "Distortion": 0.3}, ()),
    ("distortion-2-2d", "ShaderNodeTexNoise", "2D", {}, {"Detail": 2.0, "Distortion": 2.0}, ()),
    ("distortion-8", "ShaderNodeTexNoise", "3D", {}, {"Detail": 4.0, "Roughness": 0.7, "Distortion": 8.0}, ()),
    ("distortion-minus-1.2", "ShaderNodeTexNoise", "3D", {}, {"Detail": 1.0, "Distortion": -1.2}, ()),
    ("4d-constant-w", "ShaderNodeTexNoise", "4D", {}, {"Detail": 2.3, "W": 1.3, "Distortion": 1.5}, ()),
    ("4d-linked-w", "ShaderNodeTexNoise", "4D", {}, {"Detail": 3.0, "Distortion": 0.8}, ("W",)),
    ("1d-linked-w", "ShaderNodeTexNoise", "1D", {}, {"Detail": 2.5, "Distortion": 2.0}, ("W",)),
    ("fractional-detail-0.3", "ShaderNodeTexNoise", "3D", {}, {"Detail": 0.3}, ()),
    ("roughness-1.5", "ShaderNodeTexNoise", "3D", {}, {"Detail": 3.0, "Roughness": 1.5}, ()),
    ("linked-scale", "ShaderNodeTexNoise", "3D", {}, {"Detail": 2.0, "Distortion": 0.7}, ("Scale",)),
]
if LEGACY:
    _NOISE_CASES += [
        ("musgrave-fbm", "ShaderNodeTexMusgrave", "3D", {},
         {"Detail": 4.5, "Dimension": 1.2, "Lacunarity": 2.3}, ()),
        ("musgrave-fbm-2d", "ShaderNodeTexMusgrave", "2D", {}, {"Detail": 3.0}, ()),
        ("musgrave-fbm-4d", "ShaderNodeTexMusgrave", "4D", {}, {"Detail": 2.0, "Dimension": 0.7}, ("W",)),
        ("musgrave-fbm-detail-0.6", "ShaderNodeTexMusgrave", "3D", {}, {"Detail": 0.6}, ()),
        ("musgrave-multifractal-detail-0.6", "ShaderNodeTexMusgrave", "3D", {"musgrave_type": "MULTIFRACTAL"},
         {"Detail": 0.6}, ()),
        ("musgrave-hybrid-detail-1", "ShaderNodeTexMusgrave", "3D", {"musgrave_type": "HYBRID_MULTIFRACTAL"},
         {"Detail": 1.0, "Offset": 0.3}, ()),
        ("musgrave-hetero-detail-0", "ShaderNodeTexMusgrave", "3D", {"musgrave_type": "HETERO_TERRAIN"},
         {"Detail": 0.0, "Offset": 0.5}, ()),
    ]
else:
    _NOISE_CASES += [
        ("unnormalized", "ShaderNodeTexNoise", "3D", {"normalize": False},
         {"Detail": 3.4, "Roughness": 0.7, "Lacunarity": 2.5, "Distortion": 0.5}, ()),
        ("unnormalized-4d", "ShaderNodeTexNoise", "4D", {"normalize": False},
         {"Detail": 2.0, "Roughness": 0.4, "Distortion": 1.0}, ("W",)),
        ("lacunarity-1.7", "ShaderNodeTexNoise", "3D", {}, {"Detail": 5.0, "Lacunarity": 1.7}, ()),
        ("multifractal-detail-0", "ShaderNodeTexNoise", "3D", {"noise_type": "MULTIFRACTAL"},
         {"Detail": 0.0, "Distortion": 0.4}, ()),
        ("hetero-roughness-0", "ShaderNodeTexNoise", "3D", {"noise_type": "HETERO_TERRAIN"},
         {"Detail": 3.0, "Roughness": 0.0, "Offset": 0.4}, ()),
        ("hybrid-detail-0", "ShaderNodeTexNoise", "2D", {"noise_type": "HYBRID_MULTIFRACTAL"},
         {"Detail": 0.0, "Offset": 0.2}, ()),
    ]


def _socket(node, identifier):
    """An input by identifier: 4.x does not find an unavailable one by name."""
    return next(s for s in node.inputs if s.identifier == identifier)


class _Points:
    """A geometry node tree holding the node under test (its Vector: the
    point's position) and the rebuild, each stored as a point attribute."""

    def __init__(self, node_type, dimensions, properties, values, links):
        mesh = bpy.data.meshes.new("noise_points")
        self.obj = bpy.data.objects.new("noise_points", mesh)
        bpy.context.scene.collection.objects.link(self.obj)
        group = bpy.data.node_groups.new("noise at points", "GeometryNodeTree")
        interface.add_socket(group, "Geometry", "INPUT", "NodeSocketGeometry")
        interface.add_socket(group, "Geometry", "OUTPUT", "NodeSocketGeometry")
        self.group, self.b = group, node_builder.Builder(group)
        self.geometry = group.nodes.new("NodeGroupInput").outputs[0]
        self.output = group.nodes.new("NodeGroupOutput").inputs[0]
        self.node = group.nodes.new(node_type)
        self.node.name = "Bumps"
        setattr(self.node, "musgrave_dimensions" if node_type.endswith("Musgrave") else "noise_dimensions",
                dimensions)
        for key, value in properties.items():
            setattr(self.node, key, value)
        _socket(self.node, "Scale").default_value = 1.7
        for key, value in values.items():
            _socket(self.node, key).default_value = value
        position = group.nodes.new("GeometryNodeInputPosition").outputs[0]
        group.links.new(position, _socket(self.node, "Vector"))
        if "W" in links:  # W varies over the points
            group.links.new(self.b.vmath("DOT_PRODUCT", position, (0.31, -0.7, 0.52)), _socket(self.node, "W"))
        if "Scale" in links:
            value = group.nodes.new("ShaderNodeValue")
            value.outputs[0].default_value = 2.1
            group.links.new(value.outputs[0], _socket(self.node, "Scale"))
        self.obj.modifiers.new("noise", "NODES").node_group = group

    def store(self, values):
        """Stores each named float socket on the points, then wires the output."""
        geometry = self.geometry
        for name, socket in values.items():
            store = self.group.nodes.new("GeometryNodeStoreNamedAttribute")
            store.data_type, store.domain = "FLOAT", "POINT"
            store.inputs["Name"].default_value = name
            value = [s for s in store.inputs if s.name == "Value" and s.type == "VALUE"]
            self.group.links.new(socket, value[0] if value else store.inputs["Value"])
            self.group.links.new(geometry, store.inputs["Geometry"])
            geometry = store.outputs[0]
        self.group.links.new(geometry, self.output)

    def evaluate(self, points, names):
        mesh = self.obj.data
        mesh.clear_geometry()
        mesh.vertices.add(len(points))
        mesh.vertices.foreach_set("co", points.astype(np.float32).ravel())
        mesh.update()
        attributes = self.obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.attributes
        out = {}
        for name in names:
            data = attributes[name].data
            out[name] = np.empty(len(data), np.float32)
            data.foreach_get("value", out[name])
        return out


def rebuild(b, model):
    """offset + Σ c_i (Fac_i − 0.5), each octave a Detail-0 Noise Texture at
    the model's distorted coordinates with Scale·lacunarity^i."""
    scale = model.scale if model.scale is not None else model.scale_from
    coordinates = noise_nodes.distorted_vector(b, model.vector_from, scale, model,
                                               w=model.w_from if model.w is None else None)
    value = model.offset
    for i, c in enumerate(model.coefficients):
        octave_scale = scale * model.lacunarity ** i if model.scale is not None else \
            b.math("MULTIPLY", scale, model.lacunarity ** i)
        fac = noise_nodes.octave_fac(b, coordinates, octave_scale, model)
        value = b.math("MULTIPLY_ADD", b.math("SUBTRACT", fac, 0.5), c, value)
    return value


@pytest.mark.parametrize("case", _NOISE_CASES, ids=[c[0] for c in _NOISE_CASES])
def test_the_model_rebuilds_blenders_noise_from_detail_0_octaves(addon, case):
    """Blender's own node against the rebuild from its model at 500 random
    points: within 1e-4 (float32), for distortion, dimensions, fractional
    Detail, unnormalized fBm (4.1+) and Musgrave fBm (3.x)."""
    _, node_type, dimensions, properties, values, links = case
    points = _Points(node_type, dimensions, properties, values, links)
    model = noise_model.read_noise(points.node, points.node.outputs["Fac"])
    assert model.node_name == "Bumps" and model.dimensions == dimensions
    assert model.distortion == pytest.approx(values.get("Distortion", 0.0))
    assert (model.scale is None) == ("Scale" in links) and (model.w is None) == ("W" in links)
    points.store({"full": points.node.outputs["Fac"], "rebuilt": rebuild(points.b, model)})
    xyz = np.random.default_rng(5).uniform(-10, 10, (500, 3))
    out = points.evaluate(xyz, ("full", "rebuilt"))
    full, rebuilt = out["full"].astype(np.float64), out["rebuilt"].astype(np.float64)
    spread = max(model.mean_max - model.mean_min, 1e-9)
    assert np.std(full) > 0.02 * spread, "the case must vary over the points"
    assert full.min() >= model.mean_min - 1e-3 and full.max() <= model.mean_max + 1e-3
    error = float(np.max(np.abs(rebuilt - full)))
    print(f"\n{case[0]}: max |rebuilt - Blender| = {error:.2e} over {len(full)} points (Blender "
          f"{bpy.app.version_string})")
    assert error <= 1e-4, error


def test_normalized_fbm_is_today_octave_weights_and_spans_0_to_1(addon):
    points = _Points("ShaderNodeTexNoise", "3D", {}, {"Detail": 2.6, "Roughness": 0.8}, ())
    model = noise_model.read_noise(points.node)
    assert model.offset == 0.5
    assert model.coefficients == pytest.approx(noise_maths.octave_weights(2.6, 0.8, bpy.app.version))
    assert (model.mean_min, model.mean_max) == pytest.approx((0.0, 1.0))
    assert model.total_weight_sq == pytest.approx(sum(w * w for w in model.coefficients))
    assert model.vector_from is not None and model.scale == pytest.approx(1.7)


def test_distortion_offsets_are_blenders_hash():
    """Spot values of Blender's offsets (noisetex.h): 1D uses hash_uint, 2D-4D
    hash_uint2; all components lie in [100, 200] and differ per seed."""
    offsets = [noise_maths.random_offset(float(seed), axes) for axes in (1, 2, 3, 4) for seed in range(4)]
    values = [v for o in offsets for v in o]
    assert all(100.0 <= v <= 200.0 for v in values)
    assert noise_maths.random_offset(0.0, 3) == noise_maths.random_offset(0.0, 4)[:3]
    assert len(set(values)) == 20  # 4 of 1D, then component k of seed s is shared by 2D-4D


# ---- settings that can't be derived ----------------------------------------

def _not_derivable(node_type, properties, values, links=(), output="Fac", dimensions="3D"):
    points = _Points(node_type, dimensions, properties, values, ())
    node = points.node
    for name in links:
        source = points.group.nodes.new("ShaderNodeValue")
        source.outputs[0].default_value = values.get(name, 1.0)
        points.group.links.new(source.outputs[0], _socket(node, name))
    with pytest.raises(noise_model.NoiseNotDerivable) as raised:
        noise_model.read_noise(node, node.outputs[output])
    message = str(raised.value)
    assert "'Bumps'" in message, message
    return message


_REFUSED = [  # (id, node type, properties, values, linked inputs, output, words the message must hold)
    ("linked-detail", "ShaderNodeTexNoise", {}, {}, ("Detail",), "Fac", ("Noise Texture", "Detail", "link")),
    ("linked-roughness", "ShaderNodeTexNoise", {}, {}, ("Roughness",), "Fac", ("Roughness", "link")),
    ("linked-distortion", "ShaderNodeTexNoise", {}, {}, ("Distortion",), "Fac", ("Distortion", "link")),
    ("linked-detail-and-roughness", "ShaderNodeTexNoise", {}, {}, ("Detail", "Roughness"), "Fac",
     ("Detail and Roughness are",)),
    ("color-output", "ShaderNodeTexNoise", {}, {}, (), "Color", ("Color output",)),
]
if LEGACY:
    _REFUSED += [
        ("musgrave-ridged", "ShaderNodeTexMusgrave", {"musgrave_type": "RIDGED_MULTIFRACTAL"}, {"Detail": 0.0},
         (), "Fac", ("Musgrave Texture", "Ridged Multifractal", "nonlinear")),
        ("musgrave-multifractal", "ShaderNodeTexMusgrave", {"musgrave_type": "MULTIFRACTAL"}, {"Detail": 2.5},
         (), "Fac", ("Multifractal", "nonlinear", "Detail 2.5")),
        ("musgrave-hybrid", "ShaderNodeTexMusgrave", {"musgrave_type": "HYBRID_MULTIFRACTAL"}, {"Detail": 1.5},
         (), "Fac", ("Hybrid Multifractal", "nonlinear")),
        ("musgrave-hetero", "ShaderNodeTexMusgrave", {"musgrave_type": "HETERO_TERRAIN"}, {"Detail": 0.5},
         (), "Fac", ("Hetero Terrain", "nonlinear")),
        ("musgrave-linked-dimension", "ShaderNodeTexMusgrave", {}, {}, ("Dimension",), "Fac",
         ("Dimension", "link")),
        ("musgrave-linked-lacunarity", "ShaderNodeTexMusgrave", {}, {}, ("Lacunarity",), "Fac",
         ("Lacunarity", "link")),
        ("musgrave-hybrid-linked-gain", "ShaderNodeTexMusgrave", {"musgrave_type": "HYBRID_MULTIFRACTAL"},
         {"Detail": 1.0}, ("Gain",), "Fac", ("Gain", "link")),
    ]
else:
    _REFUSED += [
        ("ridged", "ShaderNodeTexNoise", {"noise_type": "RIDGED_MULTIFRACTAL"}, {"Detail": 0.0}, (), "Fac",
         ("Ridged Multifractal", "nonlinear")),
        ("multifractal", "ShaderNodeTexNoise", {"noise_type": "MULTIFRACTAL"}, {"Detail": 2.0}, (), "Fac",
         ("Multifractal", "nonlinear", "Detail 2")),
        ("hybrid", "ShaderNodeTexNoise", {"noise_type": "HYBRID_MULTIFRACTAL"}, {"Detail": 1.5}, (), "Fac",
         ("Hybrid Multifractal", "nonlinear")),
        ("hetero", "ShaderNodeTexNoise", {"noise_type": "HETERO_TERRAIN"}, {"Detail": 3.0}, (), "Fac",
         ("Hetero Terrain", "nonlinear")),
        ("linked-lacunarity", "ShaderNodeTexNoise", {}, {}, ("Lacunarity",), "Fac", ("Lacunarity", "link")),
        ("hetero-linked-offset", "ShaderNodeTexNoise", {"noise_type": "HETERO_TERRAIN"}, {"Detail": 0.0},
         ("Offset",), "Fac", ("Offset", "link")),
    ]


@pytest.mark.parametrize("case", _REFUSED, ids=[c[0] for c in _REFUSED])
def test_a_setting_that_cannot_be_derived_is_reported_by_name(addon, case):
    _, node_type, properties, values, links, output, words = case
    message = _not_derivable(node_type, properties, values, links, output)
    for word in words:
        assert word in message, (word, message)


def test_texture_mapping_and_other_nodes_are_reported(addon):
    points = _Points("ShaderNodeTexNoise", "3D", {}, {}, ())
    points.node.texture_mapping.scale[0] = 2.0
    with pytest.raises(noise_model.NoiseNotDerivable, match="'Bumps'.*Texture Mapping"):
        noise_model.read_noise(points.node)
    voronoi = points.group.nodes.new("ShaderNodeTexVoronoi")
    voronoi.name = "Cells"
    with pytest.raises(noise_model.NoiseNotDerivable, match="'Cells'.*not a Noise or Musgrave Texture"):
        noise_model.read_noise(voronoi)


def test_a_link_into_an_input_the_type_ignores_is_harmless(addon):
    """fBm ignores Offset and Gain: a link there is not a reason to refuse."""
    node_type = "ShaderNodeTexMusgrave" if LEGACY else "ShaderNodeTexNoise"
    points = _Points(node_type, "3D", {}, {"Detail": 2.0}, ())
    source = points.group.nodes.new("ShaderNodeValue")
    for name in ("Offset", "Gain"):  # unavailable for fBm
        points.group.links.new(source.outputs[0], _socket(points.node, name))
    model = noise_model.read_noise(points.node)
    assert model.noise_type == "FBM" and len(model.coefficients) >= 2
