"""Reading what the baker needs from Blender: the evaluated mesh of a frame
(world space), the armature's rest-relative bone rotations, which bones can
change this mesh's occlusion, and the World lighting. No bake logic here."""

import numpy as np

from .. import native


class VisibilityInputError(ValueError):
    """Bad input the user can fix; the message says how."""


def armature_of(obj):
    """The armature object deforming `obj` (first Armature modifier with an object)."""
    if obj is None or obj.type != "MESH":
        raise VisibilityInputError("select a mesh object to bake")
    for modifier in obj.modifiers:
        if modifier.type == "ARMATURE" and modifier.object is not None and modifier.object.type == "ARMATURE":
            return modifier.object
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
    mesh.loops.foreach_get("vertex_index", loops)
    if len(starts) and np.any(np.diff(starts) != sizes[:-1]):
        # Polygons out of loop order (never in practice): gather each polygon's loops.
        loops = np.concatenate([loops[s:s + n] for s, n in zip(starts, sizes)])
    return sizes.astype(np.int64), loops.astype(np.int64)


def topology_hash(mesh):
    sizes, loops = polygon_topology(mesh)
    return native.require().visibility_topology_hash(len(mesh.vertices), sizes, loops)


def _vertex_normals(mesh):
    n = len(mesh.vertices)
    normals = np.empty(3 * n, dtype=np.float32)
    if hasattr(mesh, "vertex_normals"):  # Blender 3.5+
        mesh.vertex_normals.foreach_get("vector", normals)
    else:
        mesh.vertices.foreach_get("normal", normals)
    return normals.reshape(n, 3)


class FrameMesh:
    """One frame of the evaluated mesh in world space."""

    def __init__(self, positions, normals, triangles, topology):
        self.positions = positions    # (V, 3) float32
        self.normals = normals        # (V, 3) float32
        self.triangles = triangles    # (M, 3) int64
        self.topology = topology      # hash of the polygon topology


def evaluated_mesh(obj, depsgraph, with_topology=True):
    """The mesh as modifiers leave it at the current frame, in world space."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        n = len(mesh.vertices)
        co = np.empty(3 * n, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        co = co.reshape(n, 3).astype(np.float64)
        normals = _vertex_normals(mesh).astype(np.float64)
        mesh.calc_loop_triangles()
        tri = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tri)
        topology = topology_hash(mesh) if with_topology else None
    finally:
        evaluated.to_mesh_clear()
    world = np.array(evaluated.matrix_world, dtype=np.float64)
    linear = world[:3, :3]
    positions = co @ linear.T + world[:3, 3]
    # Normals transform by the inverse transpose (non-uniform scale); a
    # singular matrix (scale 0) leaves them as they are.
    try:
        normal_matrix = np.linalg.inv(linear).T
    except np.linalg.LinAlgError:
        normal_matrix = np.eye(3)
    normals = normals @ normal_matrix.T
    return FrameMesh(positions.astype(np.float32), normals.astype(np.float32),
                     tri.reshape(-1, 3).astype(np.int64), topology)


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

_lighting_cache = {}


def _socket_source(socket):
    if socket is None or not socket.is_linked:
        return None
    link = socket.links[0]
    return link.from_node


def _euler_matrix(euler):
    from mathutils import Euler
    return np.array(Euler(tuple(euler), "XYZ").to_matrix(), dtype=np.float64)


def _image_pixels_top_down(image):
    width, height = image.size
    channels = image.channels
    pixels = np.empty(width * height * channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, channels)[::-1]  # Blender stores rows bottom-up
    if channels < 3:
        pixels = np.repeat(pixels[..., :1], 3, axis=2)
    pixels = np.ascontiguousarray(pixels[..., :3])
    if not image.is_float:
        # Byte images hold the file's encoding; convert to scene linear with Blender's config.
        from .. import color
        config = color.blender_config()
        name = image.colorspace_settings.name
        if name and name != config.scene_linear and name not in {"Non-Color", "Raw"}:
            pixels = config.convert(pixels, name, config.scene_linear)
    return pixels


def world_lighting(scene, order):
    """(order², 3) SH of the World's radiance (scene-linear), and a note on what
    was used. Honours Environment Texture (image, colour space), a Mapping
    node's rotation, and the Background strength; otherwise the uniform
    colour. Unsupported node set-ups fall back to the Background colour."""
    core = native.require()
    n_sh = order * order
    world = scene.world
    lighting = np.zeros((n_sh, 3))
    sqrt_4pi = np.sqrt(4.0 * np.pi)
    if world is None:
        return lighting, "no World: black"
    if not world.use_nodes or world.node_tree is None:
        lighting[0] = np.array(world.color[:3]) * sqrt_4pi
        return lighting, "World colour"
    tree = world.node_tree
    output = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output), None)
    if output is None:
        output = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"), None)
    background = _socket_source(output.inputs["Surface"]) if output else None
    if background is None or background.bl_idname != "ShaderNodeBackground":
        return lighting, "World output not fed by a Background node: black"
    strength = float(background.inputs["Strength"].default_value)
    source = _socket_source(background.inputs["Color"])
    if source is None or source.bl_idname != "ShaderNodeTexEnvironment" or source.image is None:
        lighting[0] = np.array(background.inputs["Color"].default_value[:3]) * strength * sqrt_4pi
        return lighting, "uniform Background colour"
    image = source.image
    rotation = np.eye(3)
    mapping = _socket_source(source.inputs["Vector"])
    if mapping is not None and mapping.bl_idname == "ShaderNodeMapping":
        euler = mapping.inputs["Rotation"].default_value if "Rotation" in mapping.inputs else mapping.rotation
        rotation = _euler_matrix(euler)
        if mapping.vector_type in {"TEXTURE"}:
            rotation = rotation.T
    key = (image.name, image.filepath, tuple(image.size), image.colorspace_settings.name, order)
    coefficients = _lighting_cache.get(key)
    if coefficients is None:
        pixels = _image_pixels_top_down(image)
        if pixels.size == 0:
            raise VisibilityInputError(f"the World's environment image '{image.name}' has no pixels (missing file?)")
        coefficients = core.project_environment(order, pixels)
        _lighting_cache.clear()
        _lighting_cache[key] = coefficients
    # The texture is looked up at R·d: L(d) = E(R d), so its SH are D(Rᵀ)·c.
    lit = core.rotate_sh(coefficients, rotation.T) if not np.allclose(rotation, np.eye(3)) else coefficients
    return np.asarray(lit) * strength, f"environment '{image.name}'"
