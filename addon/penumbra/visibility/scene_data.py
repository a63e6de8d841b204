"""Reading what the baker needs from Blender: the evaluated mesh of a frame
(world space), the armature's rest-relative bone rotations, which bones can
change this mesh's occlusion, and the World lighting. No bake logic here."""

import numpy as np

from .. import color, native, world


class VisibilityInputError(ValueError):
    """Bad input the user can fix; the message says how."""


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


# World lighting ---------------------------------------------------------------
# The World is read by penumbra.world (its wiring, lookups, pixels and colour
# space), as the light rig reads it: the sum of every Background that lights
# the scene. Here each Background becomes SH coefficients; SH projection is
# linear, so the World's SH is the weighted sum of its Backgrounds'.

# Projections of the World's images, one per (image, lookup): an image seen
# through a rotation is projected once and rotated, any other lookup is
# resampled onto a latlong grid first (world.environment_radiance).
_lighting_cache = {}
# Columns of the latlong grid a remapped image is resampled onto: far finer
# than an order-8 SH needs; each cell averages 2×2 lookups, so a small sun
# keeps its flux. About 0.5 s of numpy, once per image and lookup.
_REMAP_WIDTH = 512


def read_world(scene):
    """world.read_scene with the whole sum of Backgrounds, as the SH lighting
    takes it (any Mapping or Vector Rotate lookup, equirectangular or
    mirror-ball images)."""
    return world.read_scene(scene)


def world_lighting(scene, order):
    """(order², 3) SH of the World's radiance (scene-linear), and a note on what
    was used (read_world: the World as penumbra.world reads it, strengths and
    mix weights applied); what cannot be read falls back as the note says."""
    lighting, note, pixel_warning = world_lighting_checked(scene, order)
    return lighting, (f"{note}; {pixel_warning}" if pixel_warning else note)


def _pixel_warning(image, stats):
    """What was wrong with an environment image's pixels ('' when nothing)."""
    bad, negative = stats["non_finite_pixels"], stats["negative_pixels"]
    if not bad and not negative:
        return ""
    parts = []
    if bad:
        parts.append(f"{bad} NaN or infinite pixel(s), lit as black")
    if negative:
        parts.append(f"{negative} pixel(s) with negative values, kept")
    return (f"the World's environment image '{image.name}' has {' and '.join(parts)}; "
            "fix or replace the image for correct lighting")


def world_lighting_checked(scene, order):
    """world_lighting, and a warning about the environment images' pixels
    (NaN, infinite or negative values; '' when none) kept apart from the note."""
    core = native.require()
    lighting = np.zeros((order * order, 3))
    r = read_world(scene)
    warnings = []
    for term in r.terms:
        scale = term.weight * term.strength
        if scale == 0.0:
            continue
        if term.kind == "uniform":
            lighting[0] += term.colour * scale * np.sqrt(4.0 * np.pi)
            continue
        coefficients, warning = _environment_sh(core, term, order)
        lighting += coefficients * scale
        if warning and warning not in warnings:
            warnings.append(warning)
    return lighting, r.note, "; ".join(warnings)


def _lookup_key(term):
    """What, besides the image, decides an environment term's radiance."""
    if term.projection == "EQUIRECTANGULAR" and term.lookup.rotation is not None:
        return ("rotation", term.lookup.rotation.tobytes())
    steps = tuple((a.tobytes(), b.tobytes(), normalize) for a, b, normalize in term.lookup.steps)
    return ("remap", term.projection, term.interpolation, steps)


def _environment_sh(core, term, order):
    """(order², 3) SH of one environment Background at weight and strength 1,
    and its image's pixel warning, cached per image and lookup."""
    image = term.image
    # The working space (Blender 5.0+) changes what the pixels mean, and a
    # float image's pixels themselves.
    key = (image.name, image.filepath, tuple(image.size), image.colorspace_settings.name,
           color.file_working_space(), order, _lookup_key(term))
    cached = _lighting_cache.get(key)
    if cached is None:
        cached = _project_environment(core, term, order)
        if len(_lighting_cache) > 8:  # a few Worlds' images, not every one ever seen
            _lighting_cache.clear()
        _lighting_cache[key] = cached
    return cached


def _project_environment(core, term, order):
    try:
        pixels = world.image_pixels(term.image)
    except world.WorldError as error:
        raise VisibilityInputError(str(error)) from None
    rotation = term.lookup.rotation
    if term.projection == "EQUIRECTANGULAR" and rotation is not None:
        coefficients, stats = core.sh.project_environment(order, pixels, with_stats=True)
        # L(d) = E(R·d): the map's SH turned by world_from_map = Rᵀ.
        if not np.allclose(rotation, np.eye(3)):
            coefficients = core.sh.rotate(coefficients, rotation.T)
        return np.asarray(coefficients), _pixel_warning(term.image, stats)
    # Any other lookup (a Location, a bending or mirroring Scale, a mirror
    # ball): the term's radiance on a latlong grid of world directions, as
    # Blender's Environment Texture looks it up, then projected. Bad pixels
    # are counted on the image itself and lit as black, as the plain path does.
    _, stats = core.sh.project_environment(1, pixels, with_stats=True)
    pixels = np.where(np.isfinite(pixels), pixels, np.float32(0.0))
    grid = world.environment_radiance([_UnitTerm(term)], [pixels], _REMAP_WIDTH)
    coefficients = core.sh.project_environment(order, grid)
    return np.asarray(coefficients), _pixel_warning(term.image, stats)


class _UnitTerm:
    """An environment term's lookup at weight and strength 1 (the cache keeps
    the projection apart from the strength, which may be animated)."""

    def __init__(self, term):
        self.kind, self.lookup, self.projection = term.kind, term.lookup, term.projection
        self.interpolation = term.interpolation
        self.weight = self.strength = 1.0
