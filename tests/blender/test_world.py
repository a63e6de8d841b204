"""penumbra.world, the one reader of the World, inside real Blender: which
Environment Texture lights the scene (the wired one, also inside node groups,
for the render engine in use), the rotation of Mapping and Vector Rotate
nodes (checked against the same map rotated in numpy, by Blender's
equirectangular convention), Mapping Location and Scale of every vector type
and a Vector Rotate Center (the lit World checked against Cycles' own
panorama of it, the rig's light against where the remap analytically puts
the sun), Backgrounds mixed or added (against the sum made in numpy) and the
Light Path Is Camera Ray trick (against a Cycles render lit by the World),
the colour space of the image, plain-colour and broken Worlds, and that the
visibility shading and the light rig, which both read the World through it,
see the same light."""

import json
import math
import os

import bpy
import mathutils
import numpy as np
import pytest

from penumbra import compat, native, world
from penumbra.colormap import interface
from penumbra.visibility import world_lighting

from lights_scenes import directions, sky_and_sun, solid_angles, write_map

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
SUN = np.array([0.4, -0.3, 0.8]) / np.linalg.norm([0.4, -0.3, 0.8])
OTHER_SUN = np.array([-0.5, 0.6, 0.3]) / np.linalg.norm([-0.5, 0.6, 0.3])
ORDER = 4


def _core():
    return native.require()


# Building Worlds ------------------------------------------------------------------

def _new_world(scene, name="Test World"):
    """A World with the default Background → World Output, set on the scene."""
    w = bpy.data.worlds.new(name)
    scene.world = w
    return w, compat.ensure_nodes(w)


def _image(path, pixels):
    """An EXR of `pixels` (row 0 = top), loaded into Blender."""
    _core().image.write_exr(path, pixels.astype(np.float32), half=False, colorspace="Linear")
    return bpy.data.images.load(path)


def _environment(tree, image, link=True):
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    if link:
        tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    return env


def _drive_vector(tree, env, node):
    """Texture Coordinate (Generated) → `node` → the texture's Vector."""
    coords = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coords.outputs["Generated"], node.inputs["Vector"])
    tree.links.new(node.outputs["Vector"], env.inputs["Vector"])
    return node


def _mapping(tree, env, rotation, vector_type="POINT"):
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.vector_type = vector_type
    mapping.inputs["Rotation"].default_value = rotation
    return _drive_vector(tree, env, mapping)


def _map_world(scene, path, pixels, rotation=None, vector_type="POINT"):
    w, tree = _new_world(scene, os.path.basename(path))
    env = _environment(tree, _image(path, pixels))
    if rotation is not None:
        _mapping(tree, env, rotation, vector_type)
    return w


# What each tool sees ----------------------------------------------------------------

def _sh(scene):
    lighting, _ = world_lighting.world_lighting(scene, ORDER)
    return np.asarray(lighting)


def _sh_moment(coefficients):
    """∫ Y(ω) ω dω of the SH lighting's luminance Y (only band 1 contributes),
    by quadrature over Fibonacci directions: the lighting's mean direction."""
    dirs = _core().sh.fibonacci_directions(4000)
    radiance = _core().sh.eval(ORDER, dirs) @ (coefficients @ LUMINANCE)
    return (radiance[:, None] * dirs).sum(axis=0) * 4 * math.pi / len(dirs)


def _rig(scene, tmp_path, count=16, name="rig.json"):
    """(directions, rgb) of a light rig built from the World, each light its
    region's power and centroid: the irradiance fit (on by default) moves
    lights to match the map's irradiance as Blender draws wide suns, which
    keeps no light's region nor the rig's flux-weighted moment (it has its
    own tests); these tests are about what the World reader hands the rig."""
    json_path = str(tmp_path / name)
    assert bpy.ops.penumbra.build_light_rig(count=count, json_path=json_path, fit_irradiance=False) == {"FINISHED"}
    lights = json.load(open(json_path))["frames"][0]["lights"]
    return np.array([l["direction"] for l in lights]), np.array([l["rgb"] for l in lights])


def _rig_moment(directions, rgb):
    return ((rgb @ LUMINANCE)[:, None] * directions).sum(axis=0)


def _angle(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return math.degrees(math.acos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


def _refused(scene, tmp_path, *words):
    with pytest.raises(RuntimeError) as error:
        bpy.ops.penumbra.build_light_rig(count=8, json_path=str(tmp_path / "refused.json"))
    for word in words:
        assert word in str(error.value), (word, str(error.value))
    assert not os.path.exists(tmp_path / "refused.json")
    return str(error.value)


def _rotated_map(pixels, lookup):
    """P(d) = E(lookup·d), nearest pixel, by the latlong convention of
    core/common/latlong.hpp written out here in numpy."""
    h, w = pixels.shape[:2]
    m = directions(h, w) @ np.asarray(lookup).T
    col = np.floor(w * (0.5 - np.arctan2(m[..., 1], m[..., 0]) / (2 * math.pi))).astype(int) % w
    row = np.clip(np.floor(h * np.arccos(np.clip(m[..., 2], -1, 1)) / math.pi).astype(int), 0, h - 1)
    return pixels[row, col]


# Which texture ------------------------------------------------------------------------

def test_the_connected_environment_wins_over_an_unconnected_one(addon, tmp_path):
    scene = addon
    w, tree = _new_world(scene)
    # The unconnected one comes first in the tree: a reader that takes the first
    # Environment Texture it finds gets it.
    stray = _environment(tree, _image(str(tmp_path / "stray.exr"), sky_and_sun(sun=SUN)), link=False)
    wired = _environment(tree, _image(str(tmp_path / "wired.exr"), sky_and_sun(sun=OTHER_SUN)))
    assert tree.nodes[:].index(stray) < tree.nodes[:].index(wired)
    reading = world.read_scene(scene)
    assert reading.kind == "environment" and reading.supported and reading.image.name == "wired.exr"
    assert _angle(_sh_moment(_sh(scene)), OTHER_SUN) < 3.0
    directions, rgb = _rig(scene, tmp_path)
    assert _angle(_rig_moment(directions, rgb), OTHER_SUN) < 3.0
    # Unwire it: the Background's colour lights the scene, as in Blender, and
    # both textures are named as the likely mistake.
    tree.links.remove(wired.outputs["Color"].links[0])
    reading = world.read_scene(scene)
    assert reading.kind == "uniform" and not reading.supported
    assert f"'{stray.name}' (image 'stray.exr') is not connected" in reading.note
    assert f"'{wired.name}' (image 'wired.exr') is not connected" in reading.note
    _refused(scene, tmp_path, "not lit by an image", "is not connected", "Source file")


def test_an_environment_inside_nested_node_groups_behind_a_reroute_is_read(addon, tmp_path):
    scene = addon
    pixels = sky_and_sun(sun=SUN)
    rotation = (0.0, 0.0, math.radians(90))
    _map_world(scene, str(tmp_path / "flat.exr"), pixels, rotation)
    flat_sh = _sh(scene)
    flat_rig = _rig(scene, tmp_path, name="flat.json")
    # The same wiring with the texture two groups deep: the Mapping outside
    # reaches its Vector through both Group Inputs, its Color leaves through
    # both Group Outputs and a reroute.
    inner = bpy.data.node_groups.new("Inner Sky", "ShaderNodeTree")
    interface.add_socket(inner, "Vector", "INPUT", "NodeSocketVector")
    interface.add_socket(inner, "Color", "OUTPUT", "NodeSocketColor")
    env = inner.nodes.new("ShaderNodeTexEnvironment")
    env.image = _image(str(tmp_path / "grouped.exr"), pixels)
    group_in, group_out = inner.nodes.new("NodeGroupInput"), inner.nodes.new("NodeGroupOutput")
    inner.links.new(group_in.outputs["Vector"], env.inputs["Vector"])
    inner.links.new(env.outputs["Color"], group_out.inputs["Color"])
    outer = bpy.data.node_groups.new("Outer Sky", "ShaderNodeTree")
    interface.add_socket(outer, "Vector", "INPUT", "NodeSocketVector")
    interface.add_socket(outer, "Color", "OUTPUT", "NodeSocketColor")
    nested = outer.nodes.new("ShaderNodeGroup")
    nested.node_tree = inner
    group_in, group_out = outer.nodes.new("NodeGroupInput"), outer.nodes.new("NodeGroupOutput")
    outer.links.new(group_in.outputs["Vector"], nested.inputs["Vector"])
    outer.links.new(nested.outputs["Color"], group_out.inputs["Color"])
    w, tree = _new_world(scene, "Grouped")
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = outer
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(group.outputs["Color"], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], tree.nodes["Background"].inputs["Color"])
    _mapping(tree, group, rotation)
    reading = world.read_scene(scene)
    assert reading.kind == "environment" and reading.supported and reading.image.name == "grouped.exr"
    np.testing.assert_allclose(_sh(scene), flat_sh, rtol=0, atol=1e-9 * np.abs(flat_sh).max())
    directions, rgb = _rig(scene, tmp_path, name="grouped.json")
    np.testing.assert_allclose(directions, flat_rig[0], atol=1e-6)
    np.testing.assert_allclose(rgb, flat_rig[1], rtol=1e-6)
    # A muted Mapping node passes the vector on unrotated, as in Blender.
    tree.nodes["Mapping"].mute = True
    assert np.allclose(world.read_scene(scene).world_from_map, np.eye(3))


def test_the_active_world_output_for_the_render_engine_is_read(addon, tmp_path):
    scene = addon
    w, tree = _new_world(scene)
    tree.nodes["World Output"].target = "CYCLES"
    _environment(tree, _image(str(tmp_path / "cycles.exr"), sky_and_sun(sun=SUN)))
    eevee_output = tree.nodes.new("ShaderNodeOutputWorld")
    eevee_output.target = "EEVEE"
    background = tree.nodes.new("ShaderNodeBackground")
    tree.links.new(background.outputs[0], eevee_output.inputs["Surface"])
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = _image(str(tmp_path / "eevee.exr"), sky_and_sun(sun=OTHER_SUN))
    tree.links.new(env.outputs["Color"], background.inputs["Color"])
    scene.render.engine = "CYCLES"
    assert world.read_scene(scene).image.name == "cycles.exr"
    eevee = "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"
    scene.render.engine = eevee
    assert world.read_scene(scene).image.name == "eevee.exr"
    assert _angle(_sh_moment(_sh(scene)), OTHER_SUN) < 3.0
    # Two outputs for every engine: the active one.
    tree.nodes["World Output"].target = "ALL"
    eevee_output.target = "ALL"
    eevee_output.is_active_output = True
    assert world.read_scene(scene).image.name == "eevee.exr"
    tree.nodes["World Output"].is_active_output = True
    assert world.read_scene(scene).image.name == "cycles.exr"


# Rotation -------------------------------------------------------------------------------

@pytest.mark.parametrize("vector_type, roll", [("POINT", 1), ("TEXTURE", -1)])
def test_a_mapping_z_rotation_equals_the_map_pre_rotated(addon, tmp_path, vector_type, roll):
    """Mapping (POINT) looks the texture up at Rz(90°)·d, so it shows what the
    map pre-rotated by a quarter turn shows, its columns moved W/4 to the right
    (TEXTURE: the inverse). The pre-rotated map is made in numpy by the latlong
    convention (u = 0.5 − φ/2π), with no Mapping node."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.05)
    pre_rotated = np.roll(pixels, roll * pixels.shape[1] // 4, axis=1)
    _map_world(scene, str(tmp_path / "plain.exr"), pixels)
    plain_sh = _sh(scene)
    _map_world(scene, str(tmp_path / "pre.exr"), pre_rotated)
    expected_sh = _sh(scene)
    expected_rig = _rig(scene, tmp_path, name="pre.json")
    _map_world(scene, str(tmp_path / "mapped.exr"), pixels, (0.0, 0.0, math.radians(90)), vector_type)
    got_sh = _sh(scene)
    scale = np.abs(expected_sh).max()
    assert np.abs(plain_sh - expected_sh).max() > 0.1 * scale  # the rotation matters
    np.testing.assert_allclose(got_sh, expected_sh, rtol=0, atol=1e-6 * scale)
    directions, rgb = _rig(scene, tmp_path, name="mapped.json")
    # The sampler splits a rotated map into other regions: about 1° apart.
    assert _angle(_rig_moment(directions, rgb), _rig_moment(*expected_rig)) < 2.0
    # A sun at map direction s is seen at Rz(∓90°)·s.
    seen = np.array([SUN[1], -SUN[0], SUN[2]]) if roll == 1 else np.array([-SUN[1], SUN[0], SUN[2]])
    assert _angle(_rig_moment(directions, rgb), seen) < 3.0


@pytest.mark.parametrize("invert", [False, True])
def test_a_vector_rotate_about_z_equals_the_map_pre_rotated(addon, tmp_path, invert):
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.05)
    _map_world(scene, str(tmp_path / "pre.exr"), np.roll(pixels, (-1 if invert else 1) * 32, axis=1))
    expected = _sh(scene)
    w, tree = _new_world(scene)
    env = _environment(tree, _image(str(tmp_path / "rotated.exr"), pixels))
    rotate = tree.nodes.new("ShaderNodeVectorRotate")
    rotate.rotation_type = "Z_AXIS"
    rotate.inputs["Angle"].default_value = math.radians(90)
    rotate.invert = invert
    _drive_vector(tree, env, rotate)
    assert world.read_scene(scene).supported
    np.testing.assert_allclose(_sh(scene), expected, rtol=0, atol=1e-6 * np.abs(expected).max())


@pytest.mark.parametrize("vector_type", ["POINT", "TEXTURE"])
def test_a_full_euler_rotation_equals_the_map_resampled(addon, tmp_path, vector_type):
    """Rotation about all three axes: Blender's Euler XYZ (mathutils, the
    matrix Cycles builds) applied to a smooth map by resampling it in numpy."""
    scene = addon
    h, w = 128, 256
    d = directions(h, w)
    pixels = (0.1 + 3.0 * np.clip(d @ SUN, 0, None)[..., None] ** 4 * np.array([1.0, 0.8, 0.5])
              + 0.3 * np.clip(d @ OTHER_SUN, 0, None)[..., None] ** 2 * np.array([0.2, 0.4, 1.0]))
    euler = (math.radians(30), math.radians(-20), math.radians(75))
    lookup = np.array(mathutils.Euler(euler, "XYZ").to_matrix())
    if vector_type == "TEXTURE":
        lookup = lookup.T
    _map_world(scene, str(tmp_path / "resampled.exr"), _rotated_map(pixels, lookup))
    expected = _sh(scene)
    _map_world(scene, str(tmp_path / "mapped.exr"), pixels, euler, vector_type)
    reading = world.read_scene(scene)
    np.testing.assert_allclose(reading.world_from_map, lookup.T, atol=1e-6)
    got = _sh(scene)
    assert np.abs(got - expected).max() < 0.01 * np.abs(expected).max(), np.abs(got - expected).max()


def test_a_location_and_scale_are_read_and_what_no_reader_can_take_is_reported(addon, tmp_path):
    """A Location and a mirroring Scale make the lookup more than a rotation:
    both tools take it (the light rig resamples the World, the SH lighting
    projects the resampled term), so it is no problem; what neither can
    represent is a problem for both, naming the node and the input."""
    scene = addon
    w = _map_world(scene, str(tmp_path / "map.exr"), sky_and_sun(), (0.0, 0.0, 0.5))
    tree = w.node_tree
    mapping = tree.nodes["Mapping"]
    mapping.inputs["Location"].default_value = (0.5, 0.0, 0.0)
    mapping.inputs["Scale"].default_value = (-1.0, 1.0, 1.0)
    reading = world.read_scene(scene)
    assert reading.kind == "environment" and reading.supported and reading.rotated_image is None
    assert "(remapped)" in reading.note
    assert world_lighting.read_world(scene).supported
    _rig(scene, tmp_path, count=8)
    # A Location driven by other nodes: its own value stands in, for both.
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    tree.links.new(combine.outputs[0], mapping.inputs["Location"])
    reading = world.read_scene(scene)
    assert f"the Location of '{mapping.name}' comes from a Combine XYZ node" in reading.note
    _refused(scene, tmp_path, "cannot be used as it is wired", "the Location of 'Mapping'", "Source file")
    tree.links.remove(mapping.inputs["Location"].links[0])
    # The camera's view of the World is not a direction: refused.
    coords = tree.nodes["Texture Coordinate"]
    tree.links.new(coords.outputs["Window"], mapping.inputs["Vector"])
    _refused(scene, tmp_path, "the Window output of 'Texture Coordinate'", "use Generated")
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    # A uniform scale changes nothing (the lookup drops the length).
    mapping.inputs["Location"].default_value = (0.0, 0.0, 0.0)
    mapping.inputs["Scale"].default_value = (2.0, 2.0, 2.0)
    assert world.read_scene(scene).supported and world.read_scene(scene).rotated_image is not None
    # A Mapping whose own Vector is unconnected looks up one direction.
    tree.links.remove(mapping.inputs["Vector"].links[0])
    assert "is not connected, so the map is looked up in one direction" in world.read_scene(scene).note


# Location and Scale: the map looked up through any remap ------------------------------------

def _panorama(scene, tmp_path, name, h, w, samples=16):
    """(h, w, 3) the World as Cycles renders it, Blender's own L(d): an
    equirectangular panoramic camera at the origin, turned so that its picture
    follows the latlong convention (centre +X, top +Z; checked against the map
    itself below). Camera rays see the World; no light is sampled."""
    camera = bpy.data.cameras.new("Panorama")
    camera.type = "PANO"
    if hasattr(camera, "panorama_type"):
        camera.panorama_type = "EQUIRECTANGULAR"
    else:  # Blender 3.x keeps it in Cycles' settings
        camera.cycles.panorama_type = "EQUIRECTANGULAR"
    ob = bpy.data.objects.new("Panorama", camera)
    ob.rotation_euler = (math.pi / 2, 0.0, -math.pi / 2)
    scene.collection.objects.link(ob)
    scene.camera = ob
    scene.world.cycles.sampling_method = "NONE"
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01  # samples stay inside their pixel
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(tmp_path / name)
    bpy.ops.render.render(write_still=True)
    return _core().image.read(str(tmp_path / name) + ".exr")[..., :3]


def _relative_error(got, expected):
    """‖got − expected‖ / ‖expected‖ over the sphere (each pixel by its solid angle)."""
    omega = solid_angles(*expected.shape[:2])[:, None, None]
    return math.sqrt((omega * (got - expected) ** 2).sum() / (omega * expected ** 2).sum())


def _smooth_map(h=64, w=128):
    """A map without edges, so that a render's samples and the grid's agree."""
    d = directions(h, w)
    return (0.1 + 2.0 * np.clip(d @ SUN, 0, None)[..., None] ** 3 * np.array([1.0, 0.8, 0.5])
            + 0.2 * (0.5 + 0.5 * d)).astype(np.float32)


def test_a_panoramic_cycles_render_of_the_world_is_the_map(addon, tmp_path):
    """The reference the remap tests compare with: Cycles' panorama of a plain
    World, looked up Closest, is the map pixel for pixel."""
    scene = addon
    pixels = _smooth_map()
    w = _map_world(scene, str(tmp_path / "map.exr"), pixels)
    w.node_tree.nodes["Environment Texture"].interpolation = "Closest"
    np.testing.assert_allclose(_panorama(scene, tmp_path, "plain", *pixels.shape[:2]), pixels, rtol=1e-6)


def _vector_rotate_about_a_center(tree, env):
    rotate = tree.nodes.new("ShaderNodeVectorRotate")
    rotate.rotation_type = "AXIS_ANGLE"
    rotate.inputs["Axis"].default_value = (0.3, -1.0, 0.5)
    rotate.inputs["Angle"].default_value = 0.8
    rotate.inputs["Center"].default_value = (0.2, 0.4, -0.3)
    return _drive_vector(tree, env, rotate)


# (vector type, Location, Rotation, Scale); VECTOR and NORMAL have no Location.
_REMAPS = {
    "point": ("POINT", (0.3, -0.5, 0.2), (0.3, -0.2, 1.0), (1.0, 2.0, 0.5)),
    "texture": ("TEXTURE", (0.3, -0.5, 0.2), (0.3, -0.2, 1.0), (1.0, 2.0, 0.5)),
    "vector": ("VECTOR", None, (0.0, 0.4, 0.2), (1.0, 2.0, 0.5)),
    "normal": ("NORMAL", None, (0.0, 0.4, 0.2), (1.0, -2.0, 0.5)),
    "mirror_ball": ("POINT", (0.2, 0.1, -0.4), (0.0, 0.0, 0.7), (1.5, 1.0, 1.0)),
}


@pytest.mark.parametrize("case", [*_REMAPS, "vector_rotate_center"])
def test_a_mapping_location_and_scale_look_the_map_up_where_cycles_does(addon, tmp_path, case):
    """The World's light on a latlong grid (world.environment_radiance, what
    the light rig is built from) against Cycles' own panorama of the World,
    for Mapping nodes of each type with a Location, a Rotation and a
    non-uniform or negative Scale, a mirror-ball image, and a Vector Rotate
    about a Center."""
    scene = addon
    pixels = _smooth_map()
    if case == "mirror_ball":
        ball = np.full((64, 64, 3), 0.2, np.float32)
        u, v = np.meshgrid(np.linspace(-1, 1, 64), np.linspace(1, -1, 64))
        ball[..., 0] += 0.5 * (1 + u)
        ball[..., 1] += 0.5 * (1 + v)
        pixels = ball
    w, tree = _new_world(scene, case)
    env = _environment(tree, _image(str(tmp_path / f"{case}.exr"), pixels))
    if case == "vector_rotate_center":
        _vector_rotate_about_a_center(tree, env)
    else:
        vector_type, location, rotation, scale = _REMAPS[case]
        mapping = _mapping(tree, env, rotation, vector_type)
        mapping.inputs["Scale"].default_value = scale
        if location is not None:
            mapping.inputs["Location"].default_value = location
    if case == "mirror_ball":
        env.projection = "MIRROR_BALL"
    h, w_ = 64, 128
    rendered = _panorama(scene, tmp_path, f"{case}_render", h, w_)
    reading = world.read_scene(scene)
    assert reading.supported and reading.rotated_image is None, reading.note
    values = [world.image_pixels(term.image) for term in reading.terms]
    got = world.environment_radiance(reading.terms, values, w_)
    assert got.shape == (h, w_, 3)
    assert _relative_error(got, rendered) < 0.015, _relative_error(got, rendered)
    # The SH lighting projects the same remapped World: the SH of Cycles' panorama.
    expected = _core().sh.project_environment(ORDER, rendered)
    sh_error = np.abs(_sh(scene) - expected).max() / np.abs(expected).max()
    assert sh_error < 0.01, sh_error
    # The remap matters: the plain map is far from it.
    if case != "mirror_ball":
        assert _relative_error(pixels, rendered) > 0.1
        plain = _core().sh.project_environment(ORDER, pixels)
        assert np.abs(plain - expected).max() / np.abs(expected).max() > 5 * sh_error


def _remapped_light(pixels, remap):
    """The light of a map looked up at remap(d), independently of world.py:
    nearest pixels by the latlong convention, on a 4× finer grid, in numpy.
    Returns (its flux-weighted mean direction, ∫ L dω per channel)."""
    h, w = pixels.shape[0] * 4, pixels.shape[1] * 4
    d = directions(h, w)
    m = remap(d)
    m = m / np.linalg.norm(m, axis=-1, keepdims=True)
    ph, pw = pixels.shape[:2]
    col = np.floor(pw * (0.5 - np.arctan2(m[..., 1], m[..., 0]) / (2 * math.pi))).astype(int) % pw
    row = np.clip(np.floor(ph * np.arccos(np.clip(m[..., 2], -1, 1)) / math.pi).astype(int), 0, ph - 1)
    flux = pixels[row, col] * solid_angles(h, w)[:, None, None]
    return ((flux @ LUMINANCE)[..., None] * d).sum(axis=(0, 1)), flux.sum(axis=(0, 1))


def test_a_mapping_location_puts_the_sun_where_the_lookup_sees_it(addon, tmp_path):
    """Mapping POINT with a Location t looks the map up at normalize(d + t),
    so the map's sun at s is seen where d + t ∥ s: d = k·s − t with |d| = 1,
    k = s·t + √((s·t)² − |t|² + 1). The rig's light goes there, and its total
    is the remapped World's ∫ L dω (a Location changes the solid angle the
    sun covers)."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.0)
    t = np.array([0.5, 0.2, -0.3])
    w = _map_world(scene, str(tmp_path / "map.exr"), pixels, (0.0, 0.0, 0.0))
    w.node_tree.nodes["Mapping"].inputs["Location"].default_value = t
    k = SUN @ t + math.sqrt((SUN @ t) ** 2 - t @ t + 1.0)
    seen = k * SUN - t
    assert abs(np.linalg.norm(seen) - 1.0) < 1e-9 and _angle(seen, SUN) > 20.0
    directions, rgb = _rig(scene, tmp_path, count=16)
    assert _angle(_rig_moment(directions, rgb), seen) < 2.0, _angle(_rig_moment(directions, rgb), seen)
    moment, total = _remapped_light(pixels, lambda d: d + t)
    assert _angle(_rig_moment(directions, rgb), moment) < 1.0
    np.testing.assert_allclose(rgb.sum(axis=0), total, rtol=0.02)
    assert abs(rgb.sum() / (pixels * solid_angles(64, 128)[:, None, None]).sum() - 1.0) > 0.1


def test_a_uniform_scale_changes_nothing_and_others_bend_or_mirror_the_map(addon, tmp_path):
    """Scale s looks the map up at normalize(s∘d): (2, 2, 2) is the plain map,
    rig for rig; (1, 1, 3) sees the sun at normalize(s_x, s_y, s_z/3), lower;
    (−1, 1, 1) mirrors it to (−s_x, s_y, s_z)."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.0)
    w = _map_world(scene, str(tmp_path / "map.exr"), pixels, (0.0, 0.0, 0.0))
    plain = _rig(scene, tmp_path, name="plain.json")
    scale = w.node_tree.nodes["Mapping"].inputs["Scale"]
    scale.default_value = (2.0, 2.0, 2.0)
    assert world.read_scene(scene).rotated_image is not None
    uniform = _rig(scene, tmp_path, name="uniform.json")
    np.testing.assert_allclose(uniform[0], plain[0], atol=1e-9)
    np.testing.assert_allclose(uniform[1], plain[1], rtol=1e-9)
    for factors, seen in (((1.0, 1.0, 3.0), SUN / np.array([1.0, 1.0, 3.0])),
                          ((-1.0, 1.0, 1.0), SUN * np.array([-1.0, 1.0, 1.0]))):
        scale.default_value = factors
        directions, rgb = _rig(scene, tmp_path, name="scaled.json")
        moment, total = _remapped_light(pixels, lambda d: d * np.array(factors))
        assert _angle(_rig_moment(directions, rgb), seen) < 3.0, (factors, _angle(_rig_moment(directions, rgb), seen))
        assert _angle(_rig_moment(directions, rgb), moment) < 1.0
        np.testing.assert_allclose(rgb.sum(axis=0), total, rtol=0.02)


def test_a_remapped_world_image_that_is_a_sequence_or_packed_gives_every_frame(addon, tmp_path):
    """The resampled path reads what the rotated path reads: a World image
    that is the first of a numbered sequence gives one rig frame per file
    (here three exposures, so three totals in ratio 1 : 2 : 3), and the same
    image packed into the .blend gives the file's first frame."""
    scene = addon
    folder = tmp_path / "seq"
    folder.mkdir()
    pixels = sky_and_sun(sun=SUN, sky=0.05)
    for i in range(3):
        write_map(str(folder / f"sky_{i + 1:04d}.exr"), (i + 1) * pixels)
    w, tree = _new_world(scene)
    env = _environment(tree, bpy.data.images.load(str(folder / "sky_0001.exr")))
    _mapping(tree, env, (0.0, 0.0, 0.0)).inputs["Location"].default_value = (0.0, 0.3, 0.4)
    json_path = str(tmp_path / "sequence.json")
    assert bpy.ops.penumbra.build_light_rig(count=8, frame_start=1, frame_end=3, temporal_filter=False,
                                            fit_irradiance=False, json_path=json_path) == {"FINISHED"}
    frames = json.load(open(json_path))["frames"]
    totals = np.array([sum(l["rgb"][1] for l in f["lights"]) for f in frames])
    np.testing.assert_allclose(totals / totals[0], [1.0, 2.0, 3.0], rtol=1e-5)
    env.image.pack()
    directions, rgb = _rig(scene, tmp_path, count=8, name="packed.json")
    first = frames[0]["lights"]
    np.testing.assert_allclose(directions, [l["direction"] for l in first], atol=1e-5)
    np.testing.assert_allclose(rgb, [l["rgb"] for l in first], rtol=1e-4)


# Backgrounds mixed and added -------------------------------------------------------------

def _constant_background(tree, colour, strength):
    background = tree.nodes.new("ShaderNodeBackground")
    background.inputs["Color"].default_value = (*colour, 1.0)
    background.inputs["Strength"].default_value = strength
    return background


def _combine(tree, idname, first, second):
    """`first` and `second` Backgrounds into a Mix or Add Shader at the World Output."""
    node = tree.nodes.new(idname)
    inputs = (1, 2) if idname == "ShaderNodeMixShader" else (0, 1)
    tree.links.new(first.outputs[0], node.inputs[inputs[0]])
    tree.links.new(second.outputs[0], node.inputs[inputs[1]])
    tree.links.new(node.outputs[0], tree.nodes["World Output"].inputs["Surface"])
    return node


@pytest.mark.parametrize("idname, shares", [("ShaderNodeMixShader", (0.7, 0.3)), ("ShaderNodeAddShader", (1.0, 1.0))])
def test_a_background_mixed_with_a_constant_colour_lights_as_their_weighted_sum(addon, tmp_path, idname, shares):
    """A Mix Shader of Fac 0.3 gives its first Background 0.7 and its second
    0.3 (an Add Shader 1 and 1): the image at strength 2 plus a colour at
    strength 1.5 light as that sum, made in numpy and built from a file."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.05)
    colour = np.array([0.2, 0.3, 0.5])
    summed = shares[0] * 2.0 * pixels + shares[1] * 1.5 * colour
    json_path = str(tmp_path / "file.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=write_map(str(tmp_path / "summed.exr"), summed), count=16,
                                            json_path=json_path, fit_irradiance=False) == {"FINISHED"}
    lights = json.load(open(json_path))["frames"][0]["lights"]
    from_file = np.array([l["direction"] for l in lights]), np.array([l["rgb"] for l in lights])
    w, tree = _new_world(scene)
    _environment(tree, _image(str(tmp_path / "map.exr"), pixels))
    tree.nodes["Background"].inputs["Strength"].default_value = 2.0
    node = _combine(tree, idname, tree.nodes["Background"], _constant_background(tree, colour, 1.5))
    if idname == "ShaderNodeMixShader":
        node.inputs["Fac"].default_value = 0.3
    reading = world.read_scene(scene)
    assert reading.supported and [t.weight for t in reading.terms] == pytest.approx(shares)
    directions, rgb = _rig(scene, tmp_path, count=16)
    total = (summed * solid_angles(*pixels.shape[:2])[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(rgb.sum(axis=0), total, rtol=3e-3)
    np.testing.assert_allclose(from_file[1].sum(axis=0), total, rtol=1e-4)
    assert _angle(_rig_moment(directions, rgb), _rig_moment(*from_file)) < 1.0
    # The SH lighting is the SH of the same sum.
    expected = _core().sh.project_environment(ORDER, summed.astype(np.float32))
    assert world_lighting.read_world(scene).supported
    np.testing.assert_allclose(_sh(scene), expected, rtol=0, atol=1e-3 * np.abs(expected).max())


def _plane_lit(scene, tmp_path, name):
    """Mean pixel of a white diffuse plane seen from straight above by an
    orthographic camera that sees nothing else (32x32, 64 spp, Cycles)."""
    if "Plane" not in scene.objects:
        bpy.ops.mesh.primitive_plane_add(size=4.0)
        material = bpy.data.materials.new("White")
        tree = compat.ensure_nodes(material)
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
        tree.links.new(diffuse.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
        scene.objects["Plane"].data.materials.append(material)
        camera = bpy.data.objects.new("Above", bpy.data.cameras.new("Above"))
        camera.data.type, camera.data.ortho_scale = "ORTHO", 1.0
        camera.location = (0.0, 0.0, 3.0)
        scene.collection.objects.link(camera)
        scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 64, False
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(tmp_path / name)
    bpy.ops.render.render(write_still=True)
    return _core().image.read(str(tmp_path / name) + ".exr")[..., :3].reshape(-1, 3).mean(axis=0)


def test_is_camera_ray_lights_with_one_background_and_shows_the_camera_the_other(addon, tmp_path):
    """The Light Path trick: Mix Shader with Fac = Is Camera Ray, the image on
    the first Shader, a bright white on the second. Every ray that lights a
    surface sees Fac 0, so the rig is the image's alone, and a Cycles render
    of a plane lit by this World is the render of the plane lit by the rig,
    not the white's 0.8·5."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.2, radius=0.2, sun_radiance=20.0)
    w, tree = _new_world(scene, "Camera Trick")
    _environment(tree, _image(str(tmp_path / "map.exr"), pixels))
    white = _constant_background(tree, (1.0, 1.0, 1.0), 5.0)
    mix = _combine(tree, "ShaderNodeMixShader", tree.nodes["Background"], white)
    light_path = tree.nodes.new("ShaderNodeLightPath")
    tree.links.new(light_path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    reading = world.read_scene(scene)
    assert reading.supported and len(reading.terms) == 1 and "to the camera only" in reading.note
    # Blender's own evaluation first (no rig in the scene yet): the plane lit
    # by the World gets the rig's irradiance Σ rgb·max(0, d_z).
    w.cycles.sampling_method = "MANUAL"  # a small importance map: seconds, not minutes
    w.cycles.sample_map_resolution = 256
    world_lit = _plane_lit(scene, tmp_path, "world")
    directions, rgb = _rig(scene, tmp_path, count=64)
    expected = 0.8 * (rgb.T @ np.clip(directions[:, 2], 0, None)) / math.pi
    np.testing.assert_allclose(world_lit, expected, rtol=0.03)
    assert np.all(world_lit < 0.5 * 0.8 * 5.0)
    assert world_lighting.read_world(scene).supported
    # The rig is the image's alone.
    _map_world(scene, str(tmp_path / "alone.exr"), pixels)
    alone = _rig(scene, tmp_path, count=64, name="alone.json")
    np.testing.assert_allclose(directions, alone[0], atol=1e-9)
    np.testing.assert_allclose(rgb, alone[1], rtol=1e-9)
    scene.world = w
    # Swapped, the image is the camera's only: no image lights the scene.
    tree.links.new(tree.nodes["Background"].outputs[0], mix.inputs[2])
    tree.links.new(white.outputs[0], mix.inputs[1])
    _refused(scene, tmp_path, "not lit by an image", "to the camera only", "Source file")
    # Is Diffuse Ray is 1 for a bounce but 0 for a light sample: refused, named.
    tree.links.new(light_path.outputs["Is Diffuse Ray"], mix.inputs["Fac"])
    _refused(scene, tmp_path, f"the Fac of the Mix Shader '{mix.name}' comes from the Is Diffuse Ray output of the "
                              f"Light Path node '{light_path.name}'")


def test_a_mirror_ball_world_is_decomposed_as_a_mirror_ball(addon, tmp_path):
    """Cycles' direction_to_mirrorball and the core's mirror_ball mapping are
    the same for a square image (a ball seen along +Y): the World's projection
    picks the rig's mapping, and the SH lighting (the ball resampled onto a
    latlong grid, then projected) carries the rig's light in its direction."""
    scene = addon
    pixels = np.full((64, 64, 3), 0.05, np.float32)
    pixels[18:24, 40:46] = 50.0
    path = str(tmp_path / "ball.exr")
    w = _map_world(scene, path, pixels)
    w.node_tree.nodes["Environment Texture"].projection = "MIRROR_BALL"
    from_world = _rig(scene, tmp_path, count=8, name="world.json")
    json_path = str(tmp_path / "file.json")
    assert bpy.ops.penumbra.build_light_rig(filepath=path, mapping="MIRROR_BALL", count=8,
                                            fit_irradiance=False, json_path=json_path) == {"FINISHED"}
    lights = json.load(open(json_path))["frames"][0]["lights"]
    np.testing.assert_allclose(from_world[0], [l["direction"] for l in lights], atol=1e-6)
    assert world_lighting.read_world(scene).supported
    lighting = _sh(scene)
    directions, rgb = np.array([l["direction"] for l in lights]), np.array([l["rgb"] for l in lights])
    np.testing.assert_allclose(lighting[0] * math.sqrt(4 * math.pi), rgb.sum(axis=0), rtol=0.02)
    assert _angle(_sh_moment(lighting), _rig_moment(directions, rgb)) < 2.0


# Colour ----------------------------------------------------------------------------------

def _srgb_to_linear(encoded):
    """The sRGB transfer function (IEC 61966-2-1), independent of OCIO."""
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


def test_a_non_linear_image_is_converted_to_scene_linear_by_both_tools(addon, tmp_path):
    scene = addon
    h, w = 8, 16
    encoded = np.empty((h, w, 3))
    encoded[: h // 2] = np.array([200, 120, 40]) / 255.0
    encoded[h // 2:] = np.array([30, 90, 160]) / 255.0
    maker = bpy.data.images.new("maker", w, h)
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = encoded[::-1]  # Blender rows are bottom-up
    maker.pixels.foreach_set(rgba.ravel())
    maker.filepath_raw = str(tmp_path / "srgb.png")
    maker.file_format = "PNG"
    maker.save()
    image = bpy.data.images.load(str(tmp_path / "srgb.png"))
    assert not image.is_float and image.colorspace_settings.name == "sRGB"
    w_, tree = _new_world(scene)
    _environment(tree, image)
    linear = _srgb_to_linear(encoded)
    total = (linear * solid_angles(h, w)[:, None, None]).sum(axis=(0, 1))  # ∫ L dω per channel
    # Visibility: the SH lighting's constant term is ∫ L dω / √(4π).
    np.testing.assert_allclose(_sh(scene)[0] * math.sqrt(4 * math.pi), total, rtol=2e-3)
    np.testing.assert_allclose(world.image_pixels(image), linear, rtol=2e-3, atol=1e-4)
    # Light rig, from the file and from the packed image: Σ rgb = ∫ L dω.
    np.testing.assert_allclose(_rig(scene, tmp_path, count=4, name="file.json")[1].sum(axis=0), total, rtol=2e-3)
    image.pack()
    np.testing.assert_allclose(_rig(scene, tmp_path, count=4, name="packed.json")[1].sum(axis=0), total,
                               rtol=2e-3)
    # Non-Color data is not converted.
    image.colorspace_settings.name = "Non-Color"
    raw = (encoded * solid_angles(h, w)[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(_sh(scene)[0] * math.sqrt(4 * math.pi), raw, rtol=2e-3)


# Worlds without a map ------------------------------------------------------------------

def test_a_colour_only_world_is_uniform_light(addon, tmp_path):
    scene = addon
    w, tree = _new_world(scene)
    background = tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.2, 0.4, 0.8, 1.0)
    background.inputs["Strength"].default_value = 2.5
    reading = world.read_scene(scene)
    assert reading.kind == "uniform" and reading.supported
    # Strength is returned beside the colour, not folded into it.
    assert reading.strength == 2.5 and np.allclose(reading.colour, (0.2, 0.4, 0.8))
    lighting = _sh(scene)
    np.testing.assert_allclose(lighting[0], 2.5 * np.array([0.2, 0.4, 0.8]) * math.sqrt(4 * math.pi), rtol=1e-6)
    assert not lighting[1:].any()
    _refused(scene, tmp_path, "not lit by an image", "connect an Environment Texture", "Source file")
    if not compat.ALWAYS_USES_NODES:
        # Nodes off (before Blender 5.0): the World's own colour.
        w.use_nodes = False
        w.color = (0.1, 0.3, 0.5)
        reading = world.read_scene(scene)
        assert reading.kind == "uniform" and np.allclose(reading.colour, (0.1, 0.3, 0.5))


def test_a_world_with_no_nodes_no_output_or_no_image_says_what_to_do(addon, tmp_path):
    scene = addon
    scene.world = None
    reading = world.read_scene(scene)
    assert reading.kind == "black" and "no World" in reading.note
    _refused(scene, tmp_path, "World", "Source file")
    w, tree = _new_world(scene)
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    reading = world.read_scene(scene)
    assert reading.kind == "black" and not reading.supported and not _sh(scene).any()
    assert f"the World '{w.name}' has no World Output node" in reading.note
    _refused(scene, tmp_path, "no World Output node", "connect a Background node")
    tree.nodes.new("ShaderNodeOutputWorld")
    reading = world.read_scene(scene)
    assert reading.kind == "black" and "nothing (or only a muted node) is connected" in reading.note
    w, tree = _new_world(scene, "No Image")
    env = _environment(tree, None)
    reading = world.read_scene(scene)
    assert reading.kind == "uniform" and f"the Environment Texture '{env.name}' has no image" in reading.note
    _refused(scene, tmp_path, "has no image: open an image in it")
    # An image whose file is gone: the visibility shading says which file.
    env.image = _image(str(tmp_path / "gone.exr"), sky_and_sun())
    os.remove(tmp_path / "gone.exr")
    env.image.reload()
    with pytest.raises(world.WorldError, match="gone.exr' is missing; point the image at an existing file"):
        world.image_pixels(env.image)


# Both tools ------------------------------------------------------------------------------

def test_the_visibility_lighting_and_the_light_rig_see_the_same_light(addon, tmp_path):
    """Through world.py both tools read the same map, rotation and strength:
    the SH lighting's mean direction is the rig's, and its total light the rig's."""
    scene = addon
    pixels = sky_and_sun(sun=SUN, sky=0.2)
    w = _map_world(scene, str(tmp_path / "map.exr"), pixels,
                   (math.radians(20), math.radians(-35), math.radians(110)))
    tree = w.node_tree
    value = tree.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = 2.0
    tree.links.new(value.outputs[0], tree.nodes["Background"].inputs["Strength"])
    reading = world.read_scene(scene)
    assert reading.supported and reading.strength == 2.0
    lighting = _sh(scene)
    directions, rgb = _rig(scene, tmp_path, count=32)
    assert _angle(_sh_moment(lighting), _rig_moment(directions, rgb)) < 2.0
    np.testing.assert_allclose(lighting[0] * math.sqrt(4 * math.pi), rgb.sum(axis=0), rtol=1e-3)
    total = 2.0 * (pixels * solid_angles(*pixels.shape[:2])[:, None, None]).sum(axis=(0, 1))
    np.testing.assert_allclose(rgb.sum(axis=0), total, rtol=1e-4)
    # Where the sun is seen: the map's sun turned by world_from_map.
    seen = np.array(mathutils.Euler((math.radians(20), math.radians(-35), math.radians(110)),
                                    "XYZ").to_matrix()).T @ SUN
    assert _angle(_rig_moment(directions, rgb), seen) < 3.0
