"""Maps, Worlds and rig snapshots shared by the light-rig tests."""

import math
import os

import bpy
import numpy as np


def _core():
    from penumbra import native
    return native.require()


def _ensure_nodes(id_block):
    """The node tree of a material or world (Use Nodes is switched on before
    Blender 5.0, which made both always node-based; see penumbra/compat.py)."""
    from penumbra import compat
    return compat.ensure_nodes(id_block)


def _write_map(path, image):
    _core().image.write_exr(path, image.astype(np.float32), half=False, colorspace="Linear")
    return path


def _directions(h, w):
    theta = (np.arange(h) + 0.5) / h * math.pi
    phi = math.pi - 2 * math.pi * (np.arange(w) + 0.5) / w
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def _solid_angles(h, w):
    e = np.arange(h + 1) / h * math.pi
    return (2 * math.pi / w) * (np.cos(e[:-1]) - np.cos(e[1:]))


def _sky_and_sun(h=64, w=128, sun=(0.4, -0.3, 0.8), radius=0.15, sun_radiance=40.0, sky=0.3):
    d = _directions(h, w)
    s = np.asarray(sun) / np.linalg.norm(sun)
    img = np.full((h, w, 3), sky, np.float32)
    img[..., 2] *= 1.5  # a bluish sky
    img[d @ s >= math.cos(radius)] = sun_radiance
    return img


def _world_with(scene, path, rotation_z=None):
    world = bpy.data.worlds.new("Test World")
    scene.world = world
    nt = _ensure_nodes(world)
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path)
    nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])
    if rotation_z is not None:
        mapping = nt.nodes.new("ShaderNodeMapping")
        coords = nt.nodes.new("ShaderNodeTexCoord")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, rotation_z)
        nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    return world


def _rig_state(scene, json_path):
    """Everything a failed rebuild must leave as it was."""
    from penumbra.lights.rig_objects import fcurve
    state = {kind: sorted(b.name for b in getattr(bpy.data, kind))
             for kind in ("collections", "objects", "lights", "actions")}
    coll = scene.penumbra.light_rig.collection
    state["setting"] = coll.name if coll is not None else None
    state["linked"] = sorted(c.name for c in scene.collection.children)
    suns = {}
    if coll is not None:
        for ob in coll.objects:
            entry = {"parent": ob.parent.name if ob.parent else None, "rot": tuple(round(v, 6) for v in ob.rotation_quaternion)}
            if ob.type == "LIGHT":
                entry["light"] = (ob.data.name, round(ob.data.energy, 6), tuple(round(v, 6) for v in ob.data.color),
                                  round(ob.data.angle, 6), ob.data.use_shadow)
                keys = []
                for block, path, index in ((ob, "rotation_quaternion", 0), (ob, "rotation_quaternion", 3),
                                           (ob.data, "energy", 0), (ob.data, "color", 2)):
                    fc = fcurve(block, path, index)
                    keys.append(None if fc is None else [tuple(round(v, 6) for v in k.co) for k in fc.keyframe_points])
                entry["keys"] = keys
            suns[ob.name] = entry
    state["suns"] = suns
    state["json"] = open(json_path).read() if os.path.exists(json_path) else None
    return state
