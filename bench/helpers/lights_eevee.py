"""What the EEVEE light-rig measurements share, inside a Blender: EEVEE's
engine id in this Blender, a render's mean luminance and the maps a scene is
lit by (issue #26: bench/blender_scripts/lights_single_sun.py,
lights_eevee_render.py and the make-test check
tests/blender/lights_eevee_check.py)."""

import os

import bpy
import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def eevee_engine():
    """EEVEE's engine id: BLENDER_EEVEE_NEXT in 4.2-4.5, BLENDER_EEVEE before (Legacy) and from 5.0 (Next)."""
    return "BLENDER_EEVEE_NEXT" if (4, 2, 0) <= bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"


def plane_seen_from_above(scene, width, height):
    """A 20 m plane at z = 0 seen from 5 m above through an orthographic
    camera 4 m wide, width × height px, Standard view, Cycles on the CPU
    without denoising."""
    from bench.helpers.paths import use_addon
    use_addon()
    import light_rig_scene
    mesh = bpy.data.meshes.new("Plane")
    mesh.from_pydata([(-10, -10, 0), (10, -10, 0), (10, 10, 0), (-10, 10, 0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(light_rig_scene.default_surface())  # the surface Cycles and EEVEE both draw
    scene.collection.objects.link(bpy.data.objects.new("Plane", mesh))
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type, cam.data.ortho_scale = "ORTHO", 4.0
    cam.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 64, False


def mean_luminance(scene, engine, folder):
    """Renders the scene with `engine` and returns the mean Rec.709 luminance
    of its linear result (saved as a 32-bit EXR in `folder`)."""
    scene.render.engine = engine
    bpy.ops.render.render()
    path = os.path.join(folder, "render.exr")
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    bpy.data.images["Render Result"].save_render(path)
    image = bpy.data.images.load(path)
    pixels = np.array(image.pixels[:], dtype=np.float64).reshape(-1, 4)
    bpy.data.images.remove(image)
    return float(np.mean(pixels[:, :3] @ LUMINANCE))


def light_by_map(scene, path):
    """Points the World's Environment Texture at the map in `path` (the
    sunrise scene of bench/helpers/lights_render_scene.py, another map)."""
    env = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path, check_existing=True)


def bundled_map(name):
    """Path of this Blender's bundled World `name`.exr (3.4's differ from 4.5's and 5.2's)."""
    return os.path.join(bpy.utils.system_resource("DATAFILES"), "studiolights", "world", name + ".exr")
