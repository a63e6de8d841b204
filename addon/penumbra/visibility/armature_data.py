"""Reading the armature the baker and the frame shading need from Blender:
the armature deforming a mesh, its rest-relative bone rotations, which bones
can change the mesh's occlusion, and whether it is animated."""

import numpy as np

from .input_error import VisibilityInputError


def armature_of(obj):
    """The armature object deforming `obj` (first Armature modifier with an object)."""
    if obj is None or obj.type != "MESH":
        raise VisibilityInputError("select a mesh object to bake")
    for modifier in obj.modifiers:
        if modifier.type == "ARMATURE" and modifier.object is not None and modifier.object.type == "ARMATURE":
            return modifier.object
    emptied = [m.name for m in obj.modifiers if m.type == "ARMATURE"]
    if emptied:
        # Deleting the armature object leaves the modifier pointing at nothing.
        raise VisibilityInputError(
            f"the Armature modifier '{emptied[0]}' of '{obj.name}' points at no armature (was it deleted?): "
            "undo the deletion, or set the modifier's Object to the armature that deforms the mesh")
    raise VisibilityInputError(
        f"'{obj.name}' has no Armature modifier pointing at an armature: the visibility baker models "
        "self-shadowing as a function of bone rotations")


def bone_rotations(armature, names=None):
    """Each bone's rotation relative to rest in its parent's space, constraints and
    IK included, as (B, 3, 3) float32 (scale stripped). `names`: which bones, in
    that order (default: every bone)."""
    bones = armature.pose.bones
    chosen = [bones[n] for n in names] if names is not None else list(bones)
    out = np.empty((len(chosen), 3, 3), dtype=np.float32)
    for i, pose_bone in enumerate(chosen):
        bone = pose_bone.bone
        if bone.parent is not None:
            rest = bone.parent.matrix_local.inverted_safe() @ bone.matrix_local
            posed = pose_bone.parent.matrix.inverted_safe() @ pose_bone.matrix
        else:
            rest = bone.matrix_local
            posed = pose_bone.matrix
        relative = rest.inverted_safe() @ posed
        out[i] = np.array(relative.to_quaternion().to_matrix(), dtype=np.float32)
    return out


def bone_influence(obj, armature):
    """(deforms_mesh, rigid_for_whole_mesh) per bone of the armature, in pose-bone order."""
    mesh = obj.data
    group_index = {g.name: g.index for g in obj.vertex_groups}
    deform_bones = [b for b in armature.data.bones if b.use_deform and b.name in group_index]
    column = {b.name: k for k, b in enumerate(deform_bones)}
    weights = np.zeros((len(mesh.vertices), len(deform_bones)), dtype=np.float64)
    by_group = {group_index[b.name]: column[b.name] for b in deform_bones}
    for v in mesh.vertices:
        for g in v.groups:
            k = by_group.get(g.group)
            if k is not None and g.weight > 0.0:
                weights[v.index, k] = g.weight
    total = weights.sum(axis=1)
    weighted = total > 0.0
    all_weighted = bool(weighted.all())
    result = []
    for pose_bone in armature.pose.bones:
        subtree = [pose_bone.bone] + list(pose_bone.bone.children_recursive)
        columns = [column[b.name] for b in subtree if b.name in column]
        if not columns:
            result.append((False, False))
            continue
        carried = weights[:, columns].sum(axis=1)
        deforms = bool((carried > 0.0).any())
        rigid = all_weighted and bool(np.all(carried[weighted] >= total[weighted] * (1.0 - 1e-6)))
        result.append((deforms, rigid))
    return result


def armature_has_animation(armature):
    data = armature.animation_data
    if data is None:
        return False
    if data.action is not None:
        return True
    return any(track.strips for track in data.nla_tracks) or len(data.drivers) > 0
