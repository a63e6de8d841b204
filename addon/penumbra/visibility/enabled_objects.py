"""The scene's mesh objects with Shade from Model on, found once and kept
between frames. The CPU run time and the GPU preview look for them at every
frame change and depsgraph update; walking every object of the scene each
time grew with the scene, not the characters (300 empties added 0.35 ms a
frame to the GPU preview's 0.6 in bpy 5.2).

Kept per scene with the scene's object count. Looked up again when that
count changes (an object added, duplicated, appended or removed), when a kept
object is gone or no longer enabled, and after forget(): `enabled` changed
(its update callback), a file was loaded, an undo or redo (which switch
objects on without a callback). A keyframed or driven `enabled` switching an
object on is seen only at the next of these."""

_kept = {}  # scene pointer -> (object count, names of its enabled objects)


def _enabled(obj):
    settings = getattr(obj, "penumbra_visibility", None)
    return settings is not None and settings.enabled and obj.type == "MESH"


def in_scene(scene):
    """[Object] of `scene` with Shade from Model on, in the scene's order."""
    objects = scene.objects
    count = len(objects)
    kept = _kept.get(scene.as_pointer())
    if kept is not None and kept[0] == count:
        found = [objects.get(name) for name in kept[1]]
        if all(obj is not None and _enabled(obj) for obj in found):
            return found
    found = [obj for obj in objects if _enabled(obj)]
    _kept[scene.as_pointer()] = (count, [obj.name for obj in found])
    return found


def forget():
    _kept.clear()
