"""penumbra.add_surface_filter / remove_surface_filter inside real Blender:
the height and slope groups put in place of a baked Penumbra Filtered Ramp
(wiring, lookup, directions), tiny Cycles renders of what they give, re-runs,
refusals that change nothing, undo and the failure rollback."""

import math
import os

import bpy
import numpy as np
import pytest

from penumbra import native
from penumbra.colormap import node_groups, surface_filter

from colormap_scenes import make_ramp_material, plane_with

HEIGHT_NODE, SLOPE_NODE = surface_filter.FILTERS["HEIGHT"][0], surface_filter.FILTERS["SLOPE"][0]
RENDER_SIZE = 16


def bake(scene, tmp_path, name="filtered", emission=False, noise=True):
    """A ramp (driven by a one-octave Noise Texture, or undriven) on a 4 × 4
    plane, seen by an orthographic camera straight down (the view is the
    plane's normal), baked. With `emission` the material emits the ramp's
    colour (no lighting in the way). One octave keeps the noise filter small
    (building it is most of a bake's time)."""
    settings = scene.penumbra.colormap
    settings.output_folder = str(tmp_path)
    settings.lut_width, settings.lut_height = 64, 32
    material, ramp = make_ramp_material(name, noise=noise)
    tree = material.node_tree
    if noise:
        ramp.inputs["Fac"].links[0].from_node.inputs["Detail"].default_value = 0.0
    if emission:
        emit = tree.nodes.new("ShaderNodeEmission")
        tree.links.new(ramp.outputs["Color"], emit.inputs["Color"])
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
        tree.links.new(emit.outputs[0], output.inputs["Surface"])
    obj = plane_with(material)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 4.0
    camera.location = (0.0, 0.0, 5.0)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = scene.render.resolution_y = RENDER_SIZE
    scene.render.resolution_percentage = 100
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    return material, tree.nodes[node_groups.FILTERED_RAMP]


def snapshot(tree):
    """Everything a refused operator must leave as it was."""
    nodes = sorted((n.name, n.mute, n.label, tuple(round(v, 3) for v in n.location)) for n in tree.nodes)
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    return nodes, links, len(bpy.data.node_groups), len(bpy.data.images)


def add_sun(rotation=(0.6, 0.0, 0.8)):
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    bpy.context.scene.collection.objects.link(sun)
    sun.rotation_euler = rotation
    bpy.context.view_layer.update()
    return sun


def sun_towards(sun):
    """Independent of the operator: the sun shines along its local −Z."""
    from mathutils import Vector
    shine = sun.matrix_world.to_3x3() @ Vector((0.0, 0.0, -1.0))
    return -np.array(shine.normalized())


@pytest.mark.parametrize("kind", ["HEIGHT", "SLOPE"])
def test_filter_replaces_the_baked_ramp_on_the_same_lookup(addon, tmp_path, kind):
    material, ramp = bake(addon, tmp_path)
    tree = material.node_tree
    sun = add_sun()
    noise_filter = ramp.inputs["Mean"].links[0].from_node
    fed = [(l.to_node.name, l.to_socket.identifier) for l in ramp.outputs["Color"].links]
    assert fed  # the Principled BSDF's Base Color
    assert bpy.ops.penumbra.add_surface_filter(kind=kind, slope_sigma=0.35, value_per_slope=-0.7) == {"FINISHED"}
    node = tree.nodes[HEIGHT_NODE if kind == "HEIGHT" else SLOPE_NODE]
    group = node.node_tree
    assert group.name.startswith(node_groups.HEIGHT_RAMP if kind == "HEIGHT" else node_groups.SLOPE_RAMP)
    # The same lookup image and layout as the filtered ramp.
    samplers = [n.image for n in group.nodes if n.bl_idname == "ShaderNodeTexImage"]
    lookup = next(n.image for n in ramp.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
    assert lookup in samplers
    assert group["penumbra_lookup"].to_dict() == ramp.node_tree["penumbra_lookup"].to_dict()
    # The microsurface table the group reads sits beside the lookup (saved
    # with the project), not in the session's temporary folder.
    table = bpy.data.images[node_groups.MICROSURFACE_IMAGE]
    assert table in samplers
    assert os.path.dirname(bpy.path.abspath(table.filepath)) == os.path.dirname(bpy.path.abspath(lookup.filepath))
    # Inputs from what fed the filtered ramp, outputs to what it fed.
    mean_input = "Height Mean" if kind == "HEIGHT" else "Value at Zero Slope"
    assert node.inputs[mean_input].links[0].from_socket == noise_filter.outputs["Mean"]
    if kind == "HEIGHT":
        assert node.inputs["Height Sigma"].links[0].from_socket == noise_filter.outputs["Sigma"]
        assert not node.outputs["Visibility"].is_linked
    else:
        assert node.inputs["Value per Slope"].default_value == pytest.approx(-0.7)
    assert node.inputs["Slope Sigma"].default_value == pytest.approx(0.35)
    assert [(l.to_node.name, l.to_socket.identifier) for l in node.outputs["Color"].links] == fed
    assert not ramp.outputs["Color"].is_linked and not ramp.outputs["Alpha"].is_linked
    # The filtered ramp stays, muted and labelled, still fed by the noise filter.
    assert ramp.mute and "muted" in ramp.label
    assert ramp.inputs["Sigma"].links[0].from_node == noise_filter
    assert tree.nodes.active == node
    # Direction: towards the sun (+Z of its matrix, the opposite of where it shines).
    direction = node.inputs["Light Direction" if kind == "HEIGHT" else "Direction"]
    assert not direction.is_linked
    np.testing.assert_allclose(direction.default_value, sun_towards(sun), atol=1e-6)


def test_without_a_sun_height_looks_up_and_slope_follows_the_view(addon, tmp_path):
    material, ramp = bake(addon, tmp_path, noise=False)
    tree = material.node_tree
    hidden = add_sun()
    hidden.hide_render = True  # not a light of the render: ignored
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"FINISHED"}
    assert tuple(tree.nodes[HEIGHT_NODE].inputs["Light Direction"].default_value) == (0.0, 0.0, 1.0)
    assert bpy.ops.penumbra.add_surface_filter(kind="SLOPE") == {"FINISHED"}
    link = tree.nodes[SLOPE_NODE].inputs["Direction"].links[0]
    assert link.from_node.bl_idname == "ShaderNodeNewGeometry" and link.from_socket.identifier == "Incoming"
    # Removing the filter takes its Geometry node along.
    assert bpy.ops.penumbra.remove_surface_filter() == {"FINISHED"}
    assert not [n for n in tree.nodes if n.bl_idname == "ShaderNodeNewGeometry"]


def _render(scene, path):
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.device = "CPU"
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return native.require().image.read(str(path))[..., :3].astype(np.float64)


def _probe(tree, ramp, mean_shift, sigma_scale=None, sigma=None, added_sigma=None):
    """A second node of the filtered ramp's own group at (Mean + mean_shift ·
    Sigma, sigma_scale · Sigma) (or the constant `sigma`, or √(added_sigma² +
    Sigma²)), its Color into the emission."""
    mean, ramp_sigma = ramp.inputs["Mean"].links[0].from_socket, ramp.inputs["Sigma"].links[0].from_socket
    probe = tree.nodes.new("ShaderNodeGroup")
    probe.node_tree = ramp.node_tree
    shifted = tree.nodes.new("ShaderNodeMath")
    shifted.operation = "MULTIPLY_ADD"
    tree.links.new(ramp_sigma, shifted.inputs[0])
    shifted.inputs[1].default_value = mean_shift
    tree.links.new(mean, shifted.inputs[2])
    tree.links.new(shifted.outputs[0], probe.inputs["Mean"])
    if added_sigma is not None:
        square = tree.nodes.new("ShaderNodeMath")
        square.operation = "MULTIPLY_ADD"
        tree.links.new(ramp_sigma, square.inputs[0])
        tree.links.new(ramp_sigma, square.inputs[1])
        square.inputs[2].default_value = added_sigma * added_sigma
        root = tree.nodes.new("ShaderNodeMath")
        root.operation = "SQRT"
        tree.links.new(square.outputs[0], root.inputs[0])
        tree.links.new(root.outputs[0], probe.inputs["Sigma"])
    elif sigma is None:
        scaled = tree.nodes.new("ShaderNodeMath")
        scaled.operation = "MULTIPLY"
        tree.links.new(ramp_sigma, scaled.inputs[0])
        scaled.inputs[1].default_value = sigma_scale
        tree.links.new(scaled.outputs[0], probe.inputs["Sigma"])
    else:
        probe.inputs["Sigma"].default_value = sigma
    emission = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeEmission")
    tree.links.new(probe.outputs["Color"], emission.inputs["Color"])


def test_height_filter_renders_the_filtered_ramp_without_slopes_and_the_shifted_heights_at_grazing_light(
        addon, tmp_path):
    """Sec. 5.1 with σ_s = 0: Λ_o = Λ_i = 0, (μ_d, σ_d) = (0, 1): the height
    group is the plain filtered lookup at (Mean, Sigma) (one Gaussian). With σ_s = 1 and the
    light 80° from the normal (the view is the normal, Λ_o = 0): the filtered
    ramp at (Mean + μ_d Sigma, σ_d Sigma), (μ_d, σ_d) = the core's exact
    effective height at Λ_i = smith_lambda(80°, 1)."""
    core = native.require()
    material, ramp = bake(addon, tmp_path, emission=True)
    tree = material.node_tree
    # The surface filters read the Noise Filter's one Gaussian (Mean, Sigma),
    # not the mixture the baked ramp averages over: compare with the ramp fed that.
    for name in ("Offsets", "Variances"):
        tree.links.remove(ramp.inputs[name].links[0])
    plain = _render(addon, tmp_path / "filtered.exr")
    grazing = math.radians(80.0)
    light = (math.sin(grazing), 0.0, math.cos(grazing))
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT", slope_sigma=0.0, direction_source="CUSTOM",
                                               direction=light) == {"FINISHED"}
    flat = _render(addon, tmp_path / "flat.exr")
    print(f"height filter at slope sigma 0: max difference from the filtered ramp {np.abs(flat - plain).max():.1e}")
    assert np.abs(flat - plain).max() < 1e-5
    assert bpy.ops.penumbra.remove_surface_filter() == {"FINISHED"}
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT", slope_sigma=1.0, direction_source="CUSTOM",
                                               direction=light) == {"FINISHED"}
    rough = _render(addon, tmp_path / "rough.exr")
    mu_d, sigma_d = core.colormap.effective_height(core.colormap.smith_lambda(grazing, 1.0), "exact")
    assert mu_d > 0.3  # the lit and seen heights are the upper ones
    _probe(tree, ramp, mu_d, sigma_d)
    expected = _render(addon, tmp_path / "expected.exr")
    error = np.abs(rough - expected).max()
    change = np.abs(rough - plain).max(axis=2)
    print(f"height filter render: max error {error:.2e}, mean change from the plain lookup {change.mean():.3f}")
    assert error < 2e-4  # measured 5e-6: float32 and the microsurface table's interpolation
    assert (change > 0.02).mean() > 0.25  # the shift shows on a quarter of the pixels or more


def test_slope_filter_renders_the_ramp_at_the_slope_spread(addon, tmp_path):
    """Sec. 5.2 seen straight down (cot θ_o = ∞: E[z] = 0, sd[z] = 1): the
    value is N(Mean, (k σ_s)² + Sigma²), whatever the direction: the slopes'
    spread plus the noise's own over the pixel (the Noise Filter's Sigma)."""
    material, ramp = bake(addon, tmp_path, emission=True)
    tree = material.node_tree
    plain = _render(addon, tmp_path / "filtered.exr")
    assert bpy.ops.penumbra.add_surface_filter(kind="SLOPE", slope_sigma=0.25, value_per_slope=0.4) == {"FINISHED"}
    slope = _render(addon, tmp_path / "slope.exr")
    _probe(tree, ramp, 0.0, sigma=0.4 * 0.25)
    slopes_only = _render(addon, tmp_path / "slopes_only.exr")
    _probe(tree, ramp, 0.0, added_sigma=0.4 * 0.25)
    expected = _render(addon, tmp_path / "expected.exr")
    print(f"slope filter render: max error {np.abs(slope - expected).max():.1e}, "
          f"{np.abs(slope - slopes_only).max():.1e} from the slopes' spread alone")
    assert np.abs(slope - expected).max() < 2e-4
    assert np.abs(slope - slopes_only).max() > 10 * np.abs(slope - expected).max()  # the noise's σ counts
    assert np.abs(slope - plain).max() > 0.05  # the slope spread is not the footprint's


def test_running_again_keeps_one_filter_and_the_other_kind_replaces_it(addon, tmp_path):
    material, ramp = bake(addon, tmp_path, noise=False)
    tree = material.node_tree
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"FINISHED"}
    height = tree.nodes[HEIGHT_NODE]
    before = snapshot(tree)
    # The same kind again: reported, nothing changed (from the filter or from the muted ramp).
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"CANCELLED"}
    tree.nodes.active = ramp
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"CANCELLED"}
    assert snapshot(tree) == before
    # The other kind takes the height filter's place and links.
    fed = [(l.to_node.name, l.to_socket.identifier) for l in height.outputs["Color"].links]
    assert bpy.ops.penumbra.add_surface_filter(kind="SLOPE") == {"FINISHED"}
    assert HEIGHT_NODE not in tree.nodes
    slope = tree.nodes[SLOPE_NODE]
    assert [(l.to_node.name, l.to_socket.identifier) for l in slope.outputs["Color"].links] == fed
    assert len(surface_filter.filters_of(tree, ramp)) == 1 and ramp.mute


def test_remove_puts_the_filtered_ramp_back_as_it_was(addon, tmp_path):
    material, ramp = bake(addon, tmp_path, noise=False)
    tree = material.node_tree
    before = snapshot(tree)[:2]
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"FINISHED"}
    assert snapshot(tree)[:2] != before
    tree.nodes.active = ramp  # the muted ramp finds its filter too
    assert bpy.ops.penumbra.remove_surface_filter() == {"FINISHED"}
    assert snapshot(tree)[:2] == before
    with pytest.raises(RuntimeError, match="no Penumbra height or slope filter"):
        bpy.ops.penumbra.remove_surface_filter()


@pytest.mark.parametrize("problem", ["no_material", "not_baked", "image_removed", "image_file_missing",
                                     "two_ramps_none_active", "zero_direction"])
def test_problems_are_reported_and_nothing_changes(addon, tmp_path, problem):
    if problem == "not_baked":
        material, ramp = make_ramp_material()
        plane_with(material)
    else:
        material, ramp = bake(addon, tmp_path, noise=False)
    tree = material.node_tree
    arguments = {"kind": "HEIGHT"}
    expected = {"no_material": "No active material", "not_baked": "has no baked Penumbra Filtered Ramp",
                "image_removed": "was removed", "image_file_missing": "is missing",
                "two_ramps_none_active": "none is active", "zero_direction": "direction is zero"}[problem]
    if problem == "no_material":
        bpy.context.active_object.data.materials.clear()
    elif problem == "image_removed":
        bpy.data.images.remove(next(n.image for n in ramp.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage"))
    elif problem == "image_file_missing":
        image = next(n.image for n in ramp.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
        os.remove(bpy.path.abspath(image.filepath))
        image.reload()
    elif problem == "two_ramps_none_active":
        copy = tree.nodes.new("ShaderNodeGroup")
        copy.node_tree = ramp.node_tree
        tree.nodes.active = tree.nodes["Principled BSDF"]
    elif problem == "zero_direction":
        arguments.update(direction_source="CUSTOM", direction=(0.0, 0.0, 0.0))
    before = snapshot(tree)
    with pytest.raises(RuntimeError, match=expected):
        bpy.ops.penumbra.add_surface_filter(**arguments)
    assert snapshot(tree) == before


def test_linked_material_is_read_only(addon, tmp_path):
    material, _ = bake(addon, tmp_path, name="shared", noise=False)
    library = str(tmp_path / "library.blend")
    material.use_fake_user = True
    bpy.data.libraries.write(library, {material})
    bpy.data.materials.remove(material)
    with bpy.data.libraries.load(library, link=True) as (data_from, data_to):
        data_to.materials = ["shared"]
    linked = next(m for m in bpy.data.materials if m.library is not None)
    obj = bpy.context.active_object
    obj.material_slots[0].link = "OBJECT"
    obj.material_slots[0].material = linked
    before = snapshot(linked.node_tree)
    with pytest.raises(RuntimeError, match="read-only"):
        bpy.ops.penumbra.add_surface_filter(kind="SLOPE")
    assert snapshot(linked.node_tree) == before


def test_undo_restores_the_tree_and_redo_brings_the_filter_back(addon, tmp_path):
    material, _ = bake(addon, tmp_path, name="undoable", noise=False)
    before = snapshot(material.node_tree)[:2]
    bpy.ops.ed.undo_push(message="before surface filter")
    # undo=True: push an undo step as a click in the UI does (bl_options UNDO).
    assert bpy.ops.penumbra.add_surface_filter("EXEC_DEFAULT", True, kind="HEIGHT") == {"FINISHED"}
    after = snapshot(bpy.data.materials["undoable"].node_tree)[:2]
    assert after != before
    # Undo restores data blocks from memory: look everything up again by name.
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert snapshot(bpy.data.materials["undoable"].node_tree)[:2] == before
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert snapshot(bpy.data.materials["undoable"].node_tree)[:2] == after


def test_failure_half_way_puts_everything_back(addon, tmp_path, monkeypatch):
    material, ramp = bake(addon, tmp_path, noise=False)
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"FINISHED"}
    tree = material.node_tree
    before = snapshot(tree)

    def fail(*args, **kwargs):
        raise RuntimeError("simulated failure after the group node and its Geometry node were added")

    # The slope filter replacing the height filter fails after its group, its
    # node and its Geometry node exist: all go, the height filter stays.
    monkeypatch.setattr(surface_filter, "_move_output_links", fail)
    with pytest.raises(RuntimeError, match="simulated failure"):
        bpy.ops.penumbra.add_surface_filter(kind="SLOPE", direction_source="VIEW")
    assert snapshot(tree) == before


def test_panel_buttons_wait_for_a_baked_ramp(addon, tmp_path):
    material, ramp = make_ramp_material()
    plane_with(material)
    assert surface_filter.panel_state(bpy.context) == (False, False, False)
    material, ramp = bake(addon, tmp_path, noise=False)
    assert surface_filter.panel_state(bpy.context) == (True, False, False)
    assert bpy.ops.penumbra.add_surface_filter(kind="SLOPE") == {"FINISHED"}
    assert surface_filter.panel_state(bpy.context) == (True, True, False)
    # Restore ColorRamp on the ramp under the filter would strand the filter: greyed out.
    material.node_tree.nodes.active = ramp
    assert surface_filter.panel_state(bpy.context) == (True, True, True)


def test_restore_under_a_surface_filter_is_refused_and_changes_nothing(addon, tmp_path):
    """Restore ColorRamp on a filtered ramp that a surface filter replaced
    would unlink the filter's inputs: the panel greys it out, and a script
    calling it gets a clear error instead."""
    material, ramp = bake(addon, tmp_path, noise=False)
    assert bpy.ops.penumbra.add_surface_filter(kind="HEIGHT") == {"FINISHED"}
    tree = material.node_tree
    tree.nodes.active = ramp
    before = snapshot(tree)
    with pytest.raises(RuntimeError, match="remove the filter first"):
        bpy.ops.penumbra.restore_color_ramp()
    assert snapshot(tree) == before
    assert bpy.ops.penumbra.remove_surface_filter() == {"FINISHED"}
    tree.nodes.active = ramp
    assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
