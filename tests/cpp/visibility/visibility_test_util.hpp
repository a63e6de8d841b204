// Small meshes for the visibility tests.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "visibility/occlusion_scene.hpp"

namespace penumbra::visibility::testing {

// UV sphere: positions, outward normals and triangles (wound outward).
struct TestMesh {
    TriangleMesh mesh;
    std::vector<float> normals;
};

inline void add_sphere(TestMesh& out, const Eigen::Vector3d& centre, double radius, int n_u = 24, int n_v = 12) {
    const auto base = std::uint32_t(out.mesh.vertex_count());
    auto push = [&](const Eigen::Vector3d& n) {
        const Eigen::Vector3d p = centre + radius * n;
        for (int k = 0; k < 3; ++k) {
            out.mesh.positions.push_back(float(p[k]));
            out.normals.push_back(float(n[k]));
        }
    };
    push(Eigen::Vector3d::UnitZ());
    for (int i = 1; i < n_v; ++i) {
        const double th = std::numbers::pi * i / n_v;
        for (int j = 0; j < n_u; ++j) {
            const double ph = 2 * std::numbers::pi * j / n_u;
            push(Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
        }
    }
    push(-Eigen::Vector3d::UnitZ());
    auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        out.mesh.triangles.insert(out.mesh.triangles.end(), {base + a, base + b, base + c});
    };
    for (int j = 0; j < n_u; ++j) tri(0, 1 + j, 1 + (j + 1) % n_u);
    for (int i = 0; i < n_v - 2; ++i)
        for (int j = 0; j < n_u; ++j) {
            const std::uint32_t a = 1 + i * n_u + j, b = 1 + i * n_u + (j + 1) % n_u, c = 1 + (i + 1) * n_u + (j + 1) % n_u,
                                d = 1 + (i + 1) * n_u + j;
            tri(a, d, c);
            tri(a, c, b);
        }
    const std::uint32_t last = 1 + (n_v - 1) * n_u, ring = 1 + (n_v - 2) * n_u;
    for (int j = 0; j < n_u; ++j) tri(last, ring + (j + 1) % n_u, ring + j);
}

}  // namespace penumbra::visibility::testing
