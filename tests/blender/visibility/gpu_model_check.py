"""Run by tests/python/visibility/test_gpu_model_in_blender.py in a Blender
that has a GPU: Debian's Blender 3.4 in a window under Xvfb, or the bpy 5.x
module after gpu.init():

    xvfb-run -a blender --factory-startup --python gpu_model_check.py -- [--vertices 1500]
    .venv313/bin/python gpu_model_check.py --gpu-init [--vertices 1500]

The pose model evaluated in the vertex shader (gpu_model.py) against the CPU
run time (PoseModel.shade: pose → lobes → frames → shading), per vertex, read
back from an RGBA32F offscreen buffer: synthetic models (random stored
weights, biases, joint directions and per-vertex block layouts, a few
vertices with no block) on a wavy sheet, an unseen random pose and a
non-identity world matrix, for every BRDF, SH order 1–8 and 1–4 lobes,
under a uniform World of radiance 1; plus a few configurations under random
lighting. With --humanoid-detail D, also the humanoid baked at that detail,
once per BRDF (gpu_model_humanoid.py). Prints one line `RESULT {json}`.
"""

import math
import os
import sys
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path[:0] = [os.path.join(ROOT, "build", "addon"), os.path.join(ROOT, "examples", "scenes"), HERE,
                 os.path.dirname(HERE)]  # gpu_model_humanoid: visibility_character_scenes

ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
VERTICES = int(ARGS[ARGS.index("--vertices") + 1]) if "--vertices" in ARGS else 1500
# The humanoid's detail (examples/scenes/visibility_humanoid.py; 10: ~100k vertices), 0 for none.
HUMANOID_DETAIL = float(ARGS[ARGS.index("--humanoid-detail") + 1]) if "--humanoid-detail" in ARGS else 0.0
JOINTS = 5

if "--gpu-init" in ARGS:
    import gpu
    gpu.init()

sys.path.append(ROOT)  # bench.helpers
import penumbra  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from penumbra import native  # noqa: E402
from penumbra.visibility import gpu_model, gpu_preview  # noqa: E402


def sheet(vertices):
    """A wavy grid of quads: object-space positions, normals (Blender's rule,
    from the core: the CPU side's), triangles, the reference neighbours and
    the polygons (sizes, vertex loops)."""
    core = native.require()
    side = max(2, int(math.sqrt(vertices)))
    u, v = np.meshgrid(np.linspace(-1.0, 1.0, side), np.linspace(-1.0, 1.0, side), indexing="ij")
    positions = np.stack([u, v, 0.3 * np.sin(3.0 * u) * np.cos(2.0 * v)], axis=-1).reshape(-1, 3).astype(np.float32)
    index = np.arange(side * side).reshape(side, side)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], axis=-1).reshape(-1, 4)
    sizes = np.full(len(quads), 4, dtype=np.int64)
    loops = quads.reshape(-1).astype(np.int64)
    mesh = core.visibility.ShadingMesh(len(positions), sizes, loops)
    normals = mesh.vertex_normals(positions)
    neighbours = core.visibility.reference_neighbours(len(positions), sizes, loops)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int64)
    return positions, normals, triangles, np.asarray(neighbours, dtype=np.int64), (sizes, loops)


def random_rotation(rng, angle):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def synthetic_model(rng, order, lobes, vertex_count):
    """Random weights in the stored layout: joints with 1–9 feature
    directions, 0–3 blocks a vertex, each keeping 1..m_j directions."""
    core = native.require()
    d = lobes * (2 + order)
    directions = rng.integers(1, 10, JOINTS)
    feature_offsets = np.concatenate([[0], np.cumsum(directions)])
    basis = np.zeros((feature_offsets[-1], 9), dtype=np.float32)
    for j in range(JOINTS):
        q, _ = np.linalg.qr(rng.normal(size=(9, 9)))
        basis[feature_offsets[j]:feature_offsets[j + 1]] = q.T[:directions[j]]
    counts = rng.integers(0, 4, vertex_count)
    joint_offsets = np.concatenate([[0], np.cumsum(counts)])
    joint_index = np.concatenate([np.sort(rng.choice(JOINTS, c, replace=False)) for c in counts]).astype(np.int64)
    block_directions = np.array([rng.integers(1, directions[j] + 1) for j in joint_index], dtype=np.int64)
    bias = np.zeros((vertex_count, lobes, 2 + order), dtype=np.float32)
    bias[:, :, :2] = rng.normal(0.0, 0.6, (vertex_count, lobes, 2))
    bias[:, :, 2:] = rng.normal(0.0, 0.5, (vertex_count, lobes, order)) / (1.0 + np.arange(order))
    # Block scales over many binary16 exponents: weights from 1e-4 to 1.
    magnitudes = 10.0 ** rng.uniform(-4.0, 0.0, len(joint_index))
    weights = np.concatenate([rng.normal(0.0, m, c * d) for m, c in zip(magnitudes, block_directions)]) \
        if len(joint_index) else np.zeros(0)
    return core.visibility.PoseModel.from_blocks(
        order, lobes, [f"joint{j}" for j in range(JOINTS)], feature_offsets, basis.reshape(-1), joint_offsets,
        joint_index, block_directions, bias.reshape(-1), weights.astype(np.float32))


def world_matrix():
    rotation = random_rotation(np.random.default_rng(7), 0.7)
    world = np.eye(4)
    world[:3, :3] = rotation @ np.diag([1.3, 0.8, 1.1])  # non-uniform scale: normals by the inverse transpose
    world[:3, 3] = (0.2, -0.4, 1.0)
    return world


def compare(order, lobes, brdf, mesh, rng, lighting=None):
    positions, normals, triangles, neighbours, polygons = mesh
    model = synthetic_model(rng, order, lobes, len(positions))
    rotations = np.stack([random_rotation(rng, rng.uniform(0.2, 1.2)) for _ in range(JOINTS)]).astype(np.float32)
    if lighting is None:  # a uniform World of radiance 1
        lighting = np.zeros((order * order, 3))
        lighting[0] = math.sqrt(4.0 * math.pi)
    world = world_matrix()
    camera = np.array([0.3, -4.0, 2.0])
    linear = world[:3, :3]
    world_positions = (positions.astype(np.float64) @ linear.T + world[:3, 3]).astype(np.float32)
    world_normals = (normals.astype(np.float64) @ np.linalg.inv(linear)).astype(np.float32)
    rgb_cpu, ao_cpu, _ = model.shade(rotations, world_positions, world_normals, triangles, neighbours, lighting,
                                     model=brdf, phong_exponent=24.0, camera=camera, transmission=(0.4, 0.5, 0.6))
    rest = np.stack([np.eye(3, dtype=np.float32)] * JOINTS)
    rgb_rest, _, _ = model.shade(rest, world_positions, world_normals, triangles, neighbours, lighting,
                                 model=brdf, phong_exponent=24.0, camera=camera, transmission=(0.4, 0.5, 0.6))
    on_gpu = gpu_model.ModelOnGpu(model, neighbours, polygons)
    on_gpu.set_frame(gpu_model.frame_inputs(model, model.pose_features(rotations), positions, world, lighting,
                                            brdf, 24.0, camera, (0.4, 0.5, 0.6)))
    rgb_gpu, ao_gpu = on_gpu.shade_offscreen()
    return {"order": order, "lobes": lobes, "brdf": brdf,
            "max_abs_rgb": float(np.max(np.abs(rgb_gpu - rgb_cpu))),
            "max_abs_visibility": float(np.max(np.abs(ao_gpu - ao_cpu))),
            "rgb_range": [float(rgb_cpu.min()), float(rgb_cpu.max())],
            "pose_effect": float(np.max(np.abs(rgb_cpu - rgb_rest))),  # the pose's weights changed the shading
            "constant_vertices": int(np.sum(np.diff(model.stored_blocks()["joint_offsets"]) == 0))}


def check(result):
    import gpu
    penumbra.register()
    result["unavailable"] = gpu_preview.gpu_unavailable_reason()
    result["renderer"] = f"{gpu.platform.renderer_get()} / {gpu.platform.version_get()}"
    rng = np.random.default_rng(2027)
    mesh = sheet(VERTICES)
    result["vertices"] = len(mesh[0])
    started = time.perf_counter()
    cases = [compare(order, lobes, brdf, mesh, rng) for brdf in ("diffuse", "phong", "translucent")
             for order in range(1, 9) for lobes in range(1, 5)]
    for brdf in ("diffuse", "phong", "translucent"):
        lighting = rng.normal(0.0, 0.5, (16, 3))
        lighting[0] = 2.0
        cases.append(dict(compare(4, 2, brdf, mesh, rng, lighting), lighting="random"))
    result["seconds"] = round(time.perf_counter() - started, 1)
    result["cases"] = cases
    if HUMANOID_DETAIL:
        import tempfile
        from gpu_model_humanoid import humanoid_cases
        started = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            result["humanoid"] = dict(humanoid_cases(HUMANOID_DETAIL, tmp),
                                      seconds=round(time.perf_counter() - started, 1))
    penumbra.unregister()


report(check)
