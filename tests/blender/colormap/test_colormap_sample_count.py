"""The noise filter learns the render's sample count (docs/colormap.md,
"Sample-count-aware filter"): the driver on its Samples input, re-pointed when
the engine changes and removed with the filter, and a Cycles render where more
samples converge instead of blurring twice."""

import bpy
import numpy as np

from penumbra.colormap import node_groups, noise_maths, sample_count

from test_colormap_noise import _baked_plane_and_error, _render, _render_scene


def _noise_filter(material):
    nodes = sample_count.noise_filter_nodes(material)
    assert len(nodes) == 1
    return nodes[0]


def _driver_target(node):
    tree = node.id_data
    curve = tree.animation_data.drivers.find(node.inputs["Samples"].path_from_id("default_value"))
    assert curve is not None and curve.driver.type == "AVERAGE" and not curve.driver.is_simple_expression
    (variable,) = curve.driver.variables
    return variable.targets[0]


def test_samples_driver_follows_the_render_settings_and_engine(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    addon.cycles.samples = 24
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    node = _noise_filter(material)
    target = _driver_target(node)
    assert (target.id, target.data_path) == (addon, "cycles.samples")
    assert node.inputs["Samples"].default_value == 24
    # Another engine: the handler re-points the driver when a render starts.
    addon.render.engine = "BLENDER_EEVEE_NEXT" if bpy.app.version >= (4, 2, 0) and bpy.app.version < (5, 0, 0) \
        else "BLENDER_EEVEE"
    addon.eevee.taa_render_samples = 9
    assert sample_count.retarget(addon) == 1
    assert _driver_target(node).data_path == "eevee.taa_render_samples"
    assert sample_count.retarget(addon) == 0          # already right: nothing changes
    addon.render.engine = "CYCLES"
    addon.render.resolution_x, addon.render.resolution_y = 8, 6
    _render(addon, str(tmp_path / "tiny.exr"), 2, 0)  # render_init re-points it back
    assert _driver_target(node).data_path == "cycles.samples"


def test_restore_removes_the_samples_driver(addon, tmp_path):
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    tree = material.node_tree
    assert len(tree.animation_data.drivers) == 1
    tree.nodes.active = tree.nodes[node_groups.FILTERED_RAMP]
    assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
    assert len(tree.animation_data.drivers) == 0


def test_more_samples_converge_where_the_pixel_centred_filter_does_not(addon, tmp_path):
    """48×32 Cycles renders of the receding plane against the plain ramp at
    1024 spp: with the sample count driven, the filtered material at 64 spp
    is no worse than the plain ramp at 64 spp and at 4 spp well below the
    plain ramp's error; held at one sample (the pixel-centred filter of a
    1-spp render), it stays far from the reference at 64 spp."""
    # Baked at one sample: only the driver can tell it 4 or 64.
    plane = _baked_plane_and_error(addon, tmp_path, 84.0, baked_samples=1)
    material, group, emission, rmse = plane.material, plane.group, plane.emission, plane.rmse
    plain = {spp: rmse(_render(addon, str(tmp_path / f"plain{spp}.exr"), spp, 1)) for spp in (4, 64)}
    material.node_tree.links.new(group.outputs["Color"], emission.inputs["Color"])
    filtered = {spp: rmse(_render(addon, str(tmp_path / f"filtered{spp}.exr"), spp, 1)) for spp in (4, 64)}
    assert filtered[4] < 0.8 * plain[4], (filtered, plain)
    assert filtered[64] < 1.1 * plain[64], (filtered, plain)
    # The same material told it renders one sample: the old, fixed filter.
    node = _noise_filter(material)
    sample_count.unregister()
    try:
        sample_count.remove_driver(node)
        node.inputs["Samples"].default_value = 1.0
        fixed = rmse(_render(addon, str(tmp_path / "fixed64.exr"), 64, 1))
    finally:
        sample_count.register()
    assert fixed > 2.0 * filtered[64], (fixed, filtered)


def test_high_detail_with_distortion_fits_cycles_shader_stack(addon, tmp_path):
    """Noise at Detail 8 (9 octaves) with Distortion 2: 16 taps × (9 + 3)
    Noise evaluations and 9 octave-table lookups. Evaluated level by level,
    they overflowed Cycles' 255-float SVM stack and the material rendered
    black (from Detail 8, or Detail 4 with Distortion); each tap and lookup
    is now chained after the previous one (Detail 15 with Distortion 2 was
    checked by hand: its bake takes 2 min, too long here). The filtered
    render must look like the plain ramp's (mean colour within 0.05, not black)."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    addon.render.resolution_x, addon.render.resolution_y = 16, 12
    noise = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    noise.inputs["Detail"].default_value = 8.0
    noise.inputs["Distortion"].default_value = 2.0
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    assert len(_noise_filter(material).node_tree["penumbra_octave_coefficients"]) == 9
    filtered = _render(addon, str(tmp_path / "filtered.exr"), 1, 0)
    tree = material.node_tree
    ramp.mute = False
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    plain = _render(addon, str(tmp_path / "plain.exr"), 16, 0)
    ground = plain.sum(axis=2) > 0
    assert ground.mean() > 0.3
    np.testing.assert_allclose(filtered[ground].mean(axis=0), plain[ground].mean(axis=0), atol=0.05)


def test_eevee_gets_a_noise_filter_it_can_compile(addon, tmp_path):
    """EEVEE compiles the material as one shader whose memory grows faster
    than linearly with its Noise nodes (Detail 8 with Distortion at 16 taps
    ran llvmpipe out of 24 GiB): baked for EEVEE, a costly noise gets fewer
    taps, at most EEVEE_NOISE_BUDGET Noise Textures; a cheap one, and any
    noise baked for Cycles, keeps all 16."""
    addon.penumbra.colormap.filter_quality = "TAPS_16_MIXTURE"   # the taps at every sample count
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    noise = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    eevee = "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"
    counts = {}
    for engine, detail, distortion in (("CYCLES", 8.0, 0.5), (eevee, 8.0, 0.5), (eevee, 4.0, 0.0),
                                       (eevee, 2.0, 0.0)):
        addon.render.engine = engine
        noise.inputs["Detail"].default_value, noise.inputs["Distortion"].default_value = detail, distortion
        material.node_tree.nodes.active = ramp
        assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
        group = _noise_filter(material).node_tree
        textures = sum(n.bl_idname == "ShaderNodeTexNoise" for n in group.nodes)
        counts[engine, detail] = (group["penumbra_taps"], textures)
        assert bpy.ops.penumbra.restore_color_ramp() == {"FINISHED"}
    assert counts["CYCLES", 8.0] == (16, 16 * 12)          # 9 octaves + 3 distortion noises per tap
    assert counts[eevee, 8.0] == (4, 4 * 12)
    assert counts[eevee, 4.0] == (8, 8 * 5)
    assert counts[eevee, 2.0] == (16, 16 * 3)
    assert all(textures <= noise_maths.EEVEE_NOISE_BUDGET for (engine, _), (_, textures) in counts.items()
               if engine != "CYCLES")


def test_the_render_swaps_in_the_group_baked_for_its_engine(addon, tmp_path):
    """Baked for Cycles, a noise too costly for EEVEE at 16 taps also gets a
    4-tap group; a render with EEVEE (the render_init handler) swaps it in,
    one with Cycles back, links, driver and values kept."""
    addon.penumbra.colormap.filter_quality = "TAPS_16_MIXTURE"   # the taps at every sample count
    addon.penumbra.colormap.output_folder = str(tmp_path)
    material, ramp, emission, camera = _render_scene(addon, 70.0)
    addon.render.resolution_x, addon.render.resolution_y = 8, 6
    noise = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
    noise.inputs["Detail"].default_value, noise.inputs["Distortion"].default_value = 8.0, 0.5
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    node = _noise_filter(material)
    links = sorted((l.from_socket.name, l.to_socket.name) for l in material.node_tree.links
                   if node in (l.from_node, l.to_node))
    assert len(links) == 9 and node.node_tree["penumbra_taps"] == 16   # 5 in (Vector, footprint), 4 out
    units = node.inputs["Units per World"].default_value
    addon.render.engine = "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"
    assert sample_count.retarget(addon) == 1
    assert node.node_tree["penumbra_taps"] == 4 and _driver_target(node).data_path == "eevee.taa_render_samples"
    assert sorted((l.from_socket.name, l.to_socket.name) for l in material.node_tree.links
                  if node in (l.from_node, l.to_node)) == links
    addon.render.engine = "CYCLES"
    image = _render(addon, str(tmp_path / "tiny.exr"), 2, 0)          # render_init swaps back
    assert node.node_tree["penumbra_taps"] == 16 and _driver_target(node).data_path == "cycles.samples"
    assert node.inputs["Units per World"].default_value == units
    assert image.sum(axis=2).mean() > 0.05   # not black
