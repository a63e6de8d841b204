// The run time of the visibility baker (paper §4.3): a pose in, a shade per
// vertex out. Step 1 (ZH lobes from the pose) is pose_model.hpp's
// synthesis; the tangent frames come from the deformed mesh
// (mesh_frames.hpp, the same rule the bake used); steps 2–5 are the SH
// engine's PoseShader (sh/pose_shading.hpp).
//
// Two entries:
//  - shade_frame, what the Blender handler calls every frame: the evaluated
//    mesh's object-space positions and its world matrix in; the normals by
//    Blender's rule (vertex_normals.hpp) instead of Blender's own, and every
//    per-vertex step (normal, frame, lobes, shade, clamp) fused into one
//    parallel pass over blocks of vertices that stay in cache, writing the
//    point attributes' layout (RGBA) directly;
//  - shade_pose_model, the same shading of the model's pose from world-space
//    normals the caller supplies, in separate passes (kept for callers with
//    their own normals; bound as PoseModel.shade). Not _penumbra.sh.shade_pose,
//    which runs the SH engine's PoseShader on lobes the caller already has.
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "sh/pose_shading.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/pose_model.hpp"
#include "visibility/vertex_normals.hpp"

namespace penumbra::visibility {

struct ShadingTimings {
    // Seconds. shade_frame: normals is the face pass (face normals and
    // corner angles, its own parallel loop); the fused pass's wall time is
    // split in proportion to the thread time each step took, frames then
    // being the vertex normals from the face pass, the world transform and
    // the tangent frames.
    double normals = 0.0;
    double pose_to_lobes = 0.0;  // synthesis + Lambert → axis
    double frames = 0.0;         // tangent frames of the deformed mesh
    double shading = 0.0;        // PoseShader (and, in shade_frame, the clamped write)
};

struct ShadingResult {
    std::vector<float> rgb;         // V × 3, scene-linear
    std::vector<float> visibility;  // V, cosine-weighted visibility (AO) in [0, 1] up to SH ringing
    sh::ShadingStats stats;
    FrameStats frame_stats;
    ShadingTimings timings;
};

// joint_rotations: model.joints × 9 (row-major rest-relative rotations);
// positions and normals: V × 3 world space of the deformed mesh; triangles and
// neighbours as at bake time (reference_neighbours); lighting (order², 3).
// The shader's order must equal the model's. ArgumentError on size mismatch.
ShadingResult shade_pose_model(const PoseModel& model, const sh::PoseShader& shader, const float* joint_rotations,
                               const std::vector<float>& positions, const std::vector<float>& normals,
                               const std::vector<std::uint32_t>& triangles,
                               const std::vector<std::uint32_t>& neighbours, const Eigen::MatrixXd& lighting,
                               const sh::ShadingParameters& parameters);

// What shade_frame keeps of a mesh from frame to frame: its polygons and
// reference neighbours (the bake's).
struct ShadingMesh {
    ShadingMesh(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                const std::vector<std::uint32_t>& polygon_vertices);
    PolygonMesh polygons;
    std::vector<std::uint32_t> neighbours;

    // The face pass's output, kept from frame to frame (fresh megabyte-sized
    // arrays every frame cost page faults); shade_frame holds the mutex, so
    // calls on one mesh take turns.
    struct FaceScratch {
        std::mutex mutex;
        std::vector<float> face_normals, corner_angles;
    };
    mutable FaceScratch scratch;
};

struct FrameResult {
    sh::ShadingStats stats;
    FrameStats frame_stats;  // repaired_normals: Blender's rule gave a zero normal (+z world used)
    ShadingTimings timings;
};

// One frame: joint_rotations as for shade_pose_model; positions V × 3 in object
// space (the evaluated mesh's); world the object's 4 × 4 matrix (normals
// go by its inverse transpose; a singular one leaves them as they are).
// Writes rgba_out (V × 4: scene-linear RGB clamped to ≥ 0, alpha 1) and
// visibility_out (V, clamped to [0, 1]). ArgumentError on a size or order
// mismatch, before anything is written.
FrameResult shade_frame(const PoseModel& model, const sh::PoseShader& shader, const ShadingMesh& mesh,
                        const float* joint_rotations, const float* positions, const Eigen::Matrix4d& world,
                        const Eigen::MatrixXd& lighting, const sh::ShadingParameters& parameters, float* rgba_out,
                        float* visibility_out);

}  // namespace penumbra::visibility
