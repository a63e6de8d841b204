"""The rig in the .blend: one collection holding an empty (the rig's root)
and one sun per light index, created once and updated on every rebuild.

A sun shines along its local -Z axis, so its rotation takes +Z to the
direction towards the light. Colour is rgb / max(rgb); the sun's angle and
its strength per unit of the light's ∫L dω are the core's
(core/lights/sun_irradiance.hpp, through _penumbra.lights.sun_angle and
sun_strength_per_flux), the same rule the irradiance fit assumes: the angle
is 2·√2 times the region's RMS angular radius, 0 when tiny (Cycles renders
a sun of angle ~1e-10 rad or less black), and the strength depends on how
this Blender's Cycles draws a sun (docs/lights.md "Suns in Cycles"), which
the core's sun_model_for_blender picks from bpy.app.version."""

import collections
import math

import bpy
import mathutils
import numpy as np

from .. import native
from . import rig_index

INDEX_KEY = "penumbra_light_index"
ROOT_KEY = "penumbra_light_rig_root"
COLLECTION_NAME = "Penumbra Light Rig"
LINEAR = 1  # FCurve keyframe interpolation enum value of 'LINEAR'


def sun_model(version=None, eevee=False, shadow=True):
    """The _penumbra.lights.SunModel this Blender's (or `version`'s) Cycles, or
    its EEVEE when `eevee`, draws a sun with (casting a shadow or not)."""
    major, minor = tuple(bpy.app.version if version is None else version)[:2]
    return native.require().lights.sun_model_for_renderer(major, minor, eevee, shadow)


def targets_eevee(target_renderer, scene):
    """Whether a rig for `target_renderer` (settings.TARGET_RENDERER_ITEMS) is
    drawn by EEVEE: SCENE follows the scene's engine (BLENDER_EEVEE, or
    BLENDER_EEVEE_NEXT in 4.2-4.5)."""
    if target_renderer == "SCENE":
        return scene.render.engine.startswith("BLENDER_EEVEE")
    return target_renderer == "EEVEE"


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
    if bpy.app.version >= (5, 0, 0):
        # Blender 5.0 removed the legacy Action.fcurves (4.5 -> 5.0 API change
        # log, bpy.types.Action): curves live only in slot channel bags, so an
        # ID that has an action but no slot has no F-curve.
        return None
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


# EEVEE Legacy's cascaded shadow maps go to at most this many suns
# (MAX_SHADOW_CASCADE in 3.x's eevee_private.h): the first suns it meets get
# them, the others light as if unshadowed; limit_shadows gives shadows to
# this many strongest suns.
LEGACY_SHADOWED_SUNS = 8

# A sun casts an umbra behind an occluder only where the occluder looks wider
# than the sun. Seen from a receiver one occluder-width below it, the
# occluder spans 2·atan(1/2) ≈ 53.13°: a wider sun's shadow is penumbra from
# that distance on, a darkening without a shape, so a shadow budget goes to
# suns at most this wide (docs/lights.md, "Shadow budget").
UMBRA_ANGLE = 2.0 * math.atan(0.5)

# count: the suns that may cast a shadow (0: every sun); sharp_only: chosen
# only among suns no wider than UMBRA_ANGLE; renderer_cap: the count is what
# the renderer can draw, not the user's budget, so a rig of no more suns
# than that shadows them all.
ShadowChoice = collections.namedtuple("ShadowChoice", "count sharp_only renderer_cap", defaults=(False,))


def legacy_eevee(eevee):
    """Whether a rig drawn by EEVEE (`eevee`) is drawn by EEVEE Legacy (before 4.2)."""
    return eevee and bpy.app.version < (4, 2, 0)


def shadow_choice(shadow_budget, limit_shadows, legacy=False):
    """The suns that cast shadows: `shadow_budget` > 0, that many of the
    strongest sharp suns; else limit_shadows, the LEGACY_SHADOWED_SUNS
    strongest of any width (its contract since 0.2); else every sun, except
    for EEVEE Legacy (`legacy`), which would shadow the first
    LEGACY_SHADOWED_SUNS it meets and no more: the rig picks them as a
    budget of that many would (docs/lights.md, "Shadow budget")."""
    if shadow_budget > 0:
        return ShadowChoice(int(shadow_budget), True)
    if limit_shadows:
        return ShadowChoice(LEGACY_SHADOWED_SUNS, False)
    if legacy:
        return ShadowChoice(LEGACY_SHADOWED_SUNS, True, renderer_cap=True)
    return ShadowChoice(0, False)


def shadowed_indices(mean_power, limit=LEGACY_SHADOWED_SUNS, angle=None):
    """Indices of the `limit` strongest lights by mean power (ties: lower
    index); with `angle` (radians per light), only among those no wider than
    UMBRA_ANGLE."""
    order = np.argsort(-np.asarray(mean_power, dtype=float), kind="stable")
    if angle is not None:
        order = [k for k in order if angle[k] <= UMBRA_ANGLE]
    return set(int(k) for k in order[:limit])


class _Values:
    """Everything the suns get, computed and checked before the .blend is touched."""

    def __init__(self, rig, frame_start, shadows, eevee=False):
        self.slots = int(rig["slots"])
        rgb = np.asarray(rig["rgb"], dtype=float)              # (F, S, 3)
        directions = np.asarray(rig["directions"], dtype=float)
        spread = np.asarray(rig["spread"], dtype=float)
        power = np.asarray(rig["power"], dtype=float)
        if self.slots < 1 or rgb.ndim != 3 or rgb.shape[1:] != (self.slots, 3) or rgb.shape[0] < 1:
            raise ValueError(f"the rig has no lights to write (rgb {rgb.shape}, {self.slots} slots)")
        if directions.shape != rgb.shape or spread.shape != rgb.shape[:2] or power.shape != rgb.shape[:2]:
            raise ValueError("the rig's arrays do not agree in shape")
        for name, a in (("rgb", rgb), ("directions", directions), ("spread", spread), ("power", power)):
            if not np.all(np.isfinite(a)):
                raise ValueError(f"the rig's {name} has non-finite values; nothing was written")
        self.n_frames = rgb.shape[0]
        peak = rgb.max(axis=2)                                 # (F, S)
        self.colour = np.where(peak[..., None] > 0, rgb / np.maximum(peak[..., None], 1e-30), 1.0)
        lights = native.require().lights
        self.angle = lights.sun_angle(spread)
        # A sun's width over the shot, as its power weighs the frames.
        width = (self.angle * power).sum(axis=0) / np.maximum(power.sum(axis=0), 1e-30)
        chosen = shadowed_indices(power.mean(axis=0), shadows.count, width if shadows.sharp_only else None)
        every = shadows.count == 0 or (shadows.renderer_cap and self.slots <= shadows.count)
        self.shadow = [every or k in chosen for k in range(self.slots)]
        # EEVEE Legacy gives a sun another power per strength than Cycles does;
        # EEVEE Next the same, shadowed or not (docs/lights.md, "Suns in EEVEE").
        models = [sun_model(eevee=eevee, shadow=self.shadow[k]) for k in range(self.slots)]
        per_flux = np.stack([lights.sun_strength_per_flux(self.angle[:, k], models[k]) for k in range(self.slots)],
                            axis=1)
        self.strength = peak * per_flux
        self.quats = [sun_quaternions(directions[:, k]) for k in range(self.slots)]
        self.frames = np.arange(self.n_frames, dtype=float) + frame_start


def _write_sun(ob, k, v):
    """Sets and keys sun `k` from the precomputed values `v`."""
    light = ob.data
    light.use_shadow = v.shadow[k]
    quats = v.quats[k]
    ob.animation_data_clear()
    light.animation_data_clear()
    ob.rotation_mode = "QUATERNION"
    ob.rotation_quaternion = quats[0]
    light.energy = float(v.strength[0, k])
    light.color = v.colour[0, k]
    light.angle = float(v.angle[0, k])
    if v.n_frames > 1:
        for i in range(4):
            _set_keys(ob, "rotation_quaternion", i, v.frames, quats[:, i])
        _set_keys(light, "energy", None, v.frames, v.strength[:, k])
        for i in range(3):
            _set_keys(light, "color", i, v.frames, v.colour[:, k, i])
        _set_keys(light, "angle", None, v.frames, v.angle[:, k])


_KINDS = ("objects", "lights", "actions", "images", "collections")  # removal order


def _action(id_block):
    anim = id_block.animation_data
    return anim.action if anim is not None else None


class _Snapshot:
    """What write_rig may change, to put back if it fails half-way."""

    def __init__(self, scene, settings):
        self.scene = scene
        self.settings = settings
        self.collection = settings.collection
        self.linked = self.collection is not None and self.collection.name in scene.collection.children
        self.ids = {kind: set(getattr(bpy.data, kind)[:]) for kind in _KINDS}
        self.objects = []
        if self.collection is not None:
            for ob in self.collection.objects:
                entry = {"ob": ob, "parent": ob.parent, "rotation_mode": ob.rotation_mode,
                         "rotation_quaternion": tuple(ob.rotation_quaternion),
                         "rotation_euler": tuple(ob.rotation_euler), "action": _action(ob)}
                if ob.type == "LIGHT" and ob.data is not None:
                    light = ob.data
                    entry["light"] = {"energy": light.energy, "color": tuple(light.color),
                                      "use_shadow": light.use_shadow,
                                      "angle": getattr(light, "angle", None), "action": _action(light)}
                self.objects.append(entry)

    @staticmethod
    def _set_action(id_block, action):
        if action is None:
            id_block.animation_data_clear()
        else:
            id_block.animation_data_create().action = action

    def restore(self):
        """Removes what was created and puts back what was changed."""
        for entry in self.objects:
            ob = entry["ob"]
            ob.parent = entry["parent"]
            ob.rotation_mode = entry["rotation_mode"]
            ob.rotation_quaternion = entry["rotation_quaternion"]
            ob.rotation_euler = entry["rotation_euler"]
            self._set_action(ob, entry["action"])
            if "light" in entry:
                light, saved = ob.data, entry["light"]
                light.energy = saved["energy"]
                light.color = saved["color"]
                light.use_shadow = saved["use_shadow"]
                if saved["angle"] is not None:
                    light.angle = saved["angle"]
                self._set_action(light, saved["action"])
        for kind in _KINDS:
            data = getattr(bpy.data, kind)
            for block in [b for b in data if b not in self.ids[kind]]:
                data.remove(block)
        self.settings.collection = self.collection
        if self.collection is not None:
            children = self.scene.collection.children
            if self.linked and self.collection.name not in children:
                children.link(self.collection)
            elif not self.linked and self.collection.name in children:
                children.unlink(self.collection)


def write_rig(scene, settings, rig, frame_start, limit_shadows, eevee=False, shadow_budget=0):
    """Creates or updates the collection, root and suns from `rig` (the dict of
    _penumbra.lights.RigBuilder.finish) with keyframes from frame_start;
    the suns that cast a shadow are shadow_choice's: the `shadow_budget`
    strongest sharp suns, or with limit_shadows the 8 strongest, else all
    (for EEVEE Legacy, the 8 strongest sharp ones).

    All or nothing: the values are computed and checked first; if anything
    fails while the .blend is being changed, what was created is removed and
    what was changed is put back before the error propagates."""
    values = _Values(rig, frame_start, shadow_choice(shadow_budget, limit_shadows, legacy_eevee(eevee)), eevee)
    snapshot = _Snapshot(scene, settings)
    try:
        coll = settings.collection
        if coll is None or coll.name not in bpy.data.collections:
            coll = bpy.data.collections.new(COLLECTION_NAME)
            settings.collection = coll
        if coll.name not in scene.collection.children:
            scene.collection.children.link(coll)
        root = next((ob for ob in coll.objects if ob.get(ROOT_KEY)), None)
        if root is None:
            root = bpy.data.objects.new("Penumbra Light Rig Root", None)
            root[ROOT_KEY] = True
            root.empty_display_type = "SPHERE"
            coll.objects.link(root)
        existing, extra = {}, []
        for ob in coll.objects:
            if INDEX_KEY in ob:
                k = rig_index.light_index(ob[INDEX_KEY])
                if k is None or k >= values.slots or k in existing or ob.type != "LIGHT":
                    extra.append(ob)
                else:
                    existing[k] = ob
        for k in range(values.slots):
            ob = existing.get(k)
            if ob is None:
                data = bpy.data.lights.new(f"Penumbra Sun {k:03d}", "SUN")
                ob = bpy.data.objects.new(f"Penumbra Sun {k:03d}", data)
                ob[INDEX_KEY] = k
                coll.objects.link(ob)
            ob.parent = root
            _write_sun(ob, k, values)
    except BaseException:
        snapshot.restore()
        raise
    return RigWrite(coll, snapshot, extra)


class RigWrite:
    """A written rig not yet final: commit() removes the suns the new rig does
    not use; rollback() puts the .blend back as it was before write_rig."""

    def __init__(self, collection, snapshot, extra):
        self.collection = collection
        self._snapshot = snapshot
        self._extra = extra

    def commit(self):
        for ob in self._extra:
            data = ob.data
            bpy.data.objects.remove(ob, do_unlink=True)
            if data is not None and data.users == 0:
                bpy.data.lights.remove(data)
        self._extra = []

    def rollback(self):
        self._snapshot.restore()


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
