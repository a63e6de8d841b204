"""The realistic test character (examples/scenes/visibility_humanoid.py): a skin
around the CMU motion-capture skeleton of assimp-testmodels' 01_01.bvh, with
Blender's automatic weights, built small here. Checks it is what the
benchmark needs — a closed, outward skin, smooth weights, a moving skeleton
with moving finger bones — and that the visibility baker runs on it."""

import json
import os
import sys

import bpy
import numpy as np
import pytest

import penumbra
from penumbra import native
from penumbra.visibility import armature_data, frame_shading, mesh_data

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(ROOT, "examples", "scenes"))
import visibility_humanoid  # noqa: E402

FRAMES = 16
HANDS = (("LeftHand", "LeftFingerBase", "LFingers", "LThumb"), ("RightHand", "RightFingerBase", "RFingers", "RThumb"))


@pytest.fixture(scope="module")
def humanoid():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    penumbra.register()
    try:
        obj, rig = visibility_humanoid.build(detail=0.25, frames=FRAMES)
        yield bpy.context.scene, obj, rig
    finally:
        frame_shading.forget()
        penumbra.unregister()


def weights(obj):
    """(V, groups) weights of the mesh's vertex groups, by group index."""
    out = np.zeros((len(obj.data.vertices), len(obj.vertex_groups)))
    for v in obj.data.vertices:
        for g in v.groups:
            out[v.index, g.group] = g.weight
    return out


def rotation_angles(scene, rig):
    """Per bone, the largest angle (degrees) its rest-relative rotation turns away from frame 1's."""
    first = None
    largest = np.zeros(len(rig.pose.bones))
    for frame in range(1, FRAMES + 1):
        scene.frame_set(frame)
        r = armature_data.bone_rotations(rig).astype(np.float64)
        if first is None:
            first = r
        cosine = (np.einsum("bij,bij->b", first, r) - 1.0) / 2.0
        largest = np.maximum(largest, np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))))
    scene.frame_set(1)
    return dict(zip([b.name for b in rig.pose.bones], largest))


def test_the_humanoid_is_a_closed_outward_skin_of_about_the_asked_size(humanoid):
    scene, obj, rig = humanoid
    mesh = obj.data
    assert 2000 <= len(mesh.vertices) <= 3000  # detail 0.25: ~2.5k
    # Every edge borders exactly two faces (closed, manifold).
    counts = {}
    for polygon in mesh.polygons:
        for key in polygon.edge_keys:
            counts[key] = counts.get(key, 0) + 1
    assert len(counts) == len(mesh.edges) and set(counts.values()) == {2}
    positions = np.array([v.co for v in mesh.vertices], dtype=np.float32)
    normals = mesh_data._vertex_normals(mesh)
    triangles = mesh_data.mesh_triangles(mesh)
    diagnostics = native.require().visibility.mesh_diagnostics(positions, normals, triangles)
    assert not diagnostics["normals_point_inward"] and diagnostics["signed_volume"] > 0.02  # m³, a person
    # A person-sized figure: about 1.5 m from toes to the top of the head.
    height = positions[:, 2].max() - positions[:, 2].min()
    assert 1.3 < height < 1.9


def test_automatic_weights_are_smooth_and_every_vertex_is_weighted(humanoid):
    scene, obj, rig = humanoid
    w = weights(obj)
    assert len(obj.vertex_groups) == len(rig.data.bones) == 31
    assert np.all(w.sum(axis=1) > 0.5)                       # nothing left unweighted (bone heat: 0.89–1.06)
    blended = np.count_nonzero(w >= 0.05, axis=1) >= 2
    assert blended.mean() > 0.3                              # smooth: many vertices share bones
    # Across the elbows and knees the weight changes gradually: some vertices
    # take a share of both bones well inside (0.2, 0.8).
    index = {g.name: g.index for g in obj.vertex_groups}
    for a, b in (("LeftArm", "LeftForeArm"), ("RightArm", "RightForeArm"), ("LeftUpLeg", "LeftLeg"),
                 ("RightUpLeg", "RightLeg")):
        first, second = w[:, index[a]], w[:, index[b]]
        pair = (first + second) > 0.5
        share = second[pair] / (first + second)[pair]
        assert np.count_nonzero((share > 0.2) & (share < 0.8)) >= 5, (a, b)


def test_the_skeleton_moves_and_the_hands_have_moving_finger_bones(humanoid):
    scene, obj, rig = humanoid
    angles = rotation_angles(scene, rig)
    assert len(rig.data.bones) >= 20
    assert sum(a > 2.0 for a in angles.values()) >= 20, angles
    w = weights(obj)
    index = {g.name: g.index for g in obj.vertex_groups}
    for hand, finger_base, fingers, thumb in HANDS:
        # Finger bones parented in the hand, carrying the finger and thumb
        # geometry (the CMU hand bone runs along the fingers, so they share it).
        assert rig.data.bones[fingers].parent.name == finger_base and rig.data.bones[thumb].parent.name == hand
        for bone in (finger_base, fingers, thumb):
            assert (w[:, index[bone]] > 0.2).sum() > 20, bone
        assert angles[finger_base] > 2.0 and angles[thumb] > 2.0, (finger_base, thumb, angles)


def test_the_visibility_baker_bakes_and_shades_the_humanoid(humanoid, tmp_path):
    scene, obj, rig = humanoid
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    result = bpy.ops.penumbra.bake_visibility(frame_start=1, frame_end=FRAMES, frame_step=1, rays=16, lobes=2,
                                              filepath=os.path.join(str(tmp_path), "humanoid.pzh"))
    assert result == {"FINISHED"}
    report = json.loads(obj.penumbra_visibility.report)
    assert len(report["active_joints"]) >= 10, report["active_joints"]
    scene.frame_set(7)
    assert bpy.ops.penumbra.apply_visibility() == {"FINISHED"}
    ao = np.empty(len(obj.data.vertices), dtype=np.float32)
    obj.data.attributes[frame_shading.VISIBILITY_ATTRIBUTE].data.foreach_get("value", ao)
    assert np.all(np.isfinite(ao)) and 0.2 < ao.mean() < 0.95
    assert ao.min() < 0.5  # armpits, between the fingers, between the legs: shadowed
