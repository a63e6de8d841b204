"""The GLSL that evaluates the pose model in the GPU preview's vertex shader
(paper §4.3 step 1, then the frame), and the numpy packing of what it reads.
Plain Python and numpy: no bpy, no gpu (gpu_model.py uploads).

Once per model, four 2D float textures, read with texelFetch, texel i at
(i mod width, i div width), the width fixed per model by texture_width():
- model_weights (RGBA16F): every stored joint block's rows, the binary16
  values as stored (exact in RGBA16F), each row of d parameters padded to
  whole texels (R = ⌈d/4⌉ texels a row), block after block;
- model_bias (RGBA32F): each vertex's bias, R texels a vertex;
- model_blocks (RGBA32F): per block (first feature of its joint, its
  directions c_e, its power-of-two scale, its first row in model_weights);
- model_layout (RGBA32F): per vertex (first block, block count, reference
  neighbour, 0).
Integers ride in floats: exact below 2^24, which pack_model checks.

- model_corners (RGBA32F): each vertex's polygon corners (polygon's first
  loop, size, the corner's place), vertex after vertex, model_layout's w
  saying where each vertex's start; model_loops (R32F): the polygons'
  vertices. The vertex normals come from these (Blender's rule, as the CPU
  computes them), so no normal crosses the bus per frame.

Per frame, the uniform block PenumbraPose (the pose's features, 4 a vec4,
and the object's world matrix split as the CPU splits it) and one R32F
texture frame_geometry: the evaluated mesh's object-space positions, one
float a texel.
The vertex reads its own and its reference neighbour's position, so the
tangent follows the same edge as core/visibility/mesh_frames.hpp's, with the
same fallback (Duff et al. 2017) where the edge is along the normal.
"""

import functools

import numpy as np

EXACT_INTEGER = 1 << 24  # floats hold every integer below this
FEATURE_VEC4_STEP = 16   # feature array sizes round up to this many vec4s (fewer shader variants)


def texels_per_row(order, lobes):
    return -(-lobes * (2 + order) // 4)


def texture_width(max_texture_size):
    """The width every model texture is laid out at: wide rows, within the limit."""
    return int(min(max_texture_size, 4096))


def texture_grid(texel_count, width, max_texture_size):
    """(width, height) of a texture holding texel_count texels at `width`;
    ValueError past the GPU's size limit."""
    height = max(1, -(-int(texel_count) // width))
    if height > max_texture_size:
        raise ValueError(f"the GPU preview needs a {width} × {height} texture; this GPU allows "
                         f"{max_texture_size} × {max_texture_size}")
    return width, height


def grid_array(texels, width, max_texture_size):
    """Texels (N, 4) float32 zero-padded to a whole grid: ((W, H), flat float32)."""
    size = texture_grid(len(texels), width, max_texture_size)
    flat = np.zeros(size[0] * size[1] * 4, dtype=np.float32)
    flat[:texels.size] = texels.reshape(-1)
    return size, flat


def feature_vec4_count(feature_count):
    need = max(1, -(-int(feature_count) // 4))
    return -(-need // FEATURE_VEC4_STEP) * FEATURE_VEC4_STEP


def pack_model(blocks, order, lobes, neighbours, polygon_sizes, polygon_vertices):
    """The model textures' texels from PoseModel.stored_blocks(), the
    reference neighbours and the polygons: {'model_weights', 'model_bias',
    'model_blocks', 'model_layout', 'model_corners': (N, 4) float32,
    'model_loops': (N,) float32}."""
    d = lobes * (2 + order)
    rows_per_texel = texels_per_row(order, lobes)
    bias = np.asarray(blocks["bias"], dtype=np.float32).reshape(-1, d)
    vertex_count = len(bias)
    directions = np.asarray(blocks["block_directions"], dtype=np.int64)
    joint_offsets = np.asarray(blocks["joint_offsets"], dtype=np.int64)
    feature_offsets = np.asarray(blocks["feature_offsets"], dtype=np.int64)
    rows = int(directions.sum())
    if max(rows, len(directions), vertex_count) >= EXACT_INTEGER:
        raise ValueError(f"the GPU preview indexes at most {EXACT_INTEGER - 1} vertices, blocks or weight rows")
    halves = np.asarray(blocks["weights"], dtype=np.uint16).view(np.float16).astype(np.float32).reshape(rows, d)
    padded = np.zeros((rows, 4 * rows_per_texel), dtype=np.float32)
    padded[:, :d] = halves
    bias_padded = np.zeros((vertex_count, 4 * rows_per_texel), dtype=np.float32)
    bias_padded[:, :d] = bias
    first_row = np.concatenate([[0], np.cumsum(directions)[:-1]]) if len(directions) else np.zeros(0)
    block_texels = np.stack([feature_offsets[np.asarray(blocks["joint_index"], dtype=np.int64)], directions,
                             np.asarray(blocks["weight_scales"], dtype=np.float64), first_row], axis=1)
    corners, corner_start = incident_corners(vertex_count, polygon_sizes, polygon_vertices)
    # One texel more than the vertices: the last one's w ends the last vertex's corners.
    layout = np.zeros((vertex_count + 1, 4), dtype=np.float32)
    layout[:-1, 0] = joint_offsets[:-1]
    layout[:-1, 1] = np.diff(joint_offsets)
    layout[:-1, 2] = np.asarray(neighbours, dtype=np.int64)
    layout[:, 3] = corner_start
    return {"model_weights": padded.reshape(-1, 4), "model_bias": bias_padded.reshape(-1, 4),
            "model_blocks": block_texels.astype(np.float32).reshape(-1, 4), "model_layout": layout,
            "model_corners": corners, "model_loops": np.asarray(polygon_vertices, dtype=np.float32)}


def incident_corners(vertex_count, polygon_sizes, polygon_vertices):
    """Each vertex's polygon corners, vertex after vertex and, within one, in
    ascending polygon order (Blender's, core/visibility/vertex_normals.cpp):
    texels (polygon's first loop, its size, the corner's place in it, 0),
    and where each vertex's start (V + 1)."""
    sizes = np.asarray(polygon_sizes, dtype=np.int64)
    loops = np.asarray(polygon_vertices, dtype=np.int64)
    if len(loops) >= EXACT_INTEGER:
        raise ValueError(f"the GPU preview indexes at most {EXACT_INTEGER - 1} polygon corners")
    face_start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    face = np.repeat(np.arange(len(sizes)), sizes)
    order = np.argsort(loops, kind="stable")
    corners = np.zeros((len(loops), 4), dtype=np.float32)
    corners[:, 0] = face_start[face[order]]
    corners[:, 1] = sizes[face[order]]
    corners[:, 2] = order - face_start[face[order]]
    start = np.concatenate([[0], np.cumsum(np.bincount(loops, minlength=vertex_count))])
    return corners, start


def pose_data(features, feature_vec4s, world):
    """PenumbraPose's bytes: the features, then the world matrix as the core
    splits it (linear, normal matrix = inverse transpose, or identity when
    singular; offset), columns as vec4s."""
    data = np.zeros((feature_vec4s + 7, 4), dtype=np.float32)
    flat = data[:feature_vec4s].reshape(-1)
    flat[:len(features)] = features
    data[feature_vec4s:] = _world_columns(np.asarray(world, dtype=np.float64).reshape(4, 4).tobytes())
    return data.tobytes()


@functools.lru_cache(maxsize=16)
def _world_columns(world_bytes):
    """The world matrix's 7 vec4s of PenumbraPose. Kept per matrix: while a
    bone is posed the object stays put, and the inverse is most of the cost."""
    world = np.frombuffer(world_bytes, dtype=np.float64).reshape(4, 4)
    linear = world[:3, :3]
    determinant = np.linalg.det(linear)
    normal_matrix = np.linalg.inv(linear).T if determinant != 0.0 and np.isfinite(determinant) else np.eye(3)
    columns = np.zeros((7, 4), dtype=np.float32)
    columns[0:3, :3] = linear.T
    columns[3:6, :3] = normal_matrix.T
    columns[6, :3] = world[:3, 3]
    columns.setflags(write=False)
    return columns


def pose_block_source(feature_vec4s):
    return (f"struct PenumbraPose {{\n"
            f"  vec4 features[{feature_vec4s}];\n"
            f"  vec4 world_linear[3];\n"          # columns of the world matrix's 3 × 3
            f"  vec4 normal_matrix[3];\n"   # columns of its inverse transpose
            f"  vec4 offset;\n"
            f"}};\n")


def geometry_floats(positions):
    """frame_geometry's values: every position (3V float32)."""
    return np.asarray(positions, dtype=np.float32).reshape(-1)


class GeometryGrid:
    """frame_geometry (R32F, one float a texel: a frame's positions go in by
    one contiguous copy), kept from frame to frame (the texture copies it
    when made)."""

    def __init__(self, vertex_count, width, max_texture_size):
        self.vertex_count = vertex_count
        self.size = texture_grid(3 * vertex_count, width, max_texture_size)
        self.flat = np.zeros(self.size[0] * self.size[1], dtype=np.float32)

    @property
    def positions(self):
        """(V, 3) float32 view of the grid that a mesh's positions are read into
        directly (the copy fill() makes costs as much as the read at 100k)."""
        return self.flat[:3 * self.vertex_count].reshape(self.vertex_count, 3)

    def fill(self, positions):
        self.flat[:3 * self.vertex_count] = np.asarray(positions, dtype=np.float32).reshape(-1)
        return self.size, self.flat


def helper_source(width):
    return (f"ivec2 texel_at(int i) {{ return ivec2(i % {width}, i / {width}); }}\n"
            "vec3 geometry_at(int i)\n{\n"
            "  return vec3(texelFetch(frame_geometry, texel_at(i), 0).r, texelFetch(frame_geometry, texel_at(i + 1), 0).r,\n"
            "              texelFetch(frame_geometry, texel_at(i + 2), 0).r);\n}\n"
            "int loop_vertex(int i) { return int(texelFetch(model_loops, texel_at(i), 0).r); }\n"
            # Blender's math::safe_acos_approx, as the CPU's corner angles take it
            # (core/visibility/vertex_kernels.cpp): the exact acos differs by up to
            # 4.5e-5 rad, which a reference edge nearly along the normal amplifies
            # into the tangent (2.6e-3 of Phong shading on a twisted character).
            "float safe_acos_approx(float x)\n{\n"
            "  float f = abs(x);\n"
            "  float m = f < 1.0 ? 1.0 - (1.0 - f) : 1.0;\n"
            "  float a = sqrt(1.0 - m) * (1.5707963267 + m * (-0.213300989 + m * (0.077980478 + m * -0.02164095)));\n"
            "  return x < 0.0 ? 3.14159265358979 - a : a;\n}\n"
            # Blender 4.x/5.x's vertex normal (core/visibility/vertex_normals.hpp):
            # over the vertex's faces, Newell's face normal times the corner's angle.
            "vec3 vertex_normal(int vertex, vec3 own)\n{\n"
            "  int begin = int(texelFetch(model_layout, texel_at(vertex), 0).w);\n"
            "  int end = int(texelFetch(model_layout, texel_at(vertex + 1), 0).w);\n"
            "  vec3 sum = vec3(0.0);\n"
            "  for (int k = begin; k < end; k++) {\n"
            "    vec4 corner = texelFetch(model_corners, texel_at(k), 0);\n"
            "    int first = int(corner.x), size = int(corner.y), at = int(corner.z);\n"
            "    vec3 face = vec3(0.0), previous = geometry_at(3 * loop_vertex(first + size - 1));\n"
            "    for (int i = 0; i < size; i++) {\n"
            "      vec3 current = geometry_at(3 * loop_vertex(first + i));\n"
            "      face += vec3((previous.y - current.y) * (previous.z + current.z),\n"
            "                   (previous.z - current.z) * (previous.x + current.x),\n"
            "                   (previous.x - current.x) * (previous.y + current.y));\n"
            "      previous = current;\n"
            "    }\n"
            "    float face_length = length(face);\n"
            "    face = face_length > 0.0 ? face * (1.0 / face_length) : vec3(0.0, 0.0, 1.0);\n"
            "    vec3 to_previous = geometry_at(3 * loop_vertex(first + (at + size - 1) % size)) - own;\n"
            "    vec3 to_next = geometry_at(3 * loop_vertex(first + (at + 1) % size)) - own;\n"
            "    float cosine = dot(normalize(to_previous), normalize(to_next));\n"
            "    sum += face * safe_acos_approx(cosine);\n"
            "  }\n"
            "  float sum_length = length(sum);\n"
            "  if (begin == end) { return normalize(own); }  // no face: the position's direction, as Blender\n"
            "  return sum_length > 0.0 ? sum / sum_length : vec3(0.0);\n}\n"
            # Duff et al. 2017 (mesh_frames.cpp basis_from_normal): t from n alone.
            "vec3 tangent_from_normal(vec3 n)\n{\n"
            "  float sign_z = n.z >= 0.0 ? 1.0 : -1.0;\n"
            "  float a = -1.0 / (sign_z + n.z);\n"
            "  return vec3(1.0 + sign_z * n.x * n.x * a, sign_z * n.x * n.y * a, -sign_z * n.x);\n}\n")


def main_prologue(order, lobes):
    """main()'s first lines in the model path: the vertex's world position,
    normal and tangent (p_position, p_normal, p_tangent, as the attribute path
    has them), and its lobe parameters q[] from the model and the pose."""
    r = texels_per_row(order, lobes)
    return [
        "  int vertex = p_vertex;",
        "  vec4 vertex_layout = texelFetch(model_layout, texel_at(vertex), 0);",
        "  vec3 own = geometry_at(3 * vertex);",
        "  vec3 normal_object = vertex_normal(vertex, own);",
        "  int neighbour = int(vertex_layout.z);",
        "  vec3 other = geometry_at(3 * neighbour);",
        "  mat3 object_to_world = mat3(pose.world_linear[0].xyz, pose.world_linear[1].xyz, pose.world_linear[2].xyz);",
        "  mat3 normal_matrix = mat3(pose.normal_matrix[0].xyz, pose.normal_matrix[1].xyz, pose.normal_matrix[2].xyz);",
        "  vec3 p_position = object_to_world * own + pose.offset.xyz;",
        "  vec3 p_normal = normal_matrix * normal_object;",
        # The reference edge, projected on the tangent plane (mesh_frames.cpp vertex_frame).
        "  vec3 edge = (object_to_world * other + pose.offset.xyz) - p_position;",
        "  float normal_length = length(p_normal);",
        "  vec3 unit_normal = normal_length > 0.0 ? p_normal / normal_length : vec3(0.0, 0.0, 1.0);",
        "  vec3 p_tangent = edge - unit_normal * dot(unit_normal, edge);",
        "  float tangent_length = length(p_tangent);",
        "  bool from_edge = neighbour != vertex && tangent_length > 1e-3 * length(edge) && !isinf(tangent_length);",
        "  p_tangent = from_edge ? p_tangent / tangent_length : tangent_from_normal(unit_normal);",
        f"  vec4 q[{r}];",
        f"  for (int k = 0; k < {r}; k++) {{ q[k] = texelFetch(model_bias, texel_at(vertex * {r} + k), 0); }}",
        "  float lx, ly, r2, pull, s_rest;",
        "  bool usable;",
        "  int first_block = int(vertex_layout.x), block_end = int(vertex_layout.x) + int(vertex_layout.y);",
        "  for (int e = first_block; e < block_end; e++) {",
        "    vec4 block = texelFetch(model_blocks, texel_at(e), 0);",
        "    int feature = int(block.x), directions = int(block.y), row = int(block.w);",
        "    for (int c = 0; c < directions; c++) {",
        "      float z = pose.features[(feature + c) / 4][(feature + c) % 4] * block.z;",
        f"      for (int k = 0; k < {r}; k++) {{ q[k] += z * texelFetch(model_weights, texel_at((row + c) * {r} + k), 0); }}",
        "    }",
        "  }",
    ]


def lobe_from_parameters(order, lobe):
    """Lines setting `a` (unit axis, local frame) and g[] (bands) of one lobe
    from q[]: lambert_to_axis as core/visibility/vertex_kernels.cpp has it
    (outside the disc r = 2 pulled onto its rim; non-finite: +z)."""
    base = lobe * (2 + order)

    def q(k):
        return f"q[{k // 4}].{'xyzw'[k % 4]}"

    lines = [f"  // lobe {lobe}: Lambert azimuthal (X, Y) and band coefficients",
             f"  lx = {q(base)}; ly = {q(base + 1)};",
             "  r2 = lx * lx + ly * ly;",
             "  usable = !isnan(r2) && !isinf(r2);",
             "  pull = (usable && r2 > 4.0) ? 2.0 / sqrt(r2) : 1.0;",
             "  lx *= pull; ly *= pull; r2 = (usable && r2 > 4.0) ? 4.0 : r2;",
             "  s_rest = sqrt(max(1.0 - 0.25 * r2, 0.0));",
             "  a = usable ? vec3(s_rest * lx, s_rest * ly, 1.0 - 0.5 * r2) : vec3(0.0, 0.0, 1.0);"]
    lines += [f"  g[{l}] = {q(base + 2 + l)};" for l in range(order)]
    return lines
