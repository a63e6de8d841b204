#include "visibility/frame_shading.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <Eigen/LU>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "visibility/vertex_kernels.hpp"

namespace penumbra::visibility {

ShadingResult shade_pose_model(const PoseModel& model, const sh::PoseShader& shader, const float* joint_rotations,
                               const std::vector<float>& positions, const std::vector<float>& normals,
                               const std::vector<std::uint32_t>& triangles,
                               const std::vector<std::uint32_t>& neighbours, const Eigen::MatrixXd& lighting,
                               const sh::ShadingParameters& parameters) {
    using Clock = std::chrono::steady_clock;
    const std::size_t V = model.vertex_count;
    if (positions.size() != 3 * V || normals.size() != 3 * V)
        throw ArgumentError("the mesh has " + std::to_string(positions.size() / 3) + " vertices but the model was baked for " +
                            std::to_string(V));
    if (shader.order() != model.order)
        throw ArgumentError("shader order " + std::to_string(shader.order()) + " differs from the model's " +
                            std::to_string(model.order));
    ShadingResult result;
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


ShadingMesh::ShadingMesh(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                         const std::vector<std::uint32_t>& polygon_vertices)
    : polygons(vertex_count, polygon_sizes, polygon_vertices),
      neighbours(reference_neighbours(vertex_count, polygon_sizes, polygon_vertices)) {}

namespace {

using Clock = std::chrono::steady_clock;

// Vertices that go through every step together: their scratch (~40 floats
// each) stays in the core's L1/L2 between the steps.
constexpr std::size_t kChunk = 256;
// Vertices per parallel task: a multiple of kChunk and of every SIMD
// target's lanes, ~0.3 ms of work.
constexpr std::size_t kTask = 4096;

enum Step { kFrames, kLobes, kShading, kSteps };

// What one frame shares between the tasks.
struct FrameJob {
    const PoseModel& model;
    const ShadingMesh& mesh;
    const sh::PreparedShading& shading;
    const float* features;
    const float* positions;
    const float* face_normals;
    const float* corner_angles;
    detail::FrameTransform transform;
    float* rgba_out;
    float* visibility_out;
};

// Per-chunk arrays: rows of kChunk floats in sh::PoseBlock's layout (zero
// past a short last chunk).
struct ChunkScratch {
    explicit ChunkScratch(const PoseModel& model)
        : normals(3 * kChunk), tangents(3 * kChunk), positions(3 * kChunk),
          params(kChunk * model.params_per_vertex()), rgb(3 * kChunk), visibility(kChunk) {}
    std::vector<float> normals, tangents, positions, params, rgb, visibility;
};

struct TaskTotals {
    std::array<std::int64_t, kSteps> nanoseconds{};
    std::size_t invalid = 0, repaired = 0, fallback = 0;
};

// Blender's normal of each vertex, then world normals, positions and
// tangents (vertex_kernels.hpp, SIMD lanes).
void chunk_frames(const FrameJob& job, std::size_t begin, std::size_t end, ChunkScratch& s, TaskTotals& totals) {
    detail::FrameCounts counts;
    detail::frames_range(job.transform, job.mesh.polygons.normal_sources(job.face_normals, job.corner_angles),
                         job.positions, job.mesh.neighbours.data(), begin, end, kChunk, s.normals.data(),
                         s.tangents.data(), s.positions.data(), counts);
    totals.repaired += counts.repaired;
    totals.fallback += counts.fallback;
}

// Shades the chunk and writes the attributes' layout, clamped (SH
// truncation and model error can overshoot a little: visibility is a
// fraction, radiance is never negative; NaN cannot come out of a valid
// vertex, and would become 0).
void chunk_shade(const FrameJob& job, std::size_t begin, std::size_t end, ChunkScratch& s, TaskTotals& totals) {
    const std::size_t count = end - begin;
    sh::PoseBlock block;
    block.vertex_count = count;
    block.stride = kChunk;
    block.lobe_params = s.params.data();
    block.normals = s.normals.data();
    block.tangents = s.tangents.data();
    block.positions = s.positions.data();
    block.rgb = s.rgb.data();
    block.visibility = s.visibility.data();
    totals.invalid += job.shading.shade_block(block);
    for (std::size_t i = 0; i < count; ++i) {
        float* out = job.rgba_out + 4 * (begin + i);
        for (int c = 0; c < 3; ++c) out[c] = s.rgb[c * kChunk + i] > 0.0f ? s.rgb[c * kChunk + i] : 0.0f;
        out[3] = 1.0f;
        const float ao = s.visibility[i];
        job.visibility_out[begin + i] = ao > 0.0f ? std::min(ao, 1.0f) : 0.0f;
    }
}

void run_task(const FrameJob& job, std::size_t begin, std::size_t end, TaskTotals& totals) {
    ChunkScratch scratch(job.model);
    const auto add = [&](Step step, Clock::time_point& since) {
        const auto now = Clock::now();
        totals.nanoseconds[step] += std::chrono::duration_cast<std::chrono::nanoseconds>(now - since).count();
        since = now;
    };
    for (std::size_t chunk = begin; chunk < end; chunk += kChunk) {
        const std::size_t stop = std::min(end, chunk + kChunk);
        auto since = Clock::now();
        chunk_frames(job, chunk, stop, scratch, totals);
        add(kFrames, since);
        // The shader reads the lobe parameters and turns them into axes itself.
        synthesize_rows(job.model, job.features, chunk, stop, scratch.params.data(), kChunk);
        add(kLobes, since);
        chunk_shade(job, chunk, stop, scratch, totals);
        add(kShading, since);
    }
}

// world = linear · p + offset; normals by the inverse transpose (non-uniform
// scale); a singular matrix (a zero scale) leaves them as they are.
detail::FrameTransform frame_transform(const Eigen::Matrix4d& world) {
    const Eigen::Matrix3d linear = world.topLeftCorner<3, 3>();
    Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Identity();
    const double determinant = linear.determinant();
    if (determinant != 0.0 && std::isfinite(determinant)) normal_matrix = linear.inverse().transpose();
    detail::FrameTransform t;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            t.linear[3 * i + j] = float(linear(i, j));
            t.normal_matrix[3 * i + j] = float(normal_matrix(i, j));
        }
        t.offset[i] = float(world(i, 3));
    }
    return t;
}


}  // namespace

FrameResult shade_frame(const PoseModel& model, const sh::PoseShader& shader, const ShadingMesh& mesh,
                        const float* joint_rotations, const float* positions, const Eigen::Matrix4d& world,
                        const Eigen::MatrixXd& lighting, const sh::ShadingParameters& parameters, float* rgba_out,
                        float* visibility_out) {
    const std::size_t V = model.vertex_count;
    if (mesh.polygons.vertex_count() != V)
        throw ArgumentError("the mesh has " + std::to_string(mesh.polygons.vertex_count()) +
                            " vertices but the model was baked for " + std::to_string(V));
    if (shader.order() != model.order)
        throw ArgumentError("shader order " + std::to_string(shader.order()) + " differs from the model's " +
                            std::to_string(model.order));
    if (!world.allFinite()) throw ArgumentError("the object's world matrix is not finite");
    const std::vector<float> features = pose_features(model, joint_rotations);
    const sh::PreparedShading shading = shader.prepare(lighting, parameters, model.lobes, true);
    FrameResult result;
    if (V == 0) return result;

    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(mesh.scratch.mutex);
    std::vector<float>& face_normals = mesh.scratch.face_normals;
    std::vector<float>& corner_angles = mesh.scratch.corner_angles;
    face_normals.resize(3 * mesh.polygons.face_count() + 1);  // + 1: NormalSources reads 4 floats a face
    corner_angles.resize(mesh.polygons.corner_count());
    mesh.polygons.face_pass(positions, face_normals.data(), corner_angles.data(), parameters.threads);
    const auto t1 = Clock::now();

    FrameJob job{model, mesh, shading, features.data(), positions, face_normals.data(), corner_angles.data(),
                 frame_transform(world), rgba_out, visibility_out};

    std::vector<TaskTotals> totals(block_count(V, kTask));
    parallel_blocks(V, {parameters.threads, kTask, "visibility.shade_frame"},
                    [&](std::size_t task, std::size_t begin, std::size_t end) { run_task(job, begin, end, totals[task]); });
    const auto t2 = Clock::now();

    std::array<double, kSteps> thread_seconds{};
    for (const TaskTotals& t : totals) {
        for (int k = 0; k < kSteps; ++k) thread_seconds[k] += 1e-9 * double(t.nanoseconds[k]);
        result.stats.invalid_vertices += t.invalid;
        result.frame_stats.repaired_normals += t.repaired;
        result.frame_stats.fallback_tangents += t.fallback;
    }
    // The fused pass's wall time, split by each step's share of its thread time.
    double sum = 0.0;
    for (const double x : thread_seconds) sum += x;
    const double wall = std::chrono::duration<double>(t2 - t1).count();
    const auto share = [&](Step step) { return sum > 0.0 ? wall * thread_seconds[step] / sum : 0.0; };
    result.timings.normals = std::chrono::duration<double>(t1 - t0).count();
    result.timings.frames = share(kFrames);
    result.timings.pose_to_lobes = share(kLobes);
    result.timings.shading = share(kShading);
    return result;
}

}  // namespace penumbra::visibility
