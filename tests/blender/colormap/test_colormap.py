"""The colour-map tool inside real Blender: ColorRamp evaluation against
Blender's own, the bake operator end to end (undo, failures, bad input, an
image as the map), and the node groups in this Blender's node-group API."""

import os
import shutil

import bpy
import numpy as np
import pytest

from penumbra import compat, native

from penumbra.colormap import filtered_ramp, height_ramp, interface, node_groups, noise_maths, slope_ramp

from colormap_scenes import make_ramp_material, plane_with

INTERPOLATIONS = ("LINEAR", "EASE", "CARDINAL", "B_SPLINE", "CONSTANT")
COLOR_MODES = ("RGB", "HSV", "HSL")
HUES = ("NEAR", "FAR", "CW", "CCW")


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
    addon.penumbra.colormap.filter_quality = "TAPS_16_MIXTURE"   # the 16 taps' mixture at every sample count
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
    # Noise-driven: the ramp reads the Noise Filter's four-Gaussian mixture.
    assert interface.socket_names(group_node.node_tree, "INPUT") == ["Mean", "Sigma", "Offsets", "Variances"]
    assert interface.socket_names(group_node.node_tree, "OUTPUT") == ["Color", "Alpha"]
    bsdf = tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Base Color"].links[0].from_node == group_node
    assert ramp.mute and ramp.name in tree.nodes
    noise_filter = group_node.inputs["Sigma"].links[0].from_node
    assert noise_filter.node_tree.name.startswith("Penumbra Noise Filter")
    for name in ("Mean", "Offsets", "Variances"):
        assert group_node.inputs[name].links[0].from_socket == noise_filter.outputs[name]
    assert noise_filter.node_tree["penumbra_taps"] == noise_maths.TAP_COUNT   # Cycles: every tap
    # The noise's (unlinked, so Generated) coordinates and its Scale feed the octave filter.
    coords = noise_filter.inputs["Vector"].links[0].from_node
    assert coords.bl_idname == "ShaderNodeTexCoord" and noise_filter.inputs["Vector"].links[0].from_socket.name == "Generated"
    assert noise_filter.inputs["Scale"].default_value == pytest.approx(20.0)
    assert noise_filter.inputs["Units per World"].default_value == pytest.approx(0.25)  # 4 × 4 plane
    footprint = noise_filter.inputs["Minor"].links[0].from_node
    assert noise_filter.inputs["Major"].links[0].from_node == footprint
    assert footprint.inputs["Pixel Size"].default_value > 0
    weights = noise_filter.node_tree["penumbra_octave_coefficients"]
    assert len(weights) == 3 and sum(weights) == pytest.approx(1.0)  # Detail 2 (the default): 3 octaves
    # The lookup image: float EXR, no colour transform, no wrap.
    image_node = next(n for n in group_node.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
    assert image_node.extension == "EXTEND" and image_node.interpolation == "Closest"
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
    knots = native.module.colormap.ramp_to_knots(ramp_io.ramp_stops(ramp), "LINEAR", "RGB", "NEAR", sampling="cycles",
                                                 table_size=ramp_io.renderer_table_size(addon))
    expect = native.module.colormap.lut_knots(knots["positions"], knots["colors"], knots["interpolation"], 64, 32,
                                              spec["sigma_max"], spec["mean_min"], spec["mean_max"])
    np.testing.assert_allclose(pixels, expect, atol=1e-6)
    # Restore puts the ramp back.
    tree.nodes.active = group_node
    assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
    assert not ramp.mute and bsdf.inputs["Base Color"].links[0].from_node == ramp
    assert not [n.name for n in tree.nodes if n.name.startswith("Penumbra")]


def test_a_saved_files_lookups_are_stored_relative_and_follow_the_moved_folder(addon, tmp_path):
    """A project folder moved or copied with its lookups keeps them (0.2.0
    stored absolute paths, which broke in the copy)."""
    project = tmp_path / "project"
    project.mkdir()
    bpy.ops.wm.save_as_mainfile(filepath=str(project / "shot.blend"))
    addon.penumbra.colormap.output_folder = "//lookups/"
    addon.penumbra.colormap.lut_width = addon.penumbra.colormap.lut_height = 16
    material, _ = make_ramp_material(name="moved", noise=True)
    plane_with(material)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    lookups = [i for i in bpy.data.images if i.filepath]
    assert len(lookups) >= 2 and all(i.filepath.startswith("//lookups/") for i in lookups), \
        [i.filepath for i in lookups]
    bpy.ops.wm.save_mainfile()
    shutil.move(str(project), str(tmp_path / "moved"))
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "moved" / "shot.blend"))
    for image in (i for i in bpy.data.images if i.filepath):
        assert os.path.exists(bpy.path.abspath(image.filepath)), image.filepath
        assert len(image.pixels) > 0, image.filepath   # loads it: a missing file has none


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

    monkeypatch.setattr(filtered_ramp, "filtered_ramp_group", fail)
    native.require().testing.record_durable_steps()
    try:
        with pytest.raises(RuntimeError, match="simulated failure"):
            bpy.ops.penumbra.bake_colormap_lut()
    finally:
        steps = native.require().testing.recorded_durable_steps()
    assert {name: (tmp_path / name).read_bytes() for name in os.listdir(tmp_path)} == files
    # The earlier lookups were moved aside and back durably: each rename
    # between the moved file's fsync and its folder's.
    moves = []
    for i, step in enumerate(steps):
        if step.startswith("rename "):
            source, target = step[len("rename "):].split(" -> ")
            assert steps[i - 1:i + 2:2] == [f"fsync file {source}", f"fsync folder {os.path.dirname(target)}"], steps
            moves.append((source, target))
    backups = [move for move in moves if move[1].endswith(".penumbra-backup")]
    assert backups and all((b, a) in moves[moves.index((a, b)):] for a, b in backups), moves
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
    (group,) = [g for g in bpy.data.node_groups if g.name.startswith(node_groups.FILTERED_RAMP)]
    assert interface.socket_names(group, "INPUT") == ["Mean", "Sigma"]   # no noise: one Gaussian, one lookup
    assert os.path.isfile(os.path.join(str(tmp_path), "strip_lut.exr"))


def test_microsurface_groups_build_in_this_blenders_api(addon, tmp_path):
    image = bpy.data.images.new("lut", 8, 8, float_buffer=True)
    spec = {"width": 8, "height": 8, "sigma_max": 0.3, "mean_min": 0.0, "mean_max": 1.0, "sigma_spacing": "linear"}
    height = height_ramp.height_ramp_group(image, spec)
    slope = slope_ramp.slope_ramp_group(image, spec)
    assert interface.socket_names(height, "OUTPUT") == ["Color", "Alpha", "Visibility"]
    assert "Slope Sigma" in interface.socket_names(slope, "INPUT")
    table = bpy.data.images[node_groups.MICROSURFACE_IMAGE]
    px = np.empty(256 * 2 * 4, np.float32)
    table.pixels.foreach_get(px)
    px = px.reshape(2, 256, 4)
    # Row 0, G at Λ_sum = 1 (u = 0.5 → texel 127.5): mean of the max of 2 normals, 1/√π.
    assert abs(0.5 * (px[0, 127, 1] + px[0, 128, 1]) - 0.5642) < 0.01
