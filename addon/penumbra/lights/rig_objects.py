"""The rig in the .blend: one collection holding an empty (the rig's root)
and one sun per light index, created once and updated on every rebuild.

A sun shines along its local -Z axis, so its rotation takes +Z to the
direction towards the light. Strength (W/m², irradiance on a surface facing
the sun) and colour are split from the light's RGB irradiance as
strength = max(rgb), colour = rgb / strength. The sun's angle (angular
diameter) is 2·√2 times the RMS angular radius of the region or cluster the
light stands for (a uniform disc of radius ρ has RMS radius ρ/√2)."""

import math

import bpy
import mathutils
import numpy as np

INDEX_KEY = "penumbra_light_index"
ROOT_KEY = "penumbra_light_rig_root"
COLLECTION_NAME = "Penumbra Light Rig"
LINEAR = 1  # FCurve keyframe interpolation enum value of 'LINEAR'


def _collection(scene, settings):
    coll = settings.collection
    if coll is None or coll.name not in bpy.data.collections:
        coll = bpy.data.collections.new(COLLECTION_NAME)
        settings.collection = coll
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def _root(coll):
    for ob in coll.objects:
        if ob.get(ROOT_KEY):
            return ob
    root = bpy.data.objects.new("Penumbra Light Rig Root", None)
    root[ROOT_KEY] = True
    root.empty_display_type = "SPHERE"
    coll.objects.link(root)
    return root


def _suns(coll, root, slots):
    existing = {}
    for ob in list(coll.objects):
        if INDEX_KEY in ob:
            k = int(ob[INDEX_KEY])
            if k >= slots or k in existing or ob.type != "LIGHT":
                data = ob.data
                bpy.data.objects.remove(ob, do_unlink=True)
                if data is not None and data.users == 0:
                    bpy.data.lights.remove(data)
            else:
                existing[k] = ob
    suns = []
    for k in range(slots):
        ob = existing.get(k)
        if ob is None:
            data = bpy.data.lights.new(f"Penumbra Sun {k:03d}", "SUN")
            ob = bpy.data.objects.new(f"Penumbra Sun {k:03d}", data)
            ob[INDEX_KEY] = k
            coll.objects.link(ob)
        ob.parent = root
        ob.rotation_mode = "QUATERNION"
        suns.append(ob)
    return suns


def sun_quaternions(directions):
    """(F, 4) quaternions (w, x, y, z) taking +Z to each direction, with signs
    chosen so consecutive frames never flip (q and -q are the same rotation)."""
    z = mathutils.Vector((0.0, 0.0, 1.0))
    out = np.empty((len(directions), 4))
    previous = None
    for t, d in enumerate(directions):
        q = z.rotation_difference(mathutils.Vector(tuple(float(v) for v in d)))
        q = np.array([q.w, q.x, q.y, q.z])
        if previous is not None and np.dot(q, previous) < 0.0:
            q = -q
        out[t] = q
        previous = q
    return out


def fcurve(id_block, path, index=0):
    """The F-curve animating `path`[index] of an ID. Blender 4.4+ keeps each
    ID's curves in its action slot's channel bag (object and light data may
    share one action), older versions in action.fcurves."""
    anim = id_block.animation_data
    if anim is None or anim.action is None:
        return None
    slot = getattr(anim, "action_slot", None)
    if slot is not None:
        from bpy_extras import anim_utils
        if hasattr(anim_utils, "action_get_channelbag_for_slot"):
            bag = anim_utils.action_get_channelbag_for_slot(anim.action, slot)
            return bag.fcurves.find(path, index=index) if bag is not None else None
    return anim.action.fcurves.find(path, index=index)


def _set_keys(id_block, path, index, frames, values):
    """Linear keys of one channel; index None for a scalar property."""
    id_block.keyframe_insert(path, index=-1 if index is None else index, frame=float(frames[0]))
    fc = fcurve(id_block, path, 0 if index is None else index)
    fc.keyframe_points.add(len(frames) - 1)
    co = np.empty(2 * len(frames))
    co[0::2] = frames
    co[1::2] = values
    fc.keyframe_points.foreach_set("co", co)
    fc.keyframe_points.foreach_set("interpolation", [LINEAR] * len(frames))
    fc.update()


def write_rig(scene, settings, rig, frame_start, limit_shadows):
    """Creates or updates the collection, root and suns from `rig` (the dict of
    _penumbra.LightRigBuilder.finish) with keyframes from frame_start."""
    coll = _collection(scene, settings)
    root = _root(coll)
    slots = int(rig["slots"])
    suns = _suns(coll, root, slots)
    rgb = np.asarray(rig["rgb"])             # (F, S, 3)
    directions = np.asarray(rig["directions"])
    spread = np.asarray(rig["spread"])
    n_frames = rgb.shape[0]
    strength = rgb.max(axis=2)                # (F, S)
    colour = np.where(strength[..., None] > 0, rgb / np.maximum(strength[..., None], 1e-30), 1.0)
    angle = np.clip(2.0 * math.sqrt(2.0) * spread, 0.0, math.pi)
    mean_power = np.asarray(rig["power"]).mean(axis=0)
    strongest = set(np.argsort(-mean_power)[:8].tolist())
    frames = np.arange(n_frames, dtype=float) + frame_start
    for k, ob in enumerate(suns):
        light = ob.data
        light.use_shadow = (k in strongest) if limit_shadows else True
        quats = sun_quaternions(directions[:, k])
        ob.animation_data_clear()
        light.animation_data_clear()
        ob.rotation_quaternion = quats[0]
        light.energy = float(strength[0, k])
        light.color = colour[0, k]
        light.angle = float(angle[0, k])
        if n_frames > 1:
            for i in range(4):
                _set_keys(ob, "rotation_quaternion", i, frames, quats[:, i])
            _set_keys(light, "energy", None, frames, strength[:, k])
            for i in range(3):
                _set_keys(light, "color", i, frames, colour[:, k, i])
            _set_keys(light, "angle", None, frames, angle[:, k])
    return coll


def store_preview(name, pixels):
    """Stores a (H, W, 3) float picture (row 0 at the top) as a Blender image."""
    h, w = pixels.shape[:2]
    image = bpy.data.images.get(name)
    if image is None or tuple(image.size) != (w, h):
        if image is not None:
            bpy.data.images.remove(image)
        image = bpy.data.images.new(name, w, h, float_buffer=True)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = pixels[::-1]  # Blender rows are bottom-up
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image
