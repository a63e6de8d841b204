"""A procedural rigged, animated test character for the visibility baker.

Capsule torso, head and two two-segment arms, joined into one mesh; an
armature with a root, a spine, upper arms, forearms and a non-deforming
control bone; vertex weights assigned by hand (deterministic, no automatic
weights); one action that swings the arms down against the torso and bends
the elbows, so limbs occlude the body and each other.

Inside Blender (tests, benchmarks, the demo):
    import visibility_character; mesh, armature = visibility_character.build()
As a script, writes a .blend:
    blender -b --factory-startup --python examples/scenes/visibility_character.py -- --out character.blend [--detail 2]
"""

import math
import sys

import bmesh
import bpy
from mathutils import Matrix, Vector


def _capsule(bm, start, end, radius, segments, rings):
    """Adds a capsule from `start` to `end` to the bmesh; returns its new vertices."""
    start, end = Vector(start), Vector(end)
    axis = end - start
    length = axis.length
    before = set(bm.verts)
    result = bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius)
    verts = result["verts"]
    # Stretch the sphere into a capsule along +z, then turn +z onto the axis.
    for v in verts:
        v.co.z += (length / 2.0) * (1.0 if v.co.z > 1e-9 else -1.0 if v.co.z < -1e-9 else 0.0)
    rotation = Vector((0, 0, 1)).rotation_difference(axis.normalized()).to_matrix().to_4x4()
    transform = Matrix.Translation((start + end) / 2.0) @ rotation
    bmesh.ops.transform(bm, matrix=transform, verts=verts)
    return [v for v in bm.verts if v not in before]


def _smoothstep(a, b, x):
    t = min(max((x - a) / (b - a), 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def build(name="PenumbraCharacter", detail=1, frames=24, collection=None):
    """Builds the character in the current scene. `detail` scales the mesh
    resolution (1: about 1k vertices; 3.4: about 10k; 11: about 100k). The action covers
    frames 1..frames. Returns (mesh object, armature object)."""
    scene = bpy.context.scene
    collection = collection or scene.collection
    seg, rings = max(8, int(round(24 * detail))), max(4, int(round(12 * detail)))

    # Mesh ------------------------------------------------------------------
    bm = bmesh.new()
    parts = {}
    parts["torso"] = _capsule(bm, (0, 0, 0.9), (0, 0, 1.7), 0.32, seg, rings)
    parts["head"] = _capsule(bm, (0, 0, 2.05), (0, 0, 2.15), 0.2, seg, rings)
    for side, sign in (("L", 1.0), ("R", -1.0)):
        parts[f"upper_arm.{side}"] = _capsule(bm, (sign * 0.38, 0, 1.6), (sign * 0.95, 0, 1.6), 0.09, seg // 2 + 4, rings // 2 + 2)
        parts[f"forearm.{side}"] = _capsule(bm, (sign * 1.0, 0, 1.6), (sign * 1.55, 0, 1.6), 0.075, seg // 2 + 4, rings // 2 + 2)
    mesh = bpy.data.meshes.new(name)
    bm.verts.index_update()
    index_of = {v: v.index for v in bm.verts}
    part_indices = {k: [index_of[v] for v in vs] for k, vs in parts.items()}
    positions = {index_of[v]: v.co.copy() for v in bm.verts}
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)

    # Armature --------------------------------------------------------------
    arm_data = bpy.data.armatures.new(name + "Rig")
    armature = bpy.data.objects.new(name + "Rig", arm_data)
    collection.objects.link(armature)
    previous_active = bpy.context.view_layer.objects.active
    bpy.context.view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode="EDIT")
    edit = arm_data.edit_bones

    def bone(bone_name, head, tail, parent=None, deform=True):
        b = edit.new(bone_name)
        b.head, b.tail = head, tail
        b.parent = edit[parent] if parent else None
        b.use_connect = False
        b.use_deform = deform
        return b

    bone("root", (0, 0, 0), (0, 0, 0.5))
    bone("spine", (0, 0, 0.9), (0, 0, 1.7), "root")
    bone("head", (0, 0, 1.85), (0, 0, 2.3), "spine")
    bone("control", (0, -0.6, 0), (0, -0.6, 0.3), "root", deform=False)
    for side, sign in (("L", 1.0), ("R", -1.0)):
        bone(f"upper_arm.{side}", (sign * 0.38, 0, 1.6), (sign * 0.97, 0, 1.6), "spine")
        bone(f"forearm.{side}", (sign * 0.97, 0, 1.6), (sign * 1.6, 0, 1.6), f"upper_arm.{side}")
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.context.view_layer.objects.active = previous_active

    # Weights by hand: torso → spine, head → head, arms blend at the elbow.
    groups = {n: obj.vertex_groups.new(name=n) for n in
              ("spine", "head", "upper_arm.L", "forearm.L", "upper_arm.R", "forearm.R")}
    groups["spine"].add(part_indices["torso"], 1.0, "REPLACE")
    groups["head"].add(part_indices["head"], 1.0, "REPLACE")
    for side, sign in (("L", 1.0), ("R", -1.0)):
        for i in part_indices[f"upper_arm.{side}"] + part_indices[f"forearm.{side}"]:
            x = sign * positions[i].x
            fore = _smoothstep(0.9, 1.05, x)
            shoulder = 1.0 - _smoothstep(0.36, 0.5, x)  # blend into the torso at the shoulder
            if fore > 0.0:
                groups[f"forearm.{side}"].add([i], fore, "REPLACE")
            if 1.0 - fore > 0.0:
                groups[f"upper_arm.{side}"].add([i], (1.0 - fore) * (1.0 - shoulder), "REPLACE")
            if shoulder > 0.0:
                groups["spine"].add([i], shoulder, "REPLACE")
    modifier = obj.modifiers.new("Armature", "ARMATURE")
    modifier.object = armature
    obj.parent = armature

    # Action: arms swing down against the torso, elbows bend, head turns.
    armature.animation_data_create()
    action = bpy.data.actions.new(name + "Action")
    armature.animation_data.action = action
    for pose_bone in armature.pose.bones:
        pose_bone.rotation_mode = "XYZ"
    for frame in range(1, frames + 1):
        phase = 2.0 * math.pi * (frame - 1) / max(frames - 1, 1)
        swing = math.radians(35.0) * (1.0 - math.cos(phase))          # arms down: 0 → 70° → 0
        bend = math.radians(40.0) * (1.0 - math.cos(2.0 * phase))     # elbows forward, twice per cycle
        for side, sign in (("L", 1.0), ("R", -1.0)):
            upper = armature.pose.bones[f"upper_arm.{side}"]
            upper.rotation_euler = (-swing, 0.0, 0.0)
            upper.keyframe_insert("rotation_euler", frame=frame)
            fore = armature.pose.bones[f"forearm.{side}"]
            fore.rotation_euler = (0.0, 0.0, sign * bend)
            fore.keyframe_insert("rotation_euler", frame=frame)
        head = armature.pose.bones["head"]
        head.rotation_euler = (0.0, math.radians(10.0) * math.sin(phase), 0.0)
        head.keyframe_insert("rotation_euler", frame=frame)
    scene.frame_start, scene.frame_end = 1, frames
    scene.frame_set(1)
    return obj, armature


def _main():
    import argparse
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--detail", type=int, default=1)
    parser.add_argument("--frames", type=int, default=24)
    args = parser.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    build(detail=args.detail, frames=args.frames)
    bpy.ops.wm.save_as_mainfile(filepath=args.out)


if __name__ == "__main__":
    _main()
