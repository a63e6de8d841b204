"""The objects the CPU run time and the GPU preview shade, kept between
frames (addon/penumbra/visibility/enabled_objects.py): each way the set can
change must show at the next look, in every Blender."""

import bpy

from penumbra.visibility import enabled_objects


def mesh_object(scene, name, enabled):
    obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    scene.collection.objects.link(obj)
    obj.penumbra_visibility.enabled = enabled
    return obj


def names(scene):
    return [obj.name for obj in enabled_objects.in_scene(scene)]


def test_the_enabled_set_follows_every_change_of_the_scene(addon):
    scene = bpy.context.scene
    first = mesh_object(scene, "First", True)
    mesh_object(scene, "Off", False)
    empty = bpy.data.objects.new("Empty", None)
    scene.collection.objects.link(empty)
    assert names(scene) == ["First"]

    copy = first.copy()                       # a duplicate keeps `enabled`, and no callback runs
    scene.collection.objects.link(copy)
    assert sorted(names(scene)) == sorted(["First", copy.name])

    first.name = "Renamed"                    # same count, a kept name gone
    assert sorted(names(scene)) == sorted(["Renamed", copy.name])

    bpy.data.objects["Off"].penumbra_visibility.enabled = True    # the update callback
    assert sorted(names(scene)) == sorted(["Renamed", copy.name, "Off"])

    copy.penumbra_visibility.enabled = False
    assert sorted(names(scene)) == ["Off", "Renamed"]

    bpy.data.objects.remove(bpy.data.objects["Off"])
    assert names(scene) == ["Renamed"]

    scene.collection.objects.unlink(first)   # out of the scene, still in the file
    assert names(scene) == []


def test_an_object_switched_on_without_a_callback_shows_after_forget(addon):
    """Undo and load switch objects on without the update callback: their
    handlers call forget()."""
    scene = bpy.context.scene
    obj = mesh_object(scene, "Quiet", False)
    assert names(scene) == []
    obj.penumbra_visibility["enabled"] = True   # an ID property write: no callback, as an undo
    enabled_objects.forget()
    assert names(scene) == ["Quiet"]


def test_each_scene_has_its_own_set(addon):
    scene = bpy.context.scene
    other = bpy.data.scenes.new("Other")
    mesh_object(scene, "Here", True)
    mesh_object(other, "There", True)
    assert names(scene) == ["Here"]
    assert names(other) == ["There"]
