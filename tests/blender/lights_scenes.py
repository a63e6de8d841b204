"""Maps, Worlds and rig snapshots shared by the light-rig tests; the maps
come from the test-video maker (bench/helpers/test_videos.py), whose
`directions`, `solid_angles` and `write_map` the tests import from here."""

import os

import bpy

from bench.helpers.test_videos import directions, solid_angles, sun_disc, write_map  # noqa: F401  (the tests' names)


def core_module():
    from penumbra import native
    return native.require()


def ensure_nodes(id_block):
    """The node tree of a material or world (Use Nodes is switched on before
    Blender 5.0, which made both always node-based; see penumbra/compat.py)."""
    from penumbra import compat
    return compat.ensure_nodes(id_block)


def sky_and_sun(h=64, w=128, sun=(0.4, -0.3, 0.8), radius=0.15, sun_radiance=40.0, sky=0.3):
    """A bluish uniform sky and a sun disc (test_videos.sun_disc)."""
    return sun_disc(h, w, sun, radius, sun_radiance, (sky, sky, 1.5 * sky))


def world_with(scene, path, rotation_z=None):
    world = bpy.data.worlds.new("Test World")
    scene.world = world
    nt = ensure_nodes(world)
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


def rig_state(scene, json_path):
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


def window_addon():
    """The add-on registered for a window test (blender_window.py: pytest on a
    worker thread, bpy on the main one); yields the module, then unregisters."""
    from blender_window import on_main

    def register():
        import penumbra
        penumbra.register()
        return penumbra
    penumbra = on_main(register)
    yield penumbra
    on_main(penumbra.unregister)
