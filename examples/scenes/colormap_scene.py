"""The colour-map tool's test scenes, for copying: an emissive plane receding to
the horizon (or a torus), its colour a ColorRamp driven by a Noise Texture in
Object coordinates, seen by a camera. Far away (and where the surface turns
away from the camera), the noise is much finer than a pixel, which is where a
plain ramp sparkles.

`noise_ramp_plane()` with its defaults is the scene of examples/demo_colormap.py
and the Blender tests; its keyword arguments (and `noise_ramp_torus`) make the
variants bench/blender_scripts/colormap_render.py measures (grazing view, Constant or HSV ramps,
more noise detail, distortion, a curved object). `offset_noise` moves the noise
pattern without moving anything else (the EEVEE sweep's "seeds")."""

import colorsys
import math

import bpy
from mathutils import Matrix, Vector

# The two-stop ramp of the original scene: a sharp red-to-blue edge at Fac 0.5.
TWO_STOPS = ((0.47, (0.8, 0.05, 0.02, 1.0)), (0.53, (0.02, 0.3, 0.9, 1.0)))
# Four stops for a Constant ramp: three steps around the noise's mean.
CONSTANT_STOPS = ((0.38, (0.05, 0.05, 0.05, 1.0)), (0.47, (0.8, 0.05, 0.02, 1.0)),
                  (0.53, (0.02, 0.3, 0.9, 1.0)), (0.62, (0.9, 0.85, 0.6, 1.0)))
# Eight stops around the hue circle between Fac 0.3 and 0.7 (for HSV colour mode).
HSV_STOPS = tuple((0.3 + 0.4 * k / 7, (*colorsys.hsv_to_rgb(k / 8, 0.9, 0.8), 1.0)) for k in range(8))


def noise_ramp_material(scale=2.0, detail=4.0, roughness=None, distortion=None, stops=None,
                        interpolation=None, color_mode=None, name="noise ramp"):
    """A material: Texture Coordinate (Object) -> Noise Texture -> ColorRamp ->
    Emission. `stops` is ((position, RGBA), ...) (default TWO_STOPS);
    interpolation / color_mode are the ramp's (Blender's defaults LINEAR / RGB
    when None). The ramp is the tree's active node. Returns (material, ramp, emission)."""
    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):  # 5.0+: always node-based, use_nodes is deprecated
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    coords = tree.nodes.new("ShaderNodeTexCoord")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    noise.inputs["Detail"].default_value = detail
    if roughness is not None:
        noise.inputs["Roughness"].default_value = roughness
    if distortion is not None:
        noise.inputs["Distortion"].default_value = distortion
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    band = ramp.color_ramp
    if interpolation is not None:
        band.interpolation = interpolation
    if color_mode is not None:
        band.color_mode = color_mode
    stops = sorted(stops or TWO_STOPS)
    # The ends first, then new elements in between (Blender keeps them sorted
    # by position), then the colours in that order.
    band.elements[0].position, band.elements[1].position = stops[0][0], stops[-1][0]
    for position, _ in stops[1:-1]:
        band.elements.new(position)
    for element, (_, colour) in zip(band.elements, stops):
        element.color = colour
    tree.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], emission.inputs["Color"])
    tree.nodes.active = ramp
    return material, ramp, emission


def _add_camera(location, rotation_degrees):
    bpy.ops.object.camera_add(location=location, rotation=tuple(math.radians(a) for a in rotation_degrees))
    camera = bpy.context.active_object
    bpy.context.scene.camera = camera
    return camera


def noise_ramp_plane(plane_size=400.0, plane_location=(0.0, 190.0, 0.0),
                     camera_location=(0.0, -2.0, 1.2), camera_rotation_degrees=(84.0, 0.0, 0.0),
                     detail=4.0, roughness=None, **material_options):
    """Adds the plane, its material (`noise_ramp_material`; keyword arguments
    beyond `detail`/`roughness` go to it) and a camera to the current scene
    (made the scene camera; the plane is left active). Returns
    (plane, material, ramp node, emission node, camera)."""
    bpy.ops.mesh.primitive_plane_add(size=plane_size, location=plane_location)
    plane = bpy.context.active_object
    material, ramp, emission = noise_ramp_material(detail=detail, roughness=roughness, **material_options)
    plane.data.materials.append(material)
    camera = _add_camera(camera_location, camera_rotation_degrees)
    bpy.context.view_layer.objects.active = plane
    return plane, material, ramp, emission, camera


def noise_ramp_torus(camera_location=(0.0, -5.2, 3.6), major_radius=1.0, minor_radius=0.38,
                     rotation_degrees=(0.0, 12.0, 25.0), scale=10.0, detail=4.0, roughness=None, **material_options):
    """A smooth-shaded torus at the origin with the noise ramp material (its
    surface faces the camera at every angle from head-on to the silhouette),
    and a camera aimed at its centre. Returns (torus, material, ramp node,
    emission node, camera), the torus active."""
    bpy.ops.mesh.primitive_torus_add(major_radius=major_radius, minor_radius=minor_radius, major_segments=96,
                                     minor_segments=48, rotation=tuple(math.radians(a) for a in rotation_degrees))
    torus = bpy.context.active_object
    for polygon in torus.data.polygons:
        polygon.use_smooth = True
    material, ramp, emission = noise_ramp_material(scale=scale, detail=detail, roughness=roughness,
                                                   **material_options)
    torus.data.materials.append(material)
    aim = (-Vector(camera_location)).to_track_quat("-Z", "Y").to_euler()
    camera = _add_camera(camera_location, tuple(math.degrees(a) for a in aim))
    bpy.context.view_layer.objects.active = torus
    return torus, material, ramp, emission, camera


def offset_noise(obj, offset):
    """Shifts the noise pattern on `obj` by `offset` (texture units) without
    moving the surface: the mesh moves by +offset inside the object and the
    object by -offset in the world, so Object coordinates (what the noise
    reads) gain +offset at every point. The material is not touched. Call
    again with another offset to replace it (offsets do not add up)."""
    previous = Vector(obj.get("noise_offset", (0.0, 0.0, 0.0)))
    step = Vector(offset) - previous
    obj.data.transform(Matrix.Translation(step))
    obj.location -= obj.matrix_basis.to_3x3() @ step
    obj["noise_offset"] = tuple(offset)
