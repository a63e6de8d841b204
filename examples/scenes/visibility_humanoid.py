"""A realistic test character for the visibility baker: a humanoid skin around
the skeleton of a real motion capture, skinned with Blender's automatic weights.

What it is made of, all from what Blender and Debian ship (no downloads):
  * the motion: CMU motion capture 01_01 (subject 1, "playground, forward
    jumps, turn around"; public, see 01_nn.bvh.source.txt beside it) from
    Debian's `assimp-testmodels` package (/usr/share/assimp/models/BVH),
    cut to the frames asked for and resampled from 120 Hz to 24 fps, imported
    with Blender's bundled BVH importer (io_anim_bvh) at the CMU scale
    (1 unit = 0.056444 m). Its armature has 31 bones: legs with toes, a
    three-bone spine, neck, head, shoulders, arms, and hands with a finger
    base, fingers and a thumb; every one of them moves in the capture except
    the four zero-rotation hip and shoulder joints.
  * the skin: a skeleton of edges through the bones' rest positions with a
    radius at every node (pelvis, waist, chest, neck, head, limbs, a palm,
    four two-jointed fingers and a thumb per hand, feet), turned into a
    closed quad mesh by Blender's Skin modifier and smoothed by a Subdivision
    Surface modifier, both applied;
  * the weights: `parent_set(type='ARMATURE_AUTO')`, Blender's bone-heat
    automatic weights, so joints blend smoothly between bones.

`detail` sets the size: about 10k·detail vertices (0.25: 2.5k, 1: 10k,
10: 100k), by the subdivision level and the spacing of the skeleton's
nodes, and where those cannot reach the count, a Decimate (collapse) of the
next level. Automatic weights take longer on big meshes (bone heat solves
one system per bone).

Inside Blender (tests, benchmarks):
    import visibility_humanoid; mesh, armature = visibility_humanoid.build(detail=1, frames=48)
As a script, writes a .blend:
    blender -b --factory-startup --python examples/scenes/visibility_humanoid.py -- --out humanoid.blend [--detail 1] [--frames 48]
Runs in Debian's Blender 3.4 and the bpy 4.5 and 5.2 modules.
"""

import builtins
import math
import os
import sys
import tempfile

import bpy
from mathutils import Vector

BVH_FOLDER = "/usr/share/assimp/models/BVH"
DEFAULT_BVH = os.path.join(BVH_FOLDER, "01_01.bvh")
CMU_METRES_PER_UNIT = 0.056444   # the CMU conversion's unit: (1 / 0.45) inch
CAPTURE_FPS = 120.0
# Where the default window of 01_01 starts (capture frame): both arms swing,
# the legs bend, the hands open and close.
DEFAULT_START = 720


def bvh_path(path=None):
    """The BVH file to use: `path`, $PENUMBRA_HUMANOID_BVH, or CMU 01_01 from assimp-testmodels."""
    path = path or os.environ.get("PENUMBRA_HUMANOID_BVH") or DEFAULT_BVH
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no motion capture at {path}: install Debian's assimp-testmodels "
                                "(scripts/install_deps.sh does) or pass another CMU-skeleton BVH file")
    return path


def cut_motion(path, start, frames, fps):
    """Writes a BVH with `frames` frames from capture frame `start`, resampled
    to `fps` (nearest capture frame), to a temporary file; returns its path."""
    with open(path) as f:
        lines = f.read().splitlines()
    motion = next(i for i, line in enumerate(lines) if line.strip().upper() == "MOTION")
    frame_time = float(lines[motion + 2].split(":")[1])
    rows = [line for line in lines[motion + 3:] if line.strip()]
    step = 1.0 / (fps * frame_time)
    picked = []
    for k in range(frames):
        index = min(int(round(start + k * step)), len(rows) - 1)
        picked.append(rows[index])
    handle, out = tempfile.mkstemp(suffix=".bvh", prefix="penumbra_humanoid_")
    with os.fdopen(handle, "w") as f:
        f.write("\n".join(lines[:motion + 1]))
        f.write(f"\nFrames: {frames}\nFrame Time: {1.0 / fps:.7f}\n")
        f.write("\n".join(picked) + "\n")
    return out


def import_motion(path, frames, start, fps):
    """Imports the cut motion with io_anim_bvh; returns the armature object."""
    import addon_utils
    addon_utils.enable("io_anim_bvh", default_set=False)
    from io_anim_bvh import import_bvh
    cut = cut_motion(path, start, frames, fps)
    # Debian's Blender 3.4 runs Python 3.11, which removed open(..., 'rU'),
    # and its bundled importer still asks for it: give the module an `open`
    # that drops the 'U' (the importer of 4.x and 5.x has no 'rU').
    patched = "open" not in vars(import_bvh)
    if patched:
        import_bvh.open = lambda file, mode="r", *args, **kwargs: builtins.open(file, mode.replace("U", ""),
                                                                               *args, **kwargs)
    try:
        before = set(bpy.data.objects)
        result = bpy.ops.import_anim.bvh(filepath=cut, target="ARMATURE", global_scale=CMU_METRES_PER_UNIT,
                                         frame_start=1, use_fps_scale=False, rotate_mode="NATIVE",
                                         update_scene_fps=False, update_scene_duration=False)
    finally:
        if patched:
            del import_bvh.open
        os.remove(cut)
    if result != {"FINISHED"}:
        raise RuntimeError(f"the BVH importer failed on {path}: {result}")
    armature = next(o for o in bpy.data.objects if o not in before and o.type == "ARMATURE")
    return armature


class Skeleton:
    """Nodes (position, radius) and edges for the Skin modifier."""

    def __init__(self):
        self.points, self.radii, self.edges = [], [], []

    def node(self, position, radius):
        self.points.append(Vector(position))
        self.radii.append(radius)
        return len(self.points) - 1

    def chain(self, start, end_position, end_radius, segment, minimum=1):
        """Nodes from node `start` to a new end node, at most `segment` apart,
        radius interpolated; returns the end node."""
        a, b = self.points[start], Vector(end_position)
        count = max(minimum, int(math.ceil((b - a).length / segment)))
        r0 = self.radii[start]
        previous = start
        for k in range(1, count + 1):
            t = k / count
            current = self.node(a.lerp(b, t), r0 + (end_radius - r0) * t)
            self.edges.append((previous, current))
            previous = current
        return previous


def skeleton_of(armature, segment):
    """The skin's skeleton through the armature's rest pose (CMU bone names)."""
    bones = armature.data.bones
    world = armature.matrix_world

    def head(name):
        return world @ bones[name].head_local

    def tail(name):
        return world @ bones[name].tail_local

    s = Skeleton()
    up = (tail("Head") - head("Spine")).normalized()
    pelvis = s.node(head("Hips"), 0.1)
    waist = s.chain(pelvis, head("Spine"), 0.115, segment)
    belly = s.chain(waist, head("Spine1"), 0.12, segment)
    chest_height = head("LeftArm").dot(up) - 0.02
    chest_position = head("Spine1") + (chest_height - head("Spine1").dot(up)) * up
    chest = s.chain(belly, chest_position, 0.135, segment)
    neck_base = s.chain(chest, tail("Spine1") + 0.01 * up, 0.06, segment)
    neck = s.chain(neck_base, head("Head"), 0.05, segment)
    # Head: jaw, cranium, crown.
    jaw = s.chain(neck, head("Head") + 0.04 * up, 0.07, 1.0)
    cranium = s.chain(jaw, head("Head") + 0.10 * up, 0.09, 1.0)
    crown = s.chain(cranium, head("Head") + 0.15 * up, 0.075, 1.0)
    s.chain(crown, head("Head") + 0.19 * up, 0.03, 1.0)

    for side, hip, up_leg, leg, foot, toe, shoulder, arm, forearm, hand, fingers, thumb in (
            ("L", "LHipJoint", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "LeftShoulder", "LeftArm",
             "LeftForeArm", "LeftHand", "LFingers", "LThumb"),
            ("R", "RHipJoint", "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase", "RightShoulder", "RightArm",
             "RightForeArm", "RightHand", "RFingers", "RThumb")):
        # Leg: out sideways from the pelvis at its height (a T the Skin
        # modifier closes; straight to the hip joint it leaves a hole), then
        # the hip joint, knee, ankle, ball of the foot, toes.
        socket = head(up_leg) + (head("Hips") - head(up_leg)).dot(up) * up
        socket_node = s.chain(pelvis, socket, 0.09, segment)
        hip_node = s.chain(socket_node, head(up_leg), 0.085, segment)
        knee = s.chain(hip_node, head(leg), 0.052, segment)
        ankle = s.chain(knee, head(foot), 0.036, segment)
        ball = s.chain(ankle, head(toe), 0.034, segment)
        s.chain(ball, tail(toe) + 0.02 * (tail(toe) - head(toe)).normalized(), 0.025, segment)
        # Arm: from the chest to the shoulder, elbow, wrist.
        shoulder_node = s.chain(chest, head(arm), 0.05, segment)
        elbow = s.chain(shoulder_node, head(forearm), 0.038, segment)
        wrist_position = head(hand)
        wrist = s.chain(elbow, wrist_position, 0.028, segment)
        # Hand: a palm from the wrist to the knuckles (the finger bone's head),
        # four fingers of two segments spread across it, and a thumb.
        knuckles = head(fingers)
        along = (knuckles - wrist_position).normalized()
        thumb_direction = (tail(thumb) - head(thumb)).normalized()
        across = (thumb_direction - thumb_direction.dot(along) * along).normalized()  # towards the thumb
        palm = s.chain(wrist, wrist_position.lerp(knuckles, 0.55), 0.025, segment)
        for k, (length, offset) in enumerate(((0.050, 1.5), (0.055, 0.5), (0.052, -0.5), (0.042, -1.5))):
            base = knuckles + 0.017 * offset * across - 0.004 * along * abs(offset)
            knuckle = s.chain(palm, base, 0.0095, 1.0)
            direction = (along + 0.07 * offset * across).normalized()
            middle = s.chain(knuckle, base + 0.5 * length * direction, 0.0085, 1.0)
            s.chain(middle, base + length * direction, 0.007, 1.0)
        thumb_root = s.chain(wrist, wrist_position + 0.015 * along + 0.018 * across, 0.014, 1.0)
        thumb_middle = s.chain(thumb_root, wrist_position + 0.04 * along + 0.04 * across, 0.0105, 1.0)
        s.chain(thumb_middle, wrist_position + 0.065 * along + 0.055 * across, 0.0085, 1.0)
    return s, pelvis


def _evaluated_copy(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return bpy.data.meshes.new_from_object(obj.evaluated_get(depsgraph), preserve_all_data_layers=True,
                                           depsgraph=depsgraph)


def skin_mesh(name, skeleton, root, levels, collection):
    """The closed quad mesh the Skin and Subdivision Surface modifiers make of the skeleton."""
    mesh = bpy.data.meshes.new(name + "Skeleton")
    mesh.from_pydata([tuple(p) for p in skeleton.points], skeleton.edges, [])
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    skin = obj.modifiers.new("Skin", "SKIN")
    skin.use_smooth_shade = True
    skin.branch_smoothing = 0.5
    for vertex, radius in zip(mesh.skin_vertices[0].data, skeleton.radii):
        vertex.radius = (radius, radius)
        vertex.use_root = False
    mesh.skin_vertices[0].data[root].use_root = True
    _apply(obj, skin)
    subdivide(obj, levels)
    obj.data.name = name
    return obj


def _apply(obj, modifier):
    """Applies `modifier` (the object's only enabled one) and closes the result."""
    previous = obj.data
    result = _evaluated_copy(obj)
    result.name = previous.name
    obj.modifiers.remove(modifier)
    obj.data = result
    bpy.data.meshes.remove(previous)
    _close(result)


def subdivide(obj, levels):
    """Applies `levels` of Catmull–Clark subdivision; vertex weights are interpolated."""
    if levels <= 0:
        return
    armature = [m for m in obj.modifiers if m.type == "ARMATURE"]
    for m in armature:  # subdivide the rest shape, not the pose
        m.show_viewport = False
    subdivision = obj.modifiers.new("Subdivision", "SUBSURF")
    subdivision.levels = subdivision.render_levels = levels
    _apply(obj, subdivision)
    for m in armature:
        m.show_viewport = True


def _close(mesh):
    """Repairs what the Skin modifier sometimes leaves where several branches
    meet at odd angles (a hull it could not build: a hole and stray edges):
    stray edges go, holes are filled, every normal points out."""
    import bmesh
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-6)
    wire = [e for e in bm.edges if e.is_wire]
    if wire:
        bmesh.ops.delete(bm, geom=wire, context="EDGES")
    loose = [v for v in bm.verts if not v.link_edges]
    if loose:
        bmesh.ops.delete(bm, geom=loose, context="VERTS")
    boundary = [e for e in bm.edges if e.is_boundary]
    if boundary:
        filled = bmesh.ops.holes_fill(bm, edges=boundary, sides=0)["faces"]
        if filled:
            bmesh.ops.triangulate(bm, faces=filled, quad_method="BEAUTY", ngon_method="BEAUTY")
    bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()


# Vertex count at subdivision level 2 against the skeleton's segment length,
# V ≈ FIXED + PER_METRE / segment (measured in Blender 3.4: 9.9k at 0.05 m,
# 7.8k at 0.1 m): the hands and the head are a fixed part. Each level ×4.
FIXED_VERTICES, VERTICES_PER_METRE = 5610.0, 214.0
# Segment lengths the Skin modifier handles well here: below ~0.04 m the
# branch hulls at the pelvis fold over.
SEGMENT_RANGE = (0.05, 0.1)


def _resolution(vertices):
    """(subdivision levels, segment length, decimation ratio) for about `vertices` vertices:
    a level whose segment range reaches the count within 10 % (quads only), else the next
    level up at its longest segment, decimated."""
    shortest, longest = SEGMENT_RANGE
    for levels in range(1, 6):
        scale = 4.0 ** (levels - 2)
        most = scale * (FIXED_VERTICES + VERTICES_PER_METRE / shortest)
        least = scale * (FIXED_VERTICES + VERTICES_PER_METRE / longest)
        if vertices <= 1.1 * most or levels == 5:
            if vertices >= 0.9 * least:
                wanted = min(max(vertices, least), most)
                return levels, VERTICES_PER_METRE / (wanted / scale - FIXED_VERTICES), 1.0
            return levels, longest, vertices / least
    raise AssertionError("unreachable")


def decimate(obj, ratio):
    """Collapses edges down to `ratio` of the faces (the counts between two
    subdivision levels); vertex weights are interpolated."""
    if ratio >= 1.0:
        return
    armature = [m for m in obj.modifiers if m.type == "ARMATURE"]
    for m in armature:
        m.show_viewport = False
    modifier = obj.modifiers.new("Decimate", "DECIMATE")
    modifier.decimate_type = "COLLAPSE"
    modifier.ratio = ratio
    _apply(obj, modifier)
    for m in armature:
        m.show_viewport = True


# Bone heat switches between the two bones of a straight limb within about a
# centimetre (elbows and knees bend like hinges); smoothing the weights over
# the surface, as a rigger would with Weight Paint's Smooth, spreads every
# joint's transition over about this length.
SMOOTH_WEIGHTS_METRES = 0.04


def _smooth_weights(obj, length):
    """Smooths every vertex group over about `length` along the surface
    (passes of w ← w + ½(mean of the neighbours' w − w), their number set
    by the mean edge length) and normalizes each vertex's weights again."""
    import bmesh
    import numpy as np
    mesh = obj.data
    vertex_count, group_count = len(mesh.vertices), len(obj.vertex_groups)
    edges = np.empty(2 * len(mesh.edges), dtype=np.int64)
    mesh.edges.foreach_get("vertices", edges)
    edges = edges.reshape(-1, 2)
    positions = np.empty(3 * vertex_count)
    mesh.vertices.foreach_get("co", positions)
    positions = positions.reshape(-1, 3)
    edge_length = float(np.linalg.norm(positions[edges[:, 0]] - positions[edges[:, 1]], axis=1).mean())
    # One pass diffuses over about edge·sqrt(passes / 2).
    passes = max(1, min(1000, int(round(2.0 * (length / max(edge_length, 1e-9)) ** 2))))

    bm = bmesh.new()
    bm.from_mesh(mesh)
    layer = bm.verts.layers.deform.verify()
    bm.verts.ensure_lookup_table()
    weights = np.zeros((vertex_count, group_count))
    for vertex in bm.verts:
        for group, weight in vertex[layer].items():
            weights[vertex.index, group] = weight
    # Neighbours as CSR rows: each vertex's neighbours, summed with reduceat.
    ends = np.concatenate([edges, edges[:, ::-1]])
    ends = ends[np.argsort(ends[:, 0], kind="stable")]
    starts = np.searchsorted(ends[:, 0], np.arange(vertex_count))
    degree = np.bincount(ends[:, 0], minlength=vertex_count)[:, None]
    for _ in range(passes):
        mean = np.add.reduceat(weights[ends[:, 1]], starts, axis=0) / np.maximum(degree, 1)
        weights += 0.5 * np.where(degree > 0, mean - weights, 0.0)
    weights[weights < 1e-4] = 0.0
    weights /= np.maximum(weights.sum(axis=1, keepdims=True), 1e-12)
    for vertex in bm.verts:
        deform = vertex[layer]
        deform.clear()
        row = weights[vertex.index]
        for group in np.flatnonzero(row):
            deform[int(group)] = float(row[group])
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()


def build(name="PenumbraHumanoid", detail=1.0, frames=48, start=DEFAULT_START, fps=24, bvh=None, collection=None):
    """Builds the humanoid in the current scene: the BVH's armature playing
    `frames` frames of the capture from capture frame `start` at `fps`
    (scene frames 1..frames), and the skin mesh parented to it with automatic
    weights. Returns (mesh object, armature object)."""
    scene = bpy.context.scene
    collection = collection or scene.collection
    path = bvh_path(bvh)
    armature = import_motion(path, frames, start, fps)
    armature.name = name + "Rig"
    if armature.name not in collection.objects:
        for c in armature.users_collection:
            c.objects.unlink(armature)
        collection.objects.link(armature)
    scene.frame_start, scene.frame_end = 1, frames
    scene.render.fps = fps
    scene.frame_set(1)

    # The weights are made at subdivision level 2 at most (≤ 10k vertices):
    # finer levels and the decimation interpolate them, as a base mesh's
    # painted weights are subdivided, which keeps big meshes quick to build.
    levels, segment, ratio = _resolution(10000.0 * detail)
    weight_levels = min(levels, 2)
    skeleton, root = skeleton_of(armature, segment)
    obj = skin_mesh(name, skeleton, root, weight_levels, collection)

    # Automatic (bone heat) weights from the rest pose.
    view_layer = bpy.context.view_layer
    armature.data.pose_position = "REST"
    for o in view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    armature.select_set(True)
    view_layer.objects.active = armature
    result = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    armature.data.pose_position = "POSE"
    if result != {"FINISHED"}:
        raise RuntimeError(f"automatic weights failed: {result}")
    obj.select_set(False)
    armature.select_set(False)
    view_layer.objects.active = obj
    _smooth_weights(obj, SMOOTH_WEIGHTS_METRES)
    subdivide(obj, levels - weight_levels)
    decimate(obj, ratio)
    scene.frame_set(1)
    return obj, armature


def _main():
    import argparse
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--detail", type=float, default=1.0)
    parser.add_argument("--frames", type=int, default=48)
    parser.add_argument("--start", type=int, default=DEFAULT_START)
    parser.add_argument("--bvh", default=None)
    args = parser.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    obj, armature = build(detail=args.detail, frames=args.frames, start=args.start, bvh=args.bvh)
    print(f"humanoid: {len(obj.data.vertices)} vertices, {len(armature.data.bones)} bones")
    bpy.ops.wm.save_as_mainfile(filepath=args.out)


if __name__ == "__main__":
    _main()
