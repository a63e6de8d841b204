"""Test scenes for the visibility bindings, shared by
tests/python/visibility/ and tests/python/test_parallel_failures.py: two
UV spheres, a body and an arm that turns about z, baked into a TrainingSet."""

import numpy as np

import _penumbra as p


def uv_sphere(n_u=24, n_v=12, radius=1.0, centre=(0.0, 0.0, 0.0)):
    verts = [(0.0, 0.0, 1.0)]
    for i in range(1, n_v):
        th = np.pi * i / n_v
        for j in range(n_u):
            ph = 2 * np.pi * j / n_u
            verts.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
    verts.append((0.0, 0.0, -1.0))
    normals = np.array(verts)
    positions = normals * radius + np.array(centre)
    tris = [(0, 1 + j, 1 + (j + 1) % n_u) for j in range(n_u)]
    for i in range(n_v - 2):
        for j in range(n_u):
            a, b = 1 + i * n_u + j, 1 + i * n_u + (j + 1) % n_u
            c, d = 1 + (i + 1) * n_u + (j + 1) % n_u, 1 + (i + 1) * n_u + j
            tris += [(a, d, c), (a, c, b)]
    last, ring = len(verts) - 1, 1 + (n_v - 2) * n_u
    tris += [(last, ring + (j + 1) % n_u, ring + j) for j in range(n_u)]
    return positions.astype(np.float32), normals.astype(np.float32), np.array(tris, dtype=np.int64)


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=np.float32)


def two_sphere_character():
    body = uv_sphere()
    arm = uv_sphere(12, 8, 0.5, (1.6, 0.0, 0.0))
    n_body = len(body[0])
    positions = np.vstack([body[0], arm[0]])
    normals = np.vstack([body[1], arm[1]])
    tris = np.vstack([body[2], arm[2] + n_body])
    return positions, normals, tris, n_body


def bake(angles, rays=64):
    positions, normals, tris, n_body = two_sphere_character()
    neighbours = p.visibility.reference_neighbours(len(positions), np.array([], dtype=np.int64), tris.ravel())
    topology = p.visibility.topology_hash(len(positions), np.full(len(tris), 3), tris.ravel())
    ts = p.visibility.TrainingSet(len(positions), topology, ["root", "arm"], order=4, rays=rays)
    for i, angle in enumerate(angles):
        r = rot_z(angle)
        posed, posed_normals = positions.copy(), normals.copy()
        posed[n_body:] = positions[n_body:] @ r.T
        posed_normals[n_body:] = normals[n_body:] @ r.T
        ts.bake_frame(i, posed, posed_normals, tris, neighbours, np.stack([np.eye(3, dtype=np.float32), r]))
    return ts
