"""The light-rig tool's shadow scene, for copying: a smooth sphere resting on a
plane, seen from above at an angle, so a rig's suns cast visible shadows.

Used by examples/demo_light_rig.py and bench/lights_benchmark.py."""

import math

import bpy


def default_surface():
    """The one surface of these scenes: a Principled BSDF at this Blender's
    defaults, given explicitly. An object without a material is drawn by
    EEVEE with this surface, but by Cycles before 5.0 as a grey diffuse
    (0.8), which lacks the specular layer that a sun grazing the plane from
    behind it reflects towards the camera; renderers compared on one scene
    must draw the same surface."""
    material = bpy.data.materials.get("Default Surface")
    if material is None:
        material = bpy.data.materials.new("Default Surface")
        material.use_nodes = True  # a Principled BSDF at its defaults
    return material


def sphere_on_plane(scene):
    """Adds the plane, the sphere (both default_surface()) and a camera (made
    the scene camera)."""
    bpy.ops.mesh.primitive_plane_add(size=6)
    plane = bpy.context.active_object
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7, location=(0, 0, 0.7))
    bpy.ops.object.shade_smooth()
    for obj in (plane, bpy.context.active_object):
        obj.data.materials.append(default_surface())
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (4.5, -4.5, 3.2)
    camera.rotation_euler = (math.radians(65), 0, math.radians(45))
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera
