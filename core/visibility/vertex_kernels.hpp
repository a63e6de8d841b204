// Internal to the frame shading (visibility/frame_shading.hpp), Blender's
// vertex normals and the pose model's synthesis: their per-vertex and
// per-face loops in SIMD lanes of floats, compiled once per target by
// Highway (visibility/vertex_kernels.cpp, like sh/pose_shading_kernel.cpp)
// and chosen at run time, so the portable build runs AVX-512 or AVX2 where
// the CPU has them. EMU128 (one lane) is the scalar reference.
#pragma once

#include <cstddef>
#include <cstdint>

namespace penumbra::visibility::detail {

// Blender's face normals and corner angles (vertex_normals.hpp) of the
// faces faces[0 .. count): face_start (F + 1 offsets into corner_vertex),
// positions (V × 3). Every listed face has `size` corners (3 or 4: SIMD
// lanes of faces), or any number when size is 0 (one at a time). Writes
// face_normals (F × 3) and corner_angles (C) of those faces. Bit-identical on
// every target (the same IEEE operations in the same order in every lane;
// this file is compiled without FMA contraction).
void face_normals_range(const std::uint32_t* face_start, const std::uint32_t* corner_vertex, const float* positions,
                        const std::uint32_t* faces, std::size_t count, int size, float* face_normals,
                        float* corner_angles);

// What a vertex's Blender normal is made of after the face pass: its faces
// [vertex_start[v], vertex_start[v + 1]) of incident_face, each weighted by
// the corner angle incident_corner names.
// face_normals holds one float past the last face's normal (read, unused).
struct NormalSources {
    const std::uint32_t* vertex_start;
    const std::uint32_t* incident_face;
    const std::uint32_t* incident_corner;
    const float* face_normals;
    const float* corner_angles;
};

// Blender's vertex normals (object space) of vertices [begin, end) from the
// face pass (vertex_normals.hpp's rule), written to normals_out row
// v − begin. Bit-identical on every target.
void vertex_normals_range(const NormalSources& sources, const float* positions, std::size_t begin, std::size_t end,
                          float* normals_out);

// The object's transform: world = linear · p + offset; normals go by
// normal_matrix (the inverse transpose). Row-major.
struct FrameTransform {
    float linear[9], normal_matrix[9], offset[3];
};

struct FrameCounts {
    std::size_t repaired = 0;  // normals that were zero (or non-finite) in world space: +z used
    std::size_t fallback = 0;  // tangents from the normal alone (mesh_frames.hpp's rule)
};

// Vertices [begin, end): their Blender normals (object space, from
// `sources`, as vertex_normals_range makes them) → world-space unit
// normals, world positions and unit tangents, each
// as three rows x, y, z `stride` floats apart (sh::PoseBlock's layout;
// vertex v in column v − begin), by mesh_frames.hpp's rule: the tangent
// follows the edge to the reference neighbour, projected onto the tangent
// plane, or Duff et al.'s frame of the normal when that edge is within ~0.06°
// of the normal (or the vertex is its own neighbour).
void frames_range(const FrameTransform& transform, const NormalSources& sources, const float* positions,
                  const std::uint32_t* neighbours, std::size_t begin, std::size_t end, std::size_t stride,
                  float* normals_out, float* tangents_out, float* positions_out, FrameCounts& counts);

// Lobe parameters (count lobes of 2 + order each: Lambert X, Y, then the
// bands) → unit axes (count × 3) and bands (count × order): the loop of
// pose_model.hpp's lobes_from_params, over all lobes of all its vertices.
void lobes_from_params(int order, std::size_t count, const float* params, float* axes_out, float* bands_out);

// The pose model's arrays the synthesis reads (pose_model.hpp's PoseModel).
struct PoseBlocks {
    int d;                                // lobe parameters per vertex
    const std::uint32_t* feature_offsets;  // per joint: its features (m_j of them)
    const std::uint32_t* joint_offsets;    // per vertex: its blocks
    const std::uint16_t* joint_index;      // per block: its joint
    const std::uint8_t* block_directions;  // per block: how many of its joint's features it weighs
    const std::uint64_t* weight_offsets;   // per vertex: where its blocks' weights start
    const float* bias;                     // per vertex, d floats
    const std::uint16_t* weights;          // per block, m_j × d binary16
    const float* scales;                   // per block
};

// The pose model's linear map applied to the pose's features: the lobe
// parameters of vertices [begin, end) (pose_model.hpp's
// synthesize_params_range and synthesize_rows). Per vertex v, bias[v] (d
// floats) plus, for each stored joint block e, the joint's first c_e
// features times scales[e] times the block's c_e × d binary16 weights
// (weight_blocks.hpp). On targets with FMA the multiply-adds are fused (the
// result differs from the others by float rounding). stride 0: d floats per
// vertex from params_out[0]; otherwise d rows `stride` floats apart, vertex v
// in column v − begin (sh::PoseBlock's layout).
void apply_pose_blocks(const PoseBlocks& blocks, const float* features, std::size_t begin, std::size_t end,
                       float* params_out, std::size_t stride = 0);

}  // namespace penumbra::visibility::detail
