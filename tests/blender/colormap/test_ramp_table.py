"""The lookup is built from the table the renderer evaluates a ColorRamp
through (colormap.ramp.renderer_table_size): Cycles 3.x samples 256 entries at
i/255, Cycles 4.5 and 5.2 257 at i/256. A Constant ramp steps on those
entries, so a lookup built from the other table moves each step by up to one
entry, a colour bias no sample count removes (issue #12: the Constant scene
stalled above the plain ramp at 64 spp)."""

import bpy
import numpy as np

from penumbra.colormap import ramp as ramp_io

# Fac runs over [FAC_LOW, FAC_HIGH] across the image; the stops sit where the
# two tables put their steps about 0.002 apart (2 % of the image each).
FAC_LOW, FAC_HIGH = 0.44, 0.54
STOPS = ((0.0, (0.0, 0.0, 0.0, 1.0)), (0.47, (1.0, 0.0, 0.0, 1.0)), (0.51, (0.0, 0.0, 1.0, 1.0)))
WIDTH = 2000


def _gradient_scene(scene):
    """An orthographic view of a plane whose Emission is a Constant ramp of
    Fac = FAC_LOW..FAC_HIGH from left to right; returns (tree, ramp, emission)."""
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.filter_size = 0.01          # each pixel is its centre's value
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, 2
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    mesh = bpy.data.meshes.new("plane")
    mesh.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
    plane = bpy.data.objects.new("plane", mesh)
    scene.collection.objects.link(plane)
    material = bpy.data.materials.new("gradient")
    if bpy.app.version < (5, 0, 0):
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    coords, separate = tree.nodes.new("ShaderNodeTexCoord"), tree.nodes.new("ShaderNodeSeparateXYZ")
    to_fac = tree.nodes.new("ShaderNodeMapRange")
    for index, value in ((1, -1.0), (2, 1.0), (3, FAC_LOW), (4, FAC_HIGH)):
        to_fac.inputs[index].default_value = value
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.interpolation = "CONSTANT"
    elements = ramp.color_ramp.elements
    elements[0].position, elements[0].color = STOPS[0]
    elements[1].position, elements[1].color = STOPS[1]
    elements.new(STOPS[2][0]).color = STOPS[2][1]
    emission, output = tree.nodes.new("ShaderNodeEmission"), tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(coords.outputs["Object"], separate.inputs[0])
    tree.links.new(separate.outputs[0], to_fac.inputs[0])
    tree.links.new(to_fac.outputs[0], ramp.inputs[0])
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    tree.links.new(emission.outputs[0], output.inputs["Surface"])
    mesh.materials.append(material)
    camera_data = bpy.data.cameras.new("camera")
    camera_data.type, camera_data.ortho_scale = "ORTHO", 2.0
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = (0.0, 0.0, 3.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    bpy.context.view_layer.objects.active = plane
    tree.nodes.active = ramp
    return tree, ramp, emission


def _render_row(scene, path):
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.array(image.pixels[:], np.float32).reshape(image.size[1], image.size[0], 4)
    bpy.data.images.remove(image)
    return pixels[0, :, :3]


def _lookup_bias(addon, tmp_path):
    """Mean colour of the lookup at σ = 0 minus the plain ramp's, over the gradient."""
    addon.penumbra.colormap.output_folder = str(tmp_path)
    addon.penumbra.colormap.lut_width = 4096  # the bilinear step is 1/4096 wide: below what is tested
    tree, ramp, emission = _gradient_scene(addon)
    plain = _render_row(addon, str(tmp_path / "plain.exr"))
    assert bpy.ops.penumbra.bake_colormap_lut() == {"FINISHED"}
    looked_up = _render_row(addon, str(tmp_path / "lookup.exr"))
    return looked_up.mean(axis=0) - plain.mean(axis=0)


def test_lookup_at_zero_sigma_steps_where_cycles_does(addon, tmp_path):
    bias = _lookup_bias(addon, tmp_path)
    assert np.abs(bias).max() < 0.004, f"mean colour bias {bias} against the plain Constant ramp"


def test_the_other_blenders_table_is_measurably_wrong(addon, tmp_path, monkeypatch):
    """The test above can fail: built from the other Blender's table, the
    same lookup is off by about 2 % of the image per step."""
    addon.render.engine = "CYCLES"
    sizes = {ramp_io.CYCLES_3X_TABLE_SIZE, ramp_io.COLORBAND_TABLE_SIZE}
    (wrong_size,) = sizes - {ramp_io.renderer_table_size(addon)}
    monkeypatch.setattr(ramp_io, "renderer_table_size", lambda scene: wrong_size)
    bias = _lookup_bias(addon, tmp_path)
    assert np.abs(bias).max() > 0.012, f"mean colour bias {bias} with a {wrong_size}-entry table"
