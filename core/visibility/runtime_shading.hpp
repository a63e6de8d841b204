// The run time of the visibility baker (paper §4.3): a pose in, a shade per
// vertex out. Step 1 (ZH lobes from the pose) is pose_model.hpp's
// synthesize_params; the tangent frames come from the deformed mesh
// (mesh_frames.hpp, the same rule the bake used); steps 2–5 are the SH
// engine's PoseShader (sh/pose_shading.hpp).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "sh/pose_shading.hpp"
#include "visibility/pose_model.hpp"

namespace penumbra::visibility {

struct RuntimeTimings {
    double pose_to_lobes = 0.0;  // seconds: synthesize_params + params_to_lobes
    double frames = 0.0;         // seconds: tangent frames of the deformed mesh
    double shading = 0.0;        // seconds: PoseShader::shade
};

struct RuntimeResult {
    std::vector<float> rgb;         // V × 3, scene-linear
    std::vector<float> visibility;  // V, cosine-weighted visibility (AO) in [0, 1] up to SH ringing
    sh::ShadingStats stats;
    FrameStats frame_stats;
    RuntimeTimings timings;
};

// joint_rotations: model.joints × 9 (row-major rest-relative rotations);
// positions and normals: V × 3 world space of the deformed mesh; triangles and
// neighbours as at bake time (reference_neighbours); lighting (order², 3).
// The shader's order must equal the model's. ArgumentError on size mismatch.
RuntimeResult shade_pose(const PoseModel& model, const sh::PoseShader& shader, const float* joint_rotations,
                         const std::vector<float>& positions, const std::vector<float>& normals,
                         const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& neighbours,
                         const Eigen::MatrixXd& lighting, const sh::ShadingParameters& parameters);

}  // namespace penumbra::visibility
