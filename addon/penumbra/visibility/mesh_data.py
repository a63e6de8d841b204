"""Reading the mesh the baker and the frame shading need from Blender: its
polygon topology, the evaluated mesh of a frame (world space), the buffers
the frame shading reuses, and the occluders. No bake logic here."""

import numpy as np

from .. import native


def polygon_topology(mesh):
    """(sizes, loop vertex indices) of a mesh's polygons, as numpy int64."""
    sizes = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    starts = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    corner_vert = mesh.attributes.get(".corner_vert") if hasattr(mesh, "attributes") else None
    if corner_vert is not None and corner_vert.data_type == "INT" and len(corner_vert.data) == len(loops):
        corner_vert.data.foreach_get("value", loops)  # Blender 4: one block copy, ~100× faster than loops
    else:
        mesh.loops.foreach_get("vertex_index", loops)
    if len(starts) and np.any(np.diff(starts) != sizes[:-1]):
        # Polygons out of loop order (never in practice): gather each polygon's loops.
        loops = np.concatenate([loops[s:s + n] for s, n in zip(starts, sizes)])
    return sizes.astype(np.int64), loops.astype(np.int64)


def topology_hash(mesh):
    sizes, loops = polygon_topology(mesh)
    return native.require().visibility.topology_hash(len(mesh.vertices), sizes, loops)


def _vertex_normals(mesh, out=None):
    """(V, 3) float32 vertex normals (Blender computes and caches them)."""
    n = len(mesh.vertices)
    normals = np.empty((n, 3), dtype=np.float32) if out is None else out
    if hasattr(mesh, "vertex_normals"):  # Blender 3.5+
        mesh.vertex_normals.foreach_get("vector", normals.reshape(-1))
    else:
        mesh.vertices.foreach_get("normal", normals.reshape(-1))
    return normals


def _vertex_positions(mesh, out=None):
    """(V, 3) float32 positions. The `position` attribute (Blender 3.5+) reads
    as one block copy; `vertices.co` walks every vertex (~40× slower)."""
    n = len(mesh.vertices)
    co = np.empty((n, 3), dtype=np.float32) if out is None else out
    position = mesh.attributes.get("position") if hasattr(mesh, "attributes") else None
    if position is not None and position.data_type == "FLOAT_VECTOR" and position.domain == "POINT":
        position.data.foreach_get("vector", co.reshape(-1))
    else:
        mesh.vertices.foreach_get("co", co.reshape(-1))
    return co


def mesh_triangles(mesh, sizes=None, loops=None, fixed_split=False):
    """(M, 3) int64 triangles of a mesh: Blender's own loop triangles (its
    split of a quad follows the shape, so it can change with the pose), or,
    with fixed_split and only triangles and quads, every quad split 0-1-2,
    0-2-3 with numpy (fast; for the run time, where triangles only repair
    zero-length normals)."""
    if fixed_split:
        if sizes is None:
            sizes, loops = polygon_topology(mesh)
        if not (len(sizes) and sizes.max() > 4):
            per_polygon = np.maximum(sizes - 2, 0)
            starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
            polygon = np.repeat(np.arange(len(sizes)), per_polygon)
            within = np.arange(int(per_polygon.sum())) - np.repeat(np.cumsum(per_polygon) - per_polygon, per_polygon)
            first = starts[polygon]
            return np.stack([loops[first], loops[first + within + 1], loops[first + within + 2]], axis=1).astype(np.int64)
    mesh.calc_loop_triangles()
    tri = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tri)
    return tri.reshape(-1, 3).astype(np.int64)


class FrameMesh:
    """One frame of the evaluated mesh in world space."""

    def __init__(self, positions, normals, triangles, topology):
        self.positions = positions    # (V, 3) float32
        self.normals = normals        # (V, 3) float32
        self.triangles = triangles    # (M, 3) int64
        self.topology = topology      # hash of the polygon topology


class MeshBuffers:
    """What the run time keeps from frame to frame of one object's evaluated
    mesh: triangles (fixed quad split: at run time they only repair
    zero-length normals, so the split need not follow the pose) and the
    arrays the positions and normals are read into (reused: the result of
    evaluated_mesh(..., buffers=b) is overwritten by the next read)."""

    def __init__(self, mesh):
        n = len(mesh.vertices)
        self.vertex_count = n
        self.triangles = mesh_triangles(mesh, fixed_split=True)
        self.co = np.empty((n, 3), dtype=np.float32)
        self.normals_local = np.empty((n, 3), dtype=np.float32)
        self.positions = np.empty((n, 3), dtype=np.float32)
        self.normals = np.empty((n, 3), dtype=np.float32)


def _to_world(evaluated, co, normals, positions_out=None, normals_out=None):
    world = np.array(evaluated.matrix_world, dtype=np.float64)
    linear = world[:3, :3]
    if np.array_equal(world, np.eye(4)):
        if positions_out is None:
            return co, normals
        np.copyto(positions_out, co)
        np.copyto(normals_out, normals)
        return positions_out, normals_out
    # Normals transform by the inverse transpose (non-uniform scale); a
    # singular matrix (scale 0) leaves them as they are. (Only here: numpy's
    # inverse of a 3 × 3 costs ~1 ms, a tenth of reading the mesh.)
    try:
        normal_matrix = np.linalg.inv(linear).T
    except np.linalg.LinAlgError:
        normal_matrix = np.eye(3)
    positions = np.matmul(co, linear.T.astype(np.float32), out=positions_out)
    positions += world[:3, 3].astype(np.float32)
    normals = np.matmul(normals, normal_matrix.T.astype(np.float32), out=normals_out)
    return positions, normals


def evaluated_mesh(obj, depsgraph, with_topology=True, buffers=None):
    """The mesh as modifiers leave it at the current frame, in world space.
    `buffers` (MeshBuffers of this object): reuse its triangles and arrays."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        n = len(mesh.vertices)
        reuse = buffers is not None and buffers.vertex_count == n
        co = _vertex_positions(mesh, buffers.co if reuse else None)
        normals = _vertex_normals(mesh, buffers.normals_local if reuse else None)
        if with_topology:
            sizes, loops = polygon_topology(mesh)
            topology = native.require().visibility.topology_hash(n, sizes, loops)
        else:
            sizes = loops = topology = None
        # The bake needs Blender's own triangles of this pose (the occluding surface).
        tri = buffers.triangles if reuse else mesh_triangles(mesh)
    finally:
        evaluated.to_mesh_clear()
    positions, normals = _to_world(evaluated, co, normals, buffers.positions if reuse else None,
                                   buffers.normals if reuse else None)
    return FrameMesh(positions, normals, tri, topology)


def occluder_meshes(collection, depsgraph, exclude):
    """(positions, triangles) world-space pairs of the mesh objects in a collection."""
    pairs = []
    if collection is None:
        return pairs
    for obj in collection.all_objects:
        if obj == exclude or obj.type not in {"MESH", "CURVE", "SURFACE", "META", "FONT"}:
            continue
        frame = evaluated_mesh(obj, depsgraph, with_topology=False)
        if len(frame.triangles):
            pairs.append((frame.positions, frame.triangles))
    return pairs
