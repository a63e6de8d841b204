#include "visibility/visibility_bake.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "common/parallel.hpp"

namespace penumbra::visibility {

void check_bake_settings(const BakeSettings& s) {
    check_range("SH order", s.order, BakeSettings::order_range);
    check_range("rays", s.rays, BakeSettings::rays_range);
    if (!(s.offset_scale > 0.0 && s.offset_scale < 0.1))
        throw ArgumentError("offset_scale must be in (0, 0.1), got " + std::to_string(s.offset_scale));
    if (s.below_horizon != BelowHorizon::Occluded && s.below_horizon != BelowHorizon::Cast)
        throw ArgumentError("unknown below-horizon rule");
    if (s.weighting != Weighting::Plain && s.weighting != Weighting::Cosine)
        throw ArgumentError("unknown weighting");
    check_range("threads", s.threads, threads_range);
}

RaySet make_ray_set(const BakeSettings& settings) {
    check_bake_settings(settings);
    const sh::PointSet points = sh::fibonacci_sphere(settings.rays);
    const int n_sh = settings.order * settings.order;
    RaySet set;
    set.directions.reserve(settings.rays);
    set.projection.assign(std::size_t(settings.rays) * n_sh, 0.0f);
    std::vector<double> y(n_sh);
    for (int i = 0; i < settings.rays; ++i) {
        const Eigen::Vector3d& d = points.directions[i];
        // Fibonacci z decreases with i: the upper hemisphere comes first.
        if (d.z() >= 0.0) set.upper = i + 1;
        set.directions.push_back(d.cast<float>());
        sh::eval_unit(settings.order, d, y.data());
        double weight = points.weights[i];
        if (settings.weighting == Weighting::Cosine) weight *= std::max(0.0, d.z()) / std::numbers::pi;
        for (int k = 0; k < n_sh; ++k) set.projection[std::size_t(i) * n_sh + k] = float(weight * y[k]);
    }
    return set;
}

FrameBaker::FrameBaker(const BakeSettings& settings, SceneBuild build, Traversal traversal)
    : settings_(settings), build_(build), traversal_(traversal),
      rays_(std::make_unique<RaySet>(make_ray_set(settings))) {
    if (build != SceneBuild::High && build != SceneBuild::Medium && build != SceneBuild::Low && build != SceneBuild::Refit)
        throw ArgumentError("unknown scene build");
    if (traversal != Traversal::Fast && traversal != Traversal::Robust) throw ArgumentError("unknown traversal");
}

FrameBaker::~FrameBaker() = default;

void FrameBaker::set_threads(int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0 (0: every core)");
    settings_.threads = threads;
}

void bake_frame(const FrameGeometry& geometry, const std::vector<std::uint32_t>& neighbours,
                const BakeSettings& settings, float* visibility_out, const Progress& progress, FrameBakeStats* stats,
                double progress_from, double progress_to) {
    FrameBaker(settings).bake(geometry, neighbours, visibility_out, progress, stats, progress_from, progress_to);
}

void FrameBaker::bake(const FrameGeometry& geometry, const std::vector<std::uint32_t>& neighbours,
                      float* visibility_out, const Progress& progress, FrameBakeStats* stats, double progress_from,
                      double progress_to) {
    using Clock = std::chrono::steady_clock;
    const auto t_setup = Clock::now();
    const BakeSettings& settings = settings_;
    const RaySet& rays = *rays_;
    const TriangleMesh& mesh = geometry.mesh;
    const std::size_t n_vertices = mesh.vertex_count();
    if (geometry.normals.size() != mesh.positions.size())
        throw ArgumentError("normals must be (V, 3) like the positions");
    if (neighbours.size() != n_vertices) throw ArgumentError("one reference neighbour per vertex is needed");
    const int n_sh = settings.order * settings.order;

    FrameBakeStats local;
    std::vector<float> frames(9 * n_vertices);
    vertex_frames(mesh.positions, geometry.normals, mesh.triangles, neighbours, frames.data(), &local.frames,
                  settings.threads);

    std::vector<const TriangleMesh*> meshes{&mesh};
    for (const auto& o : geometry.occluders) meshes.push_back(&o);
    const auto t_build = Clock::now();
    if (scene_ && scene_->update_positions(meshes)) {
        local.scene_updated = true;
    } else {
        scene_.reset();
        scene_ = std::make_unique<OcclusionScene>(meshes, build_, traversal_);
    }
    const OcclusionScene& scene = *scene_;
    const auto t_cast = Clock::now();

    // Ray origins sit off the surface by a length that scales with the mesh,
    // so the same bake works at 1e-3 and at 1e4 units.
    const MeshDiagnostics diagnostics = mesh_diagnostics(mesh.positions, geometry.normals, {});
    const float offset = float(settings.offset_scale * std::max(diagnostics.bounding_diagonal, 1e-30));
    const float far = std::numeric_limits<float>::infinity();
    const bool cast_below = settings.below_horizon == BelowHorizon::Cast && settings.weighting == Weighting::Plain;
    const int n_cast = cast_below ? int(rays.directions.size()) : rays.upper;

    parallel_for(n_vertices, {settings.threads, 64, "visibility.bake", progress_from, progress_to},
                 [&](std::size_t begin, std::size_t end) {
        std::vector<Eigen::Vector3f> world(rays.directions.size());
        std::vector<std::uint8_t> occluded(rays.directions.size());
        std::vector<float> accumulator(n_sh);
        for (std::size_t v = begin; v < end; ++v) {
            const float* f = frames.data() + 9 * v;
            const Eigen::Vector3f t(f[0], f[1], f[2]), b(f[3], f[4], f[5]), n(f[6], f[7], f[8]);
            for (int i = 0; i < n_cast; ++i) {
                const Eigen::Vector3f& d = rays.directions[i];
                world[i] = d.x() * t + d.y() * b + d.z() * n;
            }
            const Eigen::Vector3f p(mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]);
            scene.occluded_bundle(p + offset * n, world.data(), rays.upper, 0.0f, far, occluded.data());
            if (n_cast > rays.upper)
                scene.occluded_bundle(p - offset * n, world.data() + rays.upper, n_cast - rays.upper, 0.0f, far,
                                      occluded.data() + rays.upper);
            // Project: Σ over unblocked rays of weight · y(direction).
            std::fill(accumulator.begin(), accumulator.end(), 0.0f);
            for (int i = 0; i < n_cast; ++i) {
                if (occluded[i]) continue;
                const float* row = rays.projection.data() + std::size_t(i) * n_sh;
                for (int k = 0; k < n_sh; ++k) accumulator[k] += row[k];
            }
            std::copy(accumulator.begin(), accumulator.end(), visibility_out + v * n_sh);
        }
    }, progress);

    const auto t_end = Clock::now();
    local.seconds_setup = std::chrono::duration<double>(t_build - t_setup).count();
    local.seconds_build = std::chrono::duration<double>(t_cast - t_build).count();
    local.seconds_cast = std::chrono::duration<double>(t_end - t_cast).count();
    local.rays_cast = n_vertices * std::size_t(n_cast);
    local.rays_counted = n_vertices * rays.directions.size();
    if (stats) *stats = local;
}

void check_training_set(const TrainingSet& set) {
    check_bake_settings(set.settings);
    const std::size_t n_sh = std::size_t(set.settings.order) * set.settings.order;
    const std::size_t n_bones = set.bone_names.size();
    for (const auto& frame : set.frames) {
        const std::string at = "training frame " + std::to_string(frame.frame);
        if (frame.bone_rotations.size() != 9 * n_bones)
            throw ArgumentError(at + ": expected " + std::to_string(9 * n_bones) + " bone rotation values, got " +
                                std::to_string(frame.bone_rotations.size()));
        if (frame.visibility.size() != set.vertex_count * n_sh)
            throw ArgumentError(at + ": expected " + std::to_string(set.vertex_count * n_sh) +
                                " visibility values, got " + std::to_string(frame.visibility.size()));
        for (float x : frame.bone_rotations)
            if (!std::isfinite(x)) throw ArgumentError(at + " has a non-finite bone rotation");
        for (float x : frame.visibility)
            if (!std::isfinite(x)) throw ArgumentError(at + " has a non-finite visibility value");
    }
}

TrainingSet merge_training_sets(const std::vector<TrainingSet>& pieces) {
    if (pieces.empty()) throw ArgumentError("no training sets to merge");
    const TrainingSet& first = pieces.front();
    TrainingSet merged;
    merged.settings = first.settings;
    merged.settings.threads = 0;
    merged.vertex_count = first.vertex_count;
    merged.topology_hash = first.topology_hash;
    merged.bone_names = first.bone_names;
    std::map<double, const TrainingFrame*> by_frame;
    for (std::size_t k = 0; k < pieces.size(); ++k) {
        const TrainingSet& p = pieces[k];
        const std::string which = "piece " + std::to_string(k) + " ";
        if (p.vertex_count != first.vertex_count || p.topology_hash != first.topology_hash)
            throw ArgumentError(which + "was baked from another mesh (vertex count or topology differs)");
        if (p.bone_names != first.bone_names) throw ArgumentError(which + "was baked with another armature");
        if (p.settings.order != first.settings.order || p.settings.rays != first.settings.rays ||
            p.settings.below_horizon != first.settings.below_horizon ||
            p.settings.weighting != first.settings.weighting)
            throw ArgumentError(which + "was baked with other settings (order, rays or ray rules differ)");
        check_training_set(p);
        for (const auto& f : p.frames) by_frame.emplace(f.frame, &f);
    }
    for (const auto& [number, frame] : by_frame) merged.frames.push_back(*frame);
    return merged;
}

}  // namespace penumbra::visibility
