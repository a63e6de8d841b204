// The straightforward pose-shading path that sh/pose_shading.cpp must agree
// with (to 1e-10): per vertex, build the frame G (z = n or r), expand the lobes
// in G with zh_to_sh_accumulate, apply T with ZonalOperator::apply, and rotate
// the RGB lighting into G with a full Ivanic–Ruedenberg ShRotation(Gᵀ) — the
// per-vertex rotation the fast path avoids. The benchmark times its own copy
// of the diffuse and Phong path (bench/cpp/pose_shading_bench.cpp,
// shade_straightforward) as the "reference" rows.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sh/basis.hpp"
#include "sh/brdf_operator.hpp"
#include "sh/point_sets.hpp"
#include "sh/pose_shading.hpp"
#include "sh/rotation.hpp"
#include "sh/zonal.hpp"

namespace penumbra::sh::testing {

// h_l = ∫_{S²} (1/π) max(0, cosθ) y_l0 = 2 ∫_0^1 μ y_l0(μ) dμ by Gauss–Legendre
// on [0, 1] (exact: the integrand is a polynomial of degree l + 1).
inline std::vector<double> clamped_cosine_zonal_reference(int order) {
    std::vector<double> nodes, weights, h(order, 0.0);
    gauss_legendre(32, nodes, weights);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
        const double mu = 0.5 * (nodes[k] + 1.0), w = 0.5 * weights[k];
        for (int l = 0; l < order; ++l)
            h[l] += 2.0 * w * mu * std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi)) * std::legendre(l, mu);
    }
    return h;
}

// The frame axis the models use: n, or the clamped reflection vector (header
// of sh/pose_shading.hpp).
inline Eigen::Vector3d reference_frame_axis(ShadingModel model, const Eigen::Vector3d& n,
                                            const Eigen::Vector3d& position, const Eigen::Vector3d& camera) {
    if (model != ShadingModel::phong) return n;
    const Eigen::Vector3d to_camera = camera - position;
    if (to_camera.norm() == 0.0) return n;
    const Eigen::Vector3d w = to_camera.normalized();
    const double cosine = n.dot(w);
    if (cosine >= 0.0) return (2.0 * cosine * n - w).normalized();
    const Eigen::Vector3d h = w - cosine * n;
    return h.norm() > 1e-12 ? Eigen::Vector3d(-h.normalized()) : n;
}

// Shades vertices one by one; inputs as PoseBuffers<double>, valid vertices only.
inline void shade_pose_reference(int order, const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                                 const PoseBuffers<double>& b) {
    const int count = coefficient_count(order);
    const ZonalOperator op = parameters.model == ShadingModel::phong
                                 ? phong_zonal_operator(order, parameters.phong_exponent)
                                 : diffuse_zonal_operator(order);
    const ZonalOperator diffuse = diffuse_zonal_operator(order);
    const std::vector<double> h = clamped_cosine_zonal_reference(order);
    std::vector<double> v(count), u(count), v_normal(count), t_normal(count), lit(count), light(count), back(count);
    for (std::size_t i = 0; i < b.vertex_count; ++i) {
        const Eigen::Vector3d n = Eigen::Vector3d(b.normals[3 * i], b.normals[3 * i + 1], b.normals[3 * i + 2]).normalized();
        Eigen::Vector3d t(b.tangents[3 * i], b.tangents[3 * i + 1], b.tangents[3 * i + 2]);
        t = (t - t.dot(n) * n).normalized();
        Eigen::Matrix3d frame;
        frame << t, n.cross(t), n;
        Eigen::Vector3d position = Eigen::Vector3d::Zero();
        if (b.positions) position = Eigen::Vector3d(b.positions[3 * i], b.positions[3 * i + 1], b.positions[3 * i + 2]);
        const Eigen::Vector3d z = reference_frame_axis(parameters.model, n, position, parameters.camera);
        // G: any rotation with G e_z = z.
        Eigen::Vector3d gx = (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
        gx = (gx - gx.dot(z) * z).normalized();
        Eigen::Matrix3d g;
        g << gx, z.cross(gx), z;

        std::fill(v.begin(), v.end(), 0.0);
        std::fill(v_normal.begin(), v_normal.end(), 0.0);
        for (int c = 0; c < b.lobes_per_vertex; ++c) {
            const std::size_t at = i * b.lobes_per_vertex + c;
            const Eigen::Vector3d axis(b.lobe_axes[3 * at], b.lobe_axes[3 * at + 1], b.lobe_axes[3 * at + 2]);
            const double* band = b.lobe_bands + order * at;
            if (axis.norm() == 0.0) continue;  // unused lobe (its bands are zero)
            zh_to_sh_accumulate(order, g.transpose() * frame * axis, band, v.data());
            zh_to_sh_accumulate(order, axis, band, v_normal.data());
        }
        op.apply(v.data(), u.data());

        // Lighting into G: f_G(ω') = f(G ω'), i.e. f turned by Gᵀ.
        const ShRotation into_frame(order, g.transpose());
        Eigen::VectorXd back_lobe = Eigen::VectorXd::Zero(count);
        zh_to_sh_accumulate(order, Eigen::Vector3d(-n), h.data(), back_lobe.data());  // world frame
        for (int channel = 0; channel < 3; ++channel) {
            for (int k = 0; k < count; ++k) light[k] = lighting(k, channel);
            into_frame.apply(light.data(), lit.data());
            double shade = 0.0;
            for (int k = 0; k < count; ++k) shade += lit[k] * u[k];
            if (parameters.model == ShadingModel::translucent)
                shade += parameters.transmission[channel] * back_lobe.dot(Eigen::Map<const Eigen::VectorXd>(light.data(), count));
            b.rgb[3 * i + channel] = shade;
        }
        if (b.visibility) {
            diffuse.apply(v_normal.data(), t_normal.data());
            b.visibility[i] = std::sqrt(4.0 * std::numbers::pi) * t_normal[0];
        }
    }
}

}  // namespace penumbra::sh::testing
