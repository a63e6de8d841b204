#include "visibility_throughput.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <thread>

#include "common/error.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/occlusion_scene.hpp"

namespace penumbra::visibility {

ThroughputResult measure_occlusion_throughput(const std::vector<float>& positions, const std::vector<float>& normals,
                                              const std::vector<std::uint32_t>& triangles, int rays_per_vertex,
                                              int threads, const std::string& mode) {
    if (mode != "single" && mode != "packet") throw ArgumentError("mode must be 'single' or 'packet'");
    if (rays_per_vertex < 1) throw ArgumentError("rays_per_vertex must be >= 1");
    TriangleMesh mesh{positions, triangles};
    const std::size_t V = mesh.vertex_count();
    if (normals.size() != positions.size()) throw ArgumentError("normals must be (V, 3) like the positions");
    const OcclusionScene scene({&mesh});
    const MeshDiagnostics diag = mesh_diagnostics(positions, normals, triangles);
    const float offset = float(1e-4 * diag.bounding_diagonal);
    // Directions and origins, drawn before the clock starts.
    std::vector<Eigen::Vector3f> origins(V), directions(V * rays_per_vertex);
    std::mt19937 rng(12345);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (std::size_t v = 0; v < V; ++v) {
        Eigen::Vector3d n(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
        n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
        Eigen::Vector3d t, b;
        basis_from_normal(n, t, b);
        origins[v] = Eigen::Vector3f(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]) + offset * n.cast<float>();
        for (int i = 0; i < rays_per_vertex; ++i) {
            const double z = uniform(rng), phi = 2.0 * std::numbers::pi * uniform(rng), r = std::sqrt(1.0 - z * z);
            directions[v * rays_per_vertex + i] = (r * std::cos(phi) * t + r * std::sin(phi) * b + z * n).cast<float>();
        }
    }
    const int n_threads = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
    std::atomic<std::size_t> next{0}, occluded_total{0};
    const bool single = mode == "single";
    const float far = std::numeric_limits<float>::infinity();
    auto worker = [&] {
        std::vector<std::uint8_t> hit(rays_per_vertex);
        std::size_t occluded = 0;
        for (;;) {
            const std::size_t begin = next.fetch_add(64);
            if (begin >= V) break;
            const std::size_t end = std::min(V, begin + 64);
            for (std::size_t v = begin; v < end; ++v) {
                const Eigen::Vector3f* d = directions.data() + v * rays_per_vertex;
                if (single) {
                    for (int i = 0; i < rays_per_vertex; ++i) occluded += scene.occluded1(origins[v], d[i], 0.0f, far);
                } else {
                    scene.occluded_bundle(origins[v], d, rays_per_vertex, 0.0f, far, hit.data(), true);
                    for (int i = 0; i < rays_per_vertex; ++i) occluded += hit[i];
                }
            }
        }
        occluded_total += occluded;
    };
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 1; i < n_threads; ++i) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    ThroughputResult r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.rays = V * std::size_t(rays_per_vertex);
    r.rays_per_second = r.seconds > 0 ? double(r.rays) / r.seconds : 0.0;
    r.occluded_fraction = r.rays ? double(occluded_total.load()) / double(r.rays) : 0.0;
    r.packet_width = single ? 1 : scene.packet_width();
    return r;
}

}  // namespace penumbra::visibility
