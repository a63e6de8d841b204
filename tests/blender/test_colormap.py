"""The colour-map tool inside real Blender (3.4 and 4.5): ColorRamp
evaluation against Blender's own, the bake operator end to end, node groups
in both node-group APIs, bad input, tiny Cycles renders, and the
microsurface (height / slope) groups evaluated by Cycles against the core."""

import os
import sys

import bpy
import numpy as np
import pytest

import penumbra
from penumbra import compat, native

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "examples"))
import colormap_scene  # noqa: E402  (the scene users can copy, examples/colormap_scene.py)
from penumbra.colormap import interface, node_groups

INTERPOLATIONS = ("LINEAR", "EASE", "CARDINAL", "B_SPLINE", "CONSTANT")
COLOR_MODES = ("RGB", "HSV", "HSL")
HUES = ("NEAR", "FAR", "CW", "CCW")


@pytest.fixture
def addon(factory_scene):
    penumbra.register()
    factory_scene.penumbra.colormap.output_folder = ""
    yield factory_scene
    penumbra.unregister()


def make_ramp_material(name="ramped", noise=True):
    material = bpy.data.materials.new(name)
    tree = compat.ensure_nodes(material)
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    elements = ramp.color_ramp.elements
    elements[0].color = (0.9, 0.1, 0.05, 1.0)
    elements[1].color = (0.05, 0.2, 0.9, 1.0)
    elements[0].position = 0.45
    elements[1].position = 0.55
    bsdf = tree.nodes["Principled BSDF"]
    tree.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    if noise:
        tex = tree.nodes.new("ShaderNodeTexNoise")
        tex.inputs["Scale"].default_value = 20.0
        tree.links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    tree.nodes.active = ramp
    return material, ramp


def plane_with(material):
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    obj = bpy.context.active_object
    obj.data.materials.append(material)
    return obj


def random_ramp(rng, node, count):
    elements = node.color_ramp.elements
    while len(elements) < count:
        elements.new(0.5)
    positions = np.sort(rng.uniform(0, 1, count))
    positions[1] = positions[0]  # two stops at one place
    for e, p in zip(elements, positions):
        e.position = float(p)
        e.color = tuple(rng.uniform(0, 1, 4))


@pytest.mark.parametrize("interpolation", INTERPOLATIONS)
def test_ramp_evaluation_matches_blenders_own_in_every_mode(addon, interpolation):
    core = native.require()
    material, node = make_ramp_material(noise=False)
    rng = np.random.default_rng(7)
    random_ramp(rng, node, 6)
    positions = np.concatenate([np.linspace(0, 1, 501), [s.position for s in node.color_ramp.elements]])
    from penumbra.colormap import ramp as ramp_io
    for mode in COLOR_MODES:
        for hue in (HUES if mode != "RGB" else ("NEAR",)):
            node.color_ramp.interpolation = interpolation
            node.color_ramp.color_mode = mode
            node.color_ramp.hue_interpolation = hue
            stops = ramp_io.ramp_stops(node)
            ours = core.colormap.evaluate_ramp(stops, positions.astype(np.float32), interpolation, mode, hue)
            blenders = np.array([node.color_ramp.evaluate(float(p)) for p in positions], np.float32)
            np.testing.assert_allclose(ours, blenders, atol=2e-6, err_msg=f"{interpolation} {mode} {hue}")


def test_bake_replaces_a_noise_driven_ramp_and_keeps_the_original(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = 64
    addon.penumbra.colormap.lut_height = 32
    material, ramp = make_ramp_material()
    obj = plane_with(material)
    bpy.ops.object.camera_add(location=(0, -6, 3), rotation=(1.1, 0, 0))
    addon.camera = bpy.context.active_object
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    group_node = tree.nodes[node_groups.FILTERED_RAMP]
    assert group_node.node_tree.name.startswith(node_groups.FILTERED_RAMP)
    assert interface.socket_names(group_node.node_tree, "INPUT") == ["Mean", "Sigma"]
    assert interface.socket_names(group_node.node_tree, "OUTPUT") == ["Color", "Alpha"]
    bsdf = tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Base Color"].links[0].from_node == group_node
    assert ramp.mute and ramp.name in tree.nodes
    noise_filter = group_node.inputs["Sigma"].links[0].from_node
    assert noise_filter.node_tree.name.startswith("Penumbra Noise Filter")
    # The noise's (unlinked, so Generated) coordinates and its Scale feed the octave filter.
    coords = noise_filter.inputs["Vector"].links[0].from_node
    assert coords.bl_idname == "ShaderNodeTexCoord" and noise_filter.inputs["Vector"].links[0].from_socket.name == "Generated"
    assert noise_filter.inputs["Scale"].default_value == pytest.approx(20.0)
    assert noise_filter.inputs["Units per World"].default_value == pytest.approx(0.25)  # 4 × 4 plane
    footprint = noise_filter.inputs["Minor"].links[0].from_node
    assert noise_filter.inputs["Major"].links[0].from_node == footprint
    assert footprint.inputs["Pixel Size"].default_value > 0
    weights = noise_filter.node_tree["penumbra_octave_weights"]
    assert len(weights) == 3 and sum(weights) == pytest.approx(1.0)  # Detail 2 (the default): 3 octaves
    # The lookup image: float EXR, no colour transform, no wrap.
    image_node = next(n for n in group_node.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
    assert image_node.extension == "EXTEND" and image_node.interpolation == "Linear"
    image = image_node.image
    assert image.colorspace_settings.name == "Non-Color" and image.is_float
    path = bpy.path.abspath(image.filepath)
    assert os.path.isfile(path) and path.endswith(".exr")
    # Blender reads back exactly the table the core computes (bottom row = σ 0).
    spec = group_node.node_tree["penumbra_lookup"]
    pixels = np.empty(64 * 32 * 4, np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(32, 64, 4)
    from penumbra.colormap import ramp as ramp_io
    knots = native.module.colormap.ramp_to_knots(ramp_io.ramp_stops(ramp), "LINEAR", "RGB", "NEAR", sampling="cycles")
    expect = native.module.colormap.lut_knots(knots["positions"], knots["colors"], knots["interpolation"], 64, 32,
                                              spec["sigma_max"], spec["mean_min"], spec["mean_max"])
    np.testing.assert_allclose(pixels, expect, atol=1e-6)
    # Restore puts the ramp back.
    tree.nodes.active = group_node
    assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
    assert not ramp.mute and bsdf.inputs["Base Color"].links[0].from_node == ramp
    assert not [n.name for n in tree.nodes if n.name.startswith("Penumbra")]


def test_bake_is_undone_and_redone_by_blenders_undo(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    material, ramp = make_ramp_material(name="undoable", noise=False)
    plane_with(material)
    before = sorted(n.name for n in material.node_tree.nodes)
    ramp_name = ramp.name
    bpy.ops.ed.undo_push(message="before bake")
    # undo=True: push an undo step as a click in the UI does (bl_options UNDO).
    assert bpy.ops.penumbra.bake_colormap_lut("EXEC_DEFAULT", True) == {"FINISHED"}
    baked = sorted(n.name for n in bpy.data.materials["undoable"].node_tree.nodes)
    assert node_groups.FILTERED_RAMP in baked
    # Undo restores data blocks from memory: look everything up again by name.
    assert bpy.ops.ed.undo() == {"FINISHED"}
    tree = bpy.data.materials["undoable"].node_tree
    assert sorted(n.name for n in tree.nodes) == before
    assert not tree.nodes[ramp_name].mute
    assert bpy.ops.ed.redo() == {"FINISHED"}
    tree = bpy.data.materials["undoable"].node_tree
    assert sorted(n.name for n in tree.nodes) == baked
    assert tree.nodes[ramp_name].mute


def test_failure_after_the_lookup_is_written_changes_nothing(addon, tmp_path, monkeypatch):
    settings = addon.penumbra.colormap
    settings.output_folder = str(tmp_path)
    settings.lut_width = settings.lut_height = 16
    material, ramp = make_ramp_material(name="fragile")
    plane_with(material)
    bpy.ops.object.camera_add(location=(0, -6, 3), rotation=(1.1, 0, 0))
    addon.camera = bpy.context.active_object
    bpy.context.view_layer.objects.active = bpy.data.objects["Plane"]
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}  # an earlier, good bake
    tree = material.node_tree
    tree.nodes.active = tree.nodes[node_groups.FILTERED_RAMP]
    assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
    tree.nodes.active = ramp
    ramp.color_ramp.elements[0].color = (0.0, 1.0, 0.0, 1.0)  # the new bake would differ
    files = {name: (tmp_path / name).read_bytes() for name in os.listdir(tmp_path)}
    nodes = sorted(n.name for n in tree.nodes)
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    images, groups = len(bpy.data.images), len(bpy.data.node_groups)

    def fail(*args, **kwargs):
        raise RuntimeError("simulated failure while building the node group")

    monkeypatch.setattr(node_groups, "filtered_ramp_group", fail)
    with pytest.raises(RuntimeError, match="simulated failure"):
        bpy.ops.penumbra.bake_colormap_lut()
    assert {name: (tmp_path / name).read_bytes() for name in os.listdir(tmp_path)} == files
    assert sorted(n.name for n in tree.nodes) == nodes
    assert sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                  for l in tree.links) == links
    assert (len(bpy.data.images), len(bpy.data.node_groups)) == (images, groups)
    assert not ramp.mute


@pytest.mark.parametrize("problem", ["not_a_ramp", "no_nodes", "nan_colour", "no_material"])
def test_bad_input_is_reported_and_nothing_changes(addon, problem):
    material, ramp = make_ramp_material(noise=False)
    obj = plane_with(material)
    tree = material.node_tree
    if problem == "not_a_ramp":
        tree.nodes.active = tree.nodes["Principled BSDF"]
    elif problem == "no_nodes":
        if bpy.app.version >= (5, 0, 0):
            # Blender 5.0 made every material node-based: Material.use_nodes is
            # deprecated, always True, and setting it does nothing (5.0 Python
            # API release notes, "Shading", PR #141278). The ramp is what Blender
            # renders, so there is nothing to refuse: the bake goes ahead.
            with pytest.warns(DeprecationWarning):
                material.use_nodes = False
            assert compat.uses_nodes(material)
            assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
            assert ramp.mute and tree.nodes.active.name == node_groups.FILTERED_RAMP
            return
        material.use_nodes = False
    elif problem == "nan_colour":
        ramp.color_ramp.elements[0].color = (float("nan"), 0.0, 0.0, 1.0)
    elif problem == "no_material":
        obj.data.materials.clear()
    names = sorted(n.name for n in tree.nodes)
    images = len(bpy.data.images)
    with pytest.raises(RuntimeError) as error:
        bpy.ops.penumbra.bake_colormap_lut()
    assert {"not_a_ramp": "not a ColorRamp", "no_nodes": "does not use nodes", "nan_colour": "NaN",
            "no_material": "No active material"}[problem] in str(error.value)
    assert sorted(n.name for n in tree.nodes) == names
    assert len(bpy.data.images) == images
    assert not ramp.mute


def test_single_stop_ramp_bakes_a_constant_lookup(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 8
    material, ramp = make_ramp_material(noise=False)
    ramp.color_ramp.elements.remove(ramp.color_ramp.elements[1])
    plane_with(material)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    image = next(n for n in material.node_tree.nodes[node_groups.FILTERED_RAMP].node_tree.nodes
                 if n.bl_idname == "ShaderNodeTexImage").image
    pixels = np.empty(8 * 8 * 4, np.float32)
    image.pixels.foreach_get(pixels)
    np.testing.assert_allclose(pixels.reshape(-1, 4), np.tile([0.9, 0.1, 0.05, 1.0], (64, 1)), atol=1e-6)


def test_linked_material_is_read_only(addon, tmp_path):
    library = str(tmp_path / "library.blend")
    material, _ = make_ramp_material("shared")
    material.use_fake_user = True
    bpy.data.libraries.write(library, {material})
    bpy.data.materials.remove(material)
    with bpy.data.libraries.load(library, link=True) as (data_from, data_to):
        data_to.materials = ["shared"]
    linked = bpy.data.materials["shared", bpy.path.relpath(library) if False else library] \
        if False else next(m for m in bpy.data.materials if m.library is not None)
    obj = plane_with(bpy.data.materials.new("placeholder"))
    obj.material_slots[0].link = "OBJECT"
    obj.material_slots[0].material = linked
    obj.active_material_index = 0
    with pytest.raises(RuntimeError, match="read-only"):
        bpy.ops.penumbra.bake_colormap_lut()
    assert all(n.bl_idname != "ShaderNodeGroup" for n in linked.node_tree.nodes)


def test_bake_from_an_image_makes_a_lookup_and_group(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    image = bpy.data.images.new("strip", 8, 3, float_buffer=True)
    pixels = np.zeros((3, 8, 4), np.float32)
    pixels[..., 0] = np.linspace(0, 1, 8)
    pixels[..., 3] = 1
    image.pixels.foreach_set(pixels.ravel())
    assert bpy.ops.penumbra.bake_colormap_lut(image_name="strip") == {"FINISHED"}
    assert any(g.name.startswith(node_groups.FILTERED_RAMP) for g in bpy.data.node_groups)
    assert os.path.isfile(os.path.join(str(tmp_path), "strip_lut.exr"))


def test_microsurface_groups_build_in_this_blenders_api(addon, tmp_path):
    image = bpy.data.images.new("lut", 8, 8, float_buffer=True)
    spec = {"width": 8, "height": 8, "sigma_max": 0.3, "mean_min": 0.0, "mean_max": 1.0, "sigma_spacing": "linear"}
    height = node_groups.height_ramp_group(image, spec)
    slope = node_groups.slope_ramp_group(image, spec)
    assert interface.socket_names(height, "OUTPUT") == ["Color", "Alpha", "Visibility"]
    assert "Slope Sigma" in interface.socket_names(slope, "INPUT")
    table = bpy.data.images[node_groups.MICROSURFACE_IMAGE]
    px = np.empty(256 * 2 * 4, np.float32)
    table.pixels.foreach_get(px)
    px = px.reshape(2, 256, 4)
    # Row 0, G at Λ_sum = 1 (u = 0.5 → texel 127.5): mean of the max of 2 normals, 1/√π.
    assert abs(0.5 * (px[0, 127, 1] + px[0, 128, 1]) - 0.5642) < 0.01


def _noise_evaluator():
    """Blender's own Noise Texture at given points, through geometry nodes."""
    mesh = bpy.data.meshes.new("noise_points")
    obj = bpy.data.objects.new("noise_points", mesh)
    bpy.context.scene.collection.objects.link(obj)
    group = bpy.data.node_groups.new("noise at points", "GeometryNodeTree")
    interface.add_socket(group, "Geometry", "INPUT", "NodeSocketGeometry")
    interface.add_socket(group, "Geometry", "OUTPUT", "NodeSocketGeometry")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    noise = group.nodes.new("ShaderNodeTexNoise")
    store = group.nodes.new("GeometryNodeStoreNamedAttribute")
    store.data_type, store.domain = "FLOAT", "POINT"
    store.inputs["Name"].default_value = "noise"
    group.links.new(group.nodes.new("GeometryNodeInputPosition").outputs[0], noise.inputs["Vector"])
    group.links.new(gin.outputs[0], store.inputs["Geometry"])
    value = [s for s in store.inputs if s.name == "Value" and s.type == "VALUE"]
    group.links.new(noise.outputs["Fac"], value[0] if value else store.inputs["Value"])
    group.links.new(store.outputs[0], gout.inputs[0])
    obj.modifiers.new("noise", "NODES").node_group = group

    def evaluate(points):
        mesh.clear_geometry()
        mesh.vertices.add(len(points))
        mesh.vertices.foreach_set("co", points.astype(np.float32).ravel())
        mesh.update()
        data = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.attributes["noise"].data
        out = np.empty(len(data), np.float32)
        data.foreach_get("value", out)
        return out
    return noise, evaluate


@pytest.mark.parametrize("detail, roughness", [(4.0, 0.5), (2.6, 0.8), (0.3, 0.5), (6.0, 1.0)])
def test_octave_weights_rebuild_blenders_noise(addon, detail, roughness):
    """The octave filter rebuilds the noise as Σ w_i · Noise(Detail 0,
    Scale·2^i): checked against Blender's own multi-octave Noise Texture."""
    from penumbra.colormap import noise_statistics
    noise, evaluate = _noise_evaluator()
    points = np.random.default_rng(3).uniform(-40, 40, (500, 3))
    noise.inputs["Scale"].default_value = 1.7
    noise.inputs["Detail"].default_value = detail
    noise.inputs["Roughness"].default_value = roughness
    full = evaluate(points)
    weights = noise_statistics.octave_weights(detail, roughness)
    assert len(weights) == int(np.floor(detail)) + 1 + (1 if detail % 1 else 0)
    noise.inputs["Detail"].default_value = 0.0
    rebuilt = np.zeros_like(full)
    for i, w in enumerate(weights):
        noise.inputs["Scale"].default_value = 1.7 * 2.0 ** i
        rebuilt += w * evaluate(points)
    assert np.std(full) > 0.03
    np.testing.assert_allclose(rebuilt, full, atol=1e-5)


RENDER_W, RENDER_H = 48, 32


def _render_scene(scene, pitch_deg, filter_box=False):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x, scene.render.resolution_y = RENDER_W, RENDER_H
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    if filter_box:  # shade each pixel at its centre
        scene.cycles.pixel_filter_type = "BOX"
        scene.cycles.filter_width = 0.01
    plane, material, ramp, emission, camera = colormap_scene.noise_ramp_plane(
        plane_size=600.0, plane_location=(0, 250, 0), camera_location=(0.2, -2, 1.2),
        camera_rotation_degrees=(pitch_deg, 0, 5))
    return material, ramp, emission, camera


def _render(scene, path, spp, seed):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return native.require().image.read(path)[..., :3].astype(np.float64)


def test_footprint_node_matches_the_projected_pixel(addon, tmp_path):
    """The footprint group rendered at pixel centres against the footprint
    computed here from the camera: the pixel's edge midpoints projected onto
    the plane z = 0 (finite-difference Jacobian: √|det| and singular values)."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    material, ramp, emission, camera = _render_scene(addon, 72.0, filter_box=True)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    footprint = tree.nodes[node_groups.FOOTPRINT]
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    for i, name in enumerate(("Footprint", "Minor", "Major")):
        tree.links.new(footprint.outputs[name], combine.inputs[i])
    tree.links.new(combine.outputs[0], emission.inputs["Color"])
    image = _render(addon, str(tmp_path / "footprint.exr"), 1, 0)
    frame = [camera.matrix_world @ v for v in camera.data.view_frame(scene=addon)]
    top_right, _, bottom_left, top_left = frame
    origin = camera.matrix_world.translation

    def on_plane(x, y):
        point = top_left + (top_right - top_left) * (x / RENDER_W) + (bottom_left - top_left) * (y / RENDER_H)
        d = point - origin
        return np.array(origin - d * (origin.z / d.z))[:2]

    checked = 0
    for y in range(2, RENDER_H, 5):
        for x in (3, RENDER_W // 2, RENDER_W - 4):
            ju = on_plane(x + 1.0, y + 0.5) - on_plane(x, y + 0.5)
            jv = on_plane(x + 0.5, y + 1.0) - on_plane(x + 0.5, y)
            major, minor = np.linalg.svd(np.column_stack([ju, jv]), compute_uv=False)
            node = image[y, x]
            np.testing.assert_allclose(node, [np.sqrt(major * minor), minor, major], rtol=0.01,
                                       err_msg=f"pixel {x}, {y}")
            checked += 1
    assert checked >= 15

    # Position + Centre Offset: where the ray through the pixel's centre meets
    # the plane, the same for every sample of the pixel. A 1-px box filter at
    # 8 spp keeps the samples inside their pixel and spreads them over it.
    addon.cycles.filter_width = 1.0
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    add = tree.nodes.new("ShaderNodeVectorMath")
    add.operation = "ADD"
    tree.links.new(geometry.outputs["Position"], add.inputs[0])
    tree.links.new(footprint.outputs["Centre Offset"], add.inputs[1])
    tree.links.new(add.outputs[0], emission.inputs["Color"])
    snapped = _render(addon, str(tmp_path / "centre.exr"), 8, 3)
    tree.links.new(geometry.outputs["Position"], emission.inputs["Color"])
    raw = _render(addon, str(tmp_path / "position.exr"), 8, 3)
    moved = 0
    for y in range(2, RENDER_H, 5):
        for x in (3, RENDER_W // 2, RENDER_W - 4):
            centre = on_plane(x + 0.5, y + 0.5)
            pixel = np.linalg.norm(on_plane(x + 1.0, y + 0.5) - on_plane(x, y + 0.5))
            np.testing.assert_allclose(snapped[y, x, :2], centre, atol=1e-3 * pixel, err_msg=f"pixel {x}, {y}")
            moved += np.linalg.norm(raw[y, x, :2] - centre) > 0.01 * pixel
    assert moved > 10  # the raw position does differ from the centre


def test_filtered_render_is_closer_to_the_reference_than_the_plain_ramp(addon, tmp_path):
    """A small Cycles render: the plane receding to the horizon through a
    sharp ramp. At 1 spp the filtered material is much closer to a 256-spp
    render of the plain ramp than the plain ramp at 1 spp, and in the far
    field (where the ramp averages out) its mean colour matches the reference."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 84.0)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    group = tree.nodes[node_groups.FILTERED_RAMP]
    ramp.mute = False
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    reference = _render(addon, str(tmp_path / "reference.exr"), 256, 7)
    plain = _render(addon, str(tmp_path / "plain.exr"), 1, 1)
    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    filtered = _render(addon, str(tmp_path / "filtered.exr"), 1, 1)
    ground = reference.sum(axis=2) > 0  # the plane (the sky is black)
    assert ground.mean() > 0.5

    def rmse(image):
        return float(np.sqrt(((image - reference)[ground] ** 2).mean()))
    assert rmse(filtered) < 0.6 * rmse(plain), (rmse(filtered), rmse(plain))
    far = ground & (np.arange(RENDER_H)[:, None] < RENDER_H * 0.45)  # the rows near the horizon
    assert far.sum() > 50
    np.testing.assert_allclose(filtered[far].mean(axis=0), reference[far].mean(axis=0), atol=0.02)


# ---- The microsurface groups (paper Sec. 5.1 / 5.2) evaluated by Cycles -----
# One tiny plane per pixel under an orthographic camera looking down −Z: each
# plane has its own tilt (so its own view angle: Incoming is +Z everywhere)
# and carries the group's inputs as custom properties, read by Attribute
# nodes (Object). A 0.01-px box filter at 1 spp shades each pixel at its
# centre, which sees only its own plane (side 0.5 px).
GRID = 8
# Colour map of the tests: R = v (the filtered mean itself), G a wave
# (sensitive to σ), B = v², 129 knots joined linearly.
_KNOTS = np.linspace(0.0, 1.0, 129)
_MAP = np.column_stack([_KNOTS, 0.5 + 0.4 * np.sin(3.0 * np.pi * _KNOTS), _KNOTS ** 2])


def _pixel_planes(scene, normals, props):
    """An orthographic GRID × GRID render of one small plane per pixel; pixel
    (row j from the top, column i) holds planes[j * GRID + i], whose normal is
    normals[k] and whose custom properties are props[k] (name -> 3-vector).
    Returns the emission node's material tree and the emission node."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.samples = 1
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x = scene.render.resolution_y = GRID
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = GRID
    camera.location = (0.0, 0.0, 10.0)
    scene.camera = camera
    mesh = bpy.data.meshes.new("quad")
    s = 0.25
    mesh.from_pydata([(-s, -s, 0), (s, -s, 0), (s, s, 0), (-s, s, 0)], [], [(0, 1, 2, 3)])
    material = bpy.data.materials.new("probe")
    tree = compat.ensure_nodes(material)
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    mesh.materials.append(material)
    from mathutils import Vector
    for k, (normal, values) in enumerate(zip(normals, props)):
        obj = bpy.data.objects.new(f"probe{k}", mesh)
        scene.collection.objects.link(obj)
        j, i = divmod(k, GRID)
        obj.location = (-GRID / 2 + i + 0.5, GRID / 2 - j - 0.5, 0.0)
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(normal))
        for name, value in values.items():
            obj[name] = [float(v) for v in value]
    bpy.context.view_layer.update()
    return tree, emission


def _object_vector(tree, name):
    node = tree.nodes.new("ShaderNodeAttribute")
    node.attribute_type = "OBJECT"
    node.attribute_name = name
    return node.outputs["Vector"]


def _separate(tree, vector):
    node = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(vector, node.inputs[0])
    return node.outputs


def _lookup(tmp_path, mean_min, mean_max, sigma_max, width=256, height=64):
    """The lookup image and a function giving, at given (mean, σ), the
    bilinear error of its table (read as a texture: texel centres, clamped
    edges) against the exact filtered map: the error the group cannot avoid."""
    core = native.require()
    table = core.colormap.lut_knots(_KNOTS, _MAP, "linear", width, height, sigma_max, mean_min, mean_max)
    spec = {"width": width, "height": height, "sigma_max": sigma_max, "mean_min": mean_min, "mean_max": mean_max,
            "sigma_spacing": "linear"}
    image = node_groups.table_image("probe lookup", table, str(tmp_path))

    def bilinear_error(means, sigmas):
        x = np.clip((means - mean_min) / (mean_max - mean_min) * (width - 1), 0, width - 1)
        y = np.clip(sigmas / sigma_max * (height - 1), 0, height - 1)
        x0 = np.minimum(np.floor(x).astype(int), width - 2)
        y0 = np.minimum(np.floor(y).astype(int), height - 2)
        fx, fy = (x - x0)[:, None], (y - y0)[:, None]
        value = ((table[y0, x0] * (1 - fx) + table[y0, x0 + 1] * fx) * (1 - fy)
                 + (table[y0 + 1, x0] * (1 - fx) + table[y0 + 1, x0 + 1] * fx) * fy)
        return np.abs(value - core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)).max(axis=1)
    return image, spec, bilinear_error


def _table_interp(values_at, x):
    """Linear interpolation of a 256-entry table over u = x/(1+x) (the
    microsurface image's layout: node i at u = i/255, the last at 1 − 1/1024)."""
    u = np.arange(node_groups.MICROSURFACE_TABLE_SIZE) / (node_groups.MICROSURFACE_TABLE_SIZE - 1)
    u[-1] = 1.0 - 1.0 / (4 * node_groups.MICROSURFACE_TABLE_SIZE)
    nodes = np.array([values_at(v / (1.0 - v)) for v in u])
    x = np.asarray(x, float)
    return np.array([np.interp(xi / (1.0 + xi) if np.isfinite(xi) else 1.0, u, nodes[:, c])
                     for xi in x for c in range(nodes.shape[1])]).reshape(len(x), -1)


def _render_pixels(scene, path):
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return native.require().image.read(path)[..., :3].astype(np.float64).reshape(-1, 3)


def _random_normals(rng, count, min_deg, max_deg):
    theta = np.radians(rng.uniform(min_deg, max_deg, count))
    phi = rng.uniform(0.0, 2 * np.pi, count)
    return np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]), theta


def _tangent_frame(normal):
    from mathutils import Vector
    rotation = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(normal)).to_matrix()
    return np.array(rotation.col[0]), np.array(rotation.col[1]), np.array(rotation.col[2])


def test_height_filtered_ramp_renders_the_effective_height_distribution(addon, tmp_path):
    """Penumbra Height Filtered Ramp in Cycles against the core: per pixel,
    Λ_o, Λ_i = smith_lambda(θ, σ_s), (μ_d, σ_d) = effective_height(Λ_o + Λ_i,
    'exact'), Color = the exact filtered map at (mean + μ_d σ_h, σ_d σ_h)
    (colormap.filtered) and Visibility = average_visibility(Λ_o, Λ_i)."""
    core = native.require()
    rng = np.random.default_rng(11)
    count = GRID * GRID
    normals, theta_o = _random_normals(rng, count, 40.0, 86.0)
    theta_o[:4] = 0.0
    normals[:4] = (0.0, 0.0, 1.0)
    # Light: random polar angle from each plane's normal (0 for some, the view for others).
    lights = np.empty((count, 3))
    theta_i = np.radians(rng.uniform(0.0, 85.0, count))
    theta_i[4:10] = 0.0
    for k in range(count):
        t1, t2, n = _tangent_frame(normals[k])
        psi = rng.uniform(0, 2 * np.pi)
        lights[k] = 2.5 * (np.sin(theta_i[k]) * (np.cos(psi) * t1 + np.sin(psi) * t2) + np.cos(theta_i[k]) * n)
    lights[10:16] = (0.0, 0.0, 3.0)  # the light at the viewer
    theta_i[10:16] = theta_o[10:16]
    height_mean = rng.uniform(0.25, 0.55, count)
    height_sigma = rng.uniform(0.05, 0.3, count)
    slope_sigma = rng.uniform(0.15, 1.0, count)
    props = [{"inputs": (height_mean[k], height_sigma[k], slope_sigma[k]), "light": lights[k]} for k in range(count)]
    tree, emission = _pixel_planes(addon, normals, props)
    image, spec, bilinear_error = _lookup(tmp_path, -0.25, 1.75, 0.4)
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = node_groups.height_ramp_group(image, spec)
    inputs = _separate(tree, _object_vector(tree, "inputs"))
    for index, name in enumerate(("Height Mean", "Height Sigma", "Slope Sigma")):
        tree.links.new(inputs[index], group.inputs[name])
    tree.links.new(_object_vector(tree, "light"), group.inputs["Light Direction"])
    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    color = _render_pixels(addon, str(tmp_path / "height.exr"))
    # Visibility, with the plane's location as a check of the pixel layout.
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    location = _separate(tree, tree.nodes.new("ShaderNodeObjectInfo").outputs["Location"])
    tree.links.new(group.outputs["Visibility"], combine.inputs[0])
    tree.links.new(location[0], combine.inputs[1])
    tree.links.new(location[1], combine.inputs[2])
    tree.links.new(combine.outputs[0], emission.inputs["Color"])
    visibility = _render_pixels(addon, str(tmp_path / "visibility.exr"))
    rows, cols = np.divmod(np.arange(count), GRID)
    np.testing.assert_allclose(visibility[:, 1:], np.column_stack([cols - GRID / 2 + 0.5, GRID / 2 - rows - 0.5]),
                               atol=1e-5)

    lam_o = np.array([core.colormap.smith_lambda(t, s) for t, s in zip(theta_o, slope_sigma)])
    lam_i = np.array([core.colormap.smith_lambda(t, s) for t, s in zip(theta_i, slope_sigma)])

    def filtering(lam_view, lam_light, shift=True):
        stats = np.array([core.colormap.effective_height(lo + li, "exact") for lo, li in zip(lam_view, lam_light)])
        return height_mean + (stats[:, 0] * height_sigma if shift else 0.0), stats[:, 1] * height_sigma

    means, sigmas = filtering(lam_o, lam_i)
    truth = core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)
    # Tolerance per pixel: the lookup's bilinear error at (mean, σ), plus what
    # linear interpolation of the 256-entry microsurface tables of Λ/(1+Λ)
    # and (μ_d, σ_d) changes (the tables' values from the core at their
    # nodes), plus float32.
    def lam_table(a):
        lam = core.colormap.smith_lambda_of_a(a) if a > 0 else np.inf
        return (1.0 if np.isinf(lam) else lam / (1.0 + lam),)

    def lam_from_table(theta):
        cot = np.cos(theta) / np.maximum(np.sin(theta), 1e-6)
        g = _table_interp(lam_table, cot / slope_sigma)[:, 0]
        return g / np.maximum(1.0 - g, 1e-6)

    lam_sum = lam_from_table(theta_o) + lam_from_table(theta_i)
    stats = _table_interp(lambda x: core.colormap.effective_height(x, "exact"), lam_sum)
    tabled = core.colormap.filtered(_KNOTS, _MAP, "linear", height_mean + stats[:, 0] * height_sigma,
                                    stats[:, 1] * height_sigma)
    tolerance = bilinear_error(means, sigmas) + np.abs(tabled - truth).max(axis=1) + 2e-4
    error = np.abs(color - truth).max(axis=1)
    print(f"height group: max error {error.max():.2e}, max error/tolerance {(error / tolerance).max():.2f}, "
          f"median tolerance {np.median(tolerance):.1e}")
    assert (error < tolerance).all(), (error.max(), int(np.argmax(error / tolerance)))
    np.testing.assert_allclose(visibility[:, 0],
                               [core.colormap.average_visibility(lo, li) for lo, li in zip(lam_o, lam_i)], atol=2e-3)
    # The test can fail: ignoring the view angle or the shift of the height
    # distribution moves many pixels far outside the tolerance.
    for wrong in (filtering(np.zeros(count), lam_i), filtering(lam_o, lam_i, shift=False)):
        off = np.abs(color - core.colormap.filtered(_KNOTS, _MAP, "linear", *wrong)).max(axis=1)
        assert (off > 5 * tolerance).sum() > count // 3, (off / tolerance)


def test_slope_filtered_ramp_renders_the_visible_slope_distribution(addon, tmp_path):
    """Penumbra Slope Filtered Ramp in Cycles against the core's brute-force
    slope filtering distribution: per pixel, slope_filtering(θ_o, φ_o, 0,
    σ_s² I, 'numerical') in the plane's tangent frame, v = v0 + k s·D (D the
    Direction input projected onto the plane), Color = the exact filtered map
    at (v0 + k mean·D, |k| √(Dᵀ Cov D))."""
    core = native.require()
    rng = np.random.default_rng(5)
    count = GRID * GRID
    normals, theta_o = _random_normals(rng, count, 0.0, 86.0)
    theta_o[:4] = 0.0
    normals[:4] = (0.0, 0.0, 1.0)
    directions = rng.normal(size=(count, 3))  # world vectors, not in the plane
    slope_sigma = rng.uniform(0.15, 0.8, count)
    per_slope = rng.uniform(0.15, 0.35, count) / slope_sigma * rng.choice([-1.0, 1.0], count)
    at_zero = rng.uniform(0.3, 0.7, count)
    props = [{"inputs": (at_zero[k], per_slope[k], slope_sigma[k]), "direction": directions[k]} for k in range(count)]
    tree, emission = _pixel_planes(addon, normals, props)
    image, spec, bilinear_error = _lookup(tmp_path, -0.5, 1.5, 0.4)
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = node_groups.slope_ramp_group(image, spec)
    inputs = _separate(tree, _object_vector(tree, "inputs"))
    for index, name in enumerate(("Value at Zero Slope", "Value per Slope", "Slope Sigma")):
        tree.links.new(inputs[index], group.inputs[name])
    tree.links.new(_object_vector(tree, "direction"), group.inputs["Direction"])
    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    color = _render_pixels(addon, str(tmp_path / "slope.exr"))

    def expected(view=True):
        means, sigmas = np.empty(count), np.empty(count)
        for k in range(count):
            t1, t2, n = _tangent_frame(normals[k])
            d = np.array([directions[k] @ t1, directions[k] @ t2])
            d /= np.linalg.norm(d)
            eye = np.array([0.0, 0.0, 1.0])
            theta = np.arccos(np.clip(eye @ n, -1, 1)) if view else 0.0
            phi = np.arctan2(eye @ t2, eye @ t1)
            var = slope_sigma[k] ** 2
            mean, cov = core.colormap.slope_filtering(theta, phi, (0.0, 0.0), (var, 0.0, var), "numerical", 401)
            means[k] = at_zero[k] + per_slope[k] * (np.array(mean) @ d)
            c = np.array([[cov[0], cov[1]], [cov[1], cov[2]]])
            sigmas[k] = abs(per_slope[k]) * np.sqrt(d @ c @ d)
        return means, sigmas

    means, sigmas = expected()
    truth = core.colormap.filtered(_KNOTS, _MAP, "linear", means, sigmas)
    # Tolerance per pixel: the lookup's bilinear error at (mean, σ), plus what
    # linear interpolation of the 256-entry table of (E[z], sd[z]) changes
    # (and the brute force's own error), plus float32.
    cot = np.cos(theta_o) / np.maximum(np.sin(theta_o), 1e-6)
    shift = _table_interp(lambda c: core.colormap.slope_shift(c), cot / slope_sigma)
    cos_psi = np.empty(count)
    for k in range(count):
        t1, t2, n = _tangent_frame(normals[k])
        d = np.array([directions[k] @ t1, directions[k] @ t2])
        view = np.array([t1[2], t2[2]])  # the eye (+Z) in the plane's frame
        cos_psi[k] = d @ view / np.linalg.norm(d) / max(np.linalg.norm(view), 1e-12)
    k_sigma = per_slope * slope_sigma
    tabled = core.colormap.filtered(
        _KNOTS, _MAP, "linear", at_zero + k_sigma * shift[:, 0] * cos_psi,
        np.abs(k_sigma) * np.sqrt(np.maximum(1.0 - (1.0 - shift[:, 1] ** 2) * cos_psi ** 2, 0.0)))
    tolerance = bilinear_error(means, sigmas) + np.abs(tabled - truth).max(axis=1) + 2e-4
    error = np.abs(color - truth).max(axis=1)
    print(f"slope group: max error {error.max():.2e}, max error/tolerance {(error / tolerance).max():.2f}, "
          f"median tolerance {np.median(tolerance):.1e}")
    assert (error < tolerance).all(), (error.max(), int(np.argmax(error / tolerance)))
    # The test can fail: ignoring the view (the slopes' unshifted
    # distribution) moves many pixels far outside the tolerance.
    off = np.abs(color - core.colormap.filtered(_KNOTS, _MAP, "linear", *expected(view=False))).max(axis=1)
    assert (off > 5 * tolerance).sum() > count // 3, (off / tolerance)
