"""The EEVEE check of issue #26 item 6, shared by the 3.4 window test and
the bpy 5.2 test: a plane under Blender's sunrise.exr, lit by its World in
Cycles (the reference) and by the default rig fitted for EEVEE, drawn by
EEVEE; the rig passes when its mean luminance is within TOLERANCE of the
reference's. A lone plane has no bounce light, which EEVEE's lamps do not
give, so the check sees only how EEVEE draws the suns."""

import os

import bpy

from bench.helpers.lights_eevee import eevee_engine, mean_luminance, plane_seen_from_above  # noqa: F401

TOLERANCE = 0.04


def within_tolerance(mean, reference):
    """The check: the rig's mean luminance within TOLERANCE of the reference's."""
    return abs(mean / reference - 1.0) <= TOLERANCE


def plane_under_sunrise(scene):
    """A 20 m plane seen from above through an orthographic camera, 16×12 px,
    the World lit by sunrise.exr; returns the Background's Strength input."""
    from lights_scenes import ensure_nodes
    world = bpy.data.worlds.new("Sunrise")
    scene.world = world
    tree = ensure_nodes(world)
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world",
                                                  "sunrise.exr"))
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    plane_seen_from_above(scene, 16, 12)
    scene.render.film_transparent = True
    scene.eevee.taa_render_samples = 8
    return tree.nodes["Background"].inputs["Strength"]


def rig_and_reference_means(scene, folder, count=16):
    """(the EEVEE render's mean lit by the default rig built for the scene's
    engine, EEVEE; the Cycles World render's mean)."""
    strength = plane_under_sunrise(scene)
    reference = mean_luminance(scene, "CYCLES", folder)
    scene.render.engine = eevee_engine()
    r = bpy.ops.penumbra.build_light_rig(filepath="", count=count, json_path=os.path.join(folder, "rig.json"))
    assert r == {"FINISHED"}, r
    strength.default_value = 0.0
    return mean_luminance(scene, eevee_engine(), folder), reference


def scale_rig(scene, factor):
    for ob in scene.penumbra.light_rig.collection.objects:
        if ob.type == "LIGHT":
            ob.data.energy *= factor
