"""The procedural character, its bake and its attributes, shared by the visibility tests."""

import math
import os
import sys

import bpy
import numpy as np

from penumbra import compat

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
import visibility_character  # noqa: E402


def character(scene, tmp_path=None, frames=24):
    obj, rig = visibility_character.build(frames=frames)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj, rig


def bake_op(tmp_dir, **kwargs):
    args = dict(frame_start=1, frame_end=24, frame_step=2, rays=64, lobes=2,
                filepath=os.path.join(str(tmp_dir), "model.pzh"))
    args.update(kwargs)
    return bpy.ops.penumbra.bake_visibility(**args)


def attribute(obj, name, width):
    data = obj.data.attributes[name].data
    out = np.empty(len(data) * width, dtype=np.float32)
    data.foreach_get("color" if width == 4 else "value", out)
    return out.reshape(-1, width) if width > 1 else out


def uniform_world(scene, rgb=(1.0, 1.0, 1.0), strength=1.0):
    world = bpy.data.worlds.new("Uniform")
    background = compat.ensure_nodes(world).nodes["Background"]
    background.inputs["Color"].default_value = (*rgb, 1.0)
    background.inputs["Strength"].default_value = strength
    scene.world = world
    return world


def front_camera(scene):
    """The scene's camera, 7 m in front of the character at chest height,
    looking at it."""
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, -7.0, 1.4)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
    return camera
