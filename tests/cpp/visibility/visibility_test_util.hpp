// Small meshes, ZH visibility vectors and synthetic training sets for the
// visibility tests.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sh/zonal.hpp"
#include "visibility/occlusion_scene.hpp"
#include "visibility/visibility_bake.hpp"

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

// Order-4 SH of a sum of ZH lobes (axis, bands), by paper Eq. 1.
inline std::vector<double> lobe_sh(const std::vector<std::pair<Eigen::Vector3d, std::array<double, 4>>>& lobes) {
    std::vector<double> sh(16, 0.0);
    for (const auto& [axis, band] : lobes) sh::zh_to_sh_accumulate(4, axis, band.data(), sh.data());
    return sh;
}

// A synthetic training set: vertex v's visibility is one lobe about +z whose
// band coefficients depend linearly on cos θ_v and sin θ_v of one bone's
// rotation about z (so exactly linear in the R − I features).
inline TrainingSet synthetic_set(const std::vector<double>& angles, int vertices, int extra_still_bones = 0) {
    TrainingSet set;
    set.vertex_count = vertices;
    set.topology_hash = 42;
    set.bone_names = {"arm"};
    for (int b = 0; b < extra_still_bones; ++b) set.bone_names.push_back("still" + std::to_string(b));
    set.settings.rays = 64;
    for (std::size_t f = 0; f < angles.size(); ++f) {
        TrainingFrame frame;
        frame.frame = double(f);
        const Eigen::Matrix3d r = Eigen::AngleAxisd(angles[f], Eigen::Vector3d::UnitZ()).toRotationMatrix();
        for (std::size_t b = 0; b < set.bone_names.size(); ++b)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) frame.bone_rotations.push_back(b == 0 ? float(r(i, j)) : (i == j ? 1.f : 0.f));
        for (int v = 0; v < vertices; ++v) {
            const double w = double(v) / vertices;
            const std::array<double, 4> band{1.5 + 0.4 * w * std::cos(angles[f]), 1.0 + 0.3 * std::sin(angles[f]) * w,
                                             0.3, 0.05 * w};
            const auto sh = lobe_sh({{Eigen::Vector3d::UnitZ(), band}});
            for (double x : sh) frame.visibility.push_back(float(x));
        }
        set.frames.push_back(std::move(frame));
    }
    return set;
}

}  // namespace penumbra::visibility::testing
