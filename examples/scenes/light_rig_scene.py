"""The light-rig tool's shadow scene, for copying: a smooth sphere resting on a
plane, seen from above at an angle, so a rig's suns cast visible shadows.

Used by examples/demo_light_rig.py and bench/lights_benchmark.py."""

import math

import bpy


def sphere_on_plane(scene):
    """Adds the plane, the sphere and a camera (made the scene camera)."""
    bpy.ops.mesh.primitive_plane_add(size=6)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7, location=(0, 0, 0.7))
    bpy.ops.object.shade_smooth()
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (4.5, -4.5, 3.2)
    camera.rotation_euler = (math.radians(65), 0, math.radians(45))
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera
