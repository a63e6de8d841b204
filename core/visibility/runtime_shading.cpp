#include "visibility/runtime_shading.hpp"

#include <chrono>
#include <string>

#include "common/error.hpp"

namespace penumbra::visibility {

RuntimeResult shade_pose(const PoseModel& model, const sh::PoseShader& shader, const float* joint_rotations,
                         const std::vector<float>& positions, const std::vector<float>& normals,
                         const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& neighbours,
                         const Eigen::MatrixXd& lighting, const sh::ShadingParameters& parameters) {
    using Clock = std::chrono::steady_clock;
    const std::size_t V = model.vertex_count;
    if (positions.size() != 3 * V || normals.size() != 3 * V)
        throw ArgumentError("the mesh has " + std::to_string(positions.size() / 3) + " vertices but the model was baked for " +
                            std::to_string(V));
    if (shader.order() != model.order)
        throw ArgumentError("shader order " + std::to_string(shader.order()) + " differs from the model's " +
                            std::to_string(model.order));
    RuntimeResult result;
    const int d = model.params_per_vertex();

    // §4.3 step 1: ZH lobes from the pose.
    auto t0 = Clock::now();
    std::vector<float> params(V * d), axes(V * model.lobes * 3), bands(V * model.lobes * model.order);
    synthesize_lobes(model, joint_rotations, params.data(), axes.data(), bands.data(), parameters.threads);
    auto t1 = Clock::now();

    // The frames the lobes live in, from the deformed mesh.
    std::vector<float> frames(9 * V), tangent(3 * V), normal(3 * V);
    vertex_frames(positions, normals, triangles, neighbours, frames.data(), &result.frame_stats, parameters.threads);
    for (std::size_t v = 0; v < V; ++v)
        for (int k = 0; k < 3; ++k) {
            tangent[3 * v + k] = frames[9 * v + k];
            normal[3 * v + k] = frames[9 * v + 6 + k];
        }
    auto t2 = Clock::now();

    // §4.3 steps 2–5.
    result.rgb.assign(3 * V, 0.0f);
    result.visibility.assign(V, 0.0f);
    sh::PoseBuffers<float> buffers;
    buffers.vertex_count = V;
    buffers.lobes_per_vertex = model.lobes;
    buffers.lobe_axes = axes.data();
    buffers.lobe_bands = bands.data();
    buffers.normals = normal.data();
    buffers.tangents = tangent.data();
    buffers.positions = positions.data();
    buffers.rgb = result.rgb.data();
    buffers.visibility = result.visibility.data();
    result.stats = shader.shade(lighting, parameters, buffers);
    auto t3 = Clock::now();
    result.timings.pose_to_lobes = std::chrono::duration<double>(t1 - t0).count();
    result.timings.frames = std::chrono::duration<double>(t2 - t1).count();
    result.timings.shading = std::chrono::duration<double>(t3 - t2).count();
    return result;
}

}  // namespace penumbra::visibility
