"""The scene of the light-rig benchmarks' shadowed comparisons
(bench/blender_scripts/lights_shadowed_render.py in Cycles,
lights_eevee_render.py in EEVEE): a sphere on a plane under Blender's
sunrise.exr, whose sun casts a visible shadow, 128x96, black film. Inside
Blender, with examples/scenes on sys.path (paths.use_addon)."""

import os

import bpy

import light_rig_scene


def sunrise_sphere_scene(cycles_samples, eevee_samples=None):
    """The scene on a factory-settings file, Cycles on the CPU without
    denoising; returns (scene, the World's Background Strength input)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    tree = world.node_tree
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world",
                                                  "sunrise.exr"))
    tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    light_rig_scene.sphere_on_plane(scene)
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 128, 96, 100
    scene.render.film_transparent = True  # black background: only the lit scene is compared
    scene.view_settings.view_transform = "Standard"
    # The factory file's engine is EEVEE from 4.2 on (lost in 0fe84f2: the
    # shadowed comparison rendered EEVEE since).
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", cycles_samples, False
    if eevee_samples is not None:
        scene.eevee.taa_render_samples = eevee_samples
    return scene, tree.nodes["Background"].inputs["Strength"]
