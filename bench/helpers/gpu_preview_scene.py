"""A character for the GPU preview's benchmark and window tests: the
procedural character (examples/scenes/visibility_character.py) at a given
size, under a uniform World of radiance 1, with a synthetic pose model in
the stored layout (order 4, 2 lobes by default, 1–3 joint blocks a vertex
of 3 directions each) saved beside it: made in a second instead of baked.
Runs inside Blender."""

import math
import os
import statistics
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
if os.path.join(ROOT, "examples", "scenes") not in sys.path:
    sys.path.append(os.path.join(ROOT, "examples", "scenes"))


def empty_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.armatures, bpy.data.actions,
                       bpy.data.cameras, bpy.data.worlds, bpy.data.images, bpy.data.materials):
        for block in list(collection):
            collection.remove(block)
    return bpy.context.scene


def synthetic_model(obj, armature, path, order=4, lobes=2, seed=27):
    from penumbra import native
    from penumbra.visibility import mesh_data
    core = native.require()
    rng = np.random.default_rng(seed)
    mesh = obj.data
    vertex_count = len(mesh.vertices)
    joints = [b.name for b in armature.data.bones if b.use_deform]
    directions = np.full(len(joints), 3)
    feature_offsets = np.concatenate([[0], np.cumsum(directions)])
    basis = np.zeros((feature_offsets[-1], 9), dtype=np.float32)
    for j in range(len(joints)):
        basis[feature_offsets[j]:feature_offsets[j + 1], :3] = np.eye(3)
    counts = rng.integers(1, 4, vertex_count)
    joint_offsets = np.concatenate([[0], np.cumsum(counts)])
    joint_index = np.concatenate([np.sort(rng.choice(len(joints), c, replace=False)) for c in counts])
    block_directions = np.full(len(joint_index), 3)
    d = lobes * (2 + order)
    bias = rng.normal(0.0, 0.3, (vertex_count, d)).astype(np.float32)
    weights = rng.normal(0.0, 0.1, int(block_directions.sum()) * d).astype(np.float32)
    model = core.visibility.PoseModel.from_blocks(order, lobes, joints, feature_offsets, basis.reshape(-1),
                                                  joint_offsets, joint_index, block_directions, bias.reshape(-1),
                                                  weights, topology_hash=mesh_data.topology_hash(mesh))
    model.save(path)
    return model


# Past this size the character is built at 1/16 of it and subdivided twice:
# bmesh builds 1M vertices in minutes, Catmull–Clark in seconds.
SUBDIVIDE_ABOVE = 300000


def subdivided(obj, levels):
    """Applies `levels` of Catmull–Clark to the rest shape (the Armature
    modifier held off); the vertex weights are interpolated."""
    armature = [m for m in obj.modifiers if m.type == "ARMATURE"]
    for m in armature:
        m.show_viewport = False
    subdivision = obj.modifiers.new("Subdivision", "SUBSURF")
    subdivision.levels = subdivision.render_levels = levels
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = bpy.data.meshes.new_from_object(obj.evaluated_get(depsgraph), preserve_all_data_layers=True,
                                           depsgraph=depsgraph)
    obj.modifiers.remove(subdivision)
    previous, obj.data = obj.data, mesh
    mesh.name = previous.name
    bpy.data.meshes.remove(previous)
    for m in armature:
        m.show_viewport = True


def character(vertices, tmp, name="PenumbraCharacter", empty=True, seed=27):
    """(scene, mesh object) with its model at tmp/<name>_<V>.pzh, Shade from
    Model on, live_update off."""
    import visibility_character
    from penumbra import compat
    scene = empty_scene() if empty else bpy.context.scene
    levels = 2 if vertices > SUBDIVIDE_ABOVE else 0
    base = vertices / 4 ** levels
    obj, armature = visibility_character.build(name=name, detail=max(1.0, math.sqrt(base / 890.0)), frames=24)
    if levels:
        subdivided(obj, levels)
    if scene.world is None or scene.world.name != "Uniform":
        world = bpy.data.worlds.new("Uniform")
        compat.ensure_nodes(world).nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        scene.world = world
    if scene.camera is None:
        camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
        scene.collection.objects.link(camera)
        scene.camera = camera
        camera.location = (1.5, -6.0, 2.0)
    path = os.path.join(tmp, f"{name}_{len(obj.data.vertices)}.pzh")
    synthetic_model(obj, armature, path, seed=seed)
    obj.penumbra_visibility.model_path = path
    obj.penumbra_visibility.enabled = True
    scene.penumbra.visibility.live_update = False
    return scene, obj


def _look_at_character(width, height):
    """A view-projection matrix framing the character (as the viewport would)."""
    from mathutils import Matrix, Vector
    eye, target = Vector((2.0, -5.0, 2.0)), Vector((0.0, 0.0, 1.3))
    forward = (target - eye).normalized()
    right = forward.cross(Vector((0.0, 0.0, 1.0))).normalized()
    up = right.cross(forward)
    view = Matrix((tuple(right) + (-right.dot(eye),), tuple(up) + (-up.dot(eye),),
                   tuple(-forward) + (forward.dot(eye),), (0.0, 0.0, 0.0, 1.0)))
    f, near, far, aspect = 1.0 / math.tan(math.radians(20.0)), 0.1, 100.0, width / height
    projection = Matrix(((f / aspect, 0, 0, 0), (0, f, 0, 0),
                         (0, 0, (far + near) / (near - far), 2 * far * near / (near - far)), (0, 0, -1, 0)))
    return projection @ view


def gpu_draw_seconds(draw, width=1280, height=720, repeats=5):
    """draw(view_projection) into a viewport-sized buffer with depth, synchronized by a
    readback, framing the character: (median seconds, pixels covered)."""
    import gpu
    offscreen = gpu.types.GPUOffScreen(width, height)
    view_projection = _look_at_character(width, height)
    pixel = gpu.types.Buffer("FLOAT", 4)
    samples, covered = [], 0
    try:
        with offscreen.bind():
            framebuffer = gpu.state.active_framebuffer_get()
            for k in range(repeats + 1):
                t = time.perf_counter()
                framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(True)
                draw(view_projection)
                framebuffer.read_color(width // 2, height // 2, 1, 1, 4, 0, "FLOAT", data=pixel)
                if k:
                    samples.append(time.perf_counter() - t)
            image = gpu.types.Buffer("FLOAT", width * height * 4)
            framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT", data=image)
            covered = int(np.count_nonzero(np.asarray(image).reshape(-1, 4)[:, 3] > 0.0))
            gpu.state.depth_mask_set(False)
            gpu.state.depth_test_set("NONE")
    finally:
        offscreen.free()
    return statistics.median(samples), covered
