// Batched pose shading (sh/pose_shading.hpp) against three independent things:
// brute-force hemisphere quadrature of the truncated visibility × lighting ×
// kernel in world coordinates (no SH rotation, no operator), the
// straightforward per-vertex reference of pose_shading_reference.hpp
// (full SH rotation of the lighting), and closed forms (unit radiance).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/pose_shading.hpp"
#include "sh/pose_shading_setup.hpp"
#include "sh/projection.hpp"
#include "sh/rotation.hpp"
#include "sh/pose_shading_reference.hpp"
#include "sh/sh_test_util.hpp"

namespace penumbra::sh {
namespace {

using testing::random_direction;
using testing::random_rotation;

// One pose's inputs and outputs, owned.
struct Pose {
    int order = 4;
    int lobes = 2;
    std::size_t n = 0;
    std::vector<double> axes, bands, normals, tangents, positions, rgb, visibility;

    Pose(int order_, int lobes_, std::size_t n_) : order(order_), lobes(lobes_), n(n_) {
        axes.resize(n * lobes * 3);
        bands.resize(n * lobes * order);
        normals.resize(n * 3);
        tangents.resize(n * 3);
        positions.resize(n * 3);
        rgb.assign(n * 3, -1.0);
        visibility.assign(n, -1.0);
    }

    PoseBuffers<double> buffers() {
        PoseBuffers<double> b;
        b.vertex_count = n;
        b.lobes_per_vertex = lobes;
        b.lobe_axes = axes.data();
        b.lobe_bands = bands.data();
        b.normals = normals.data();
        b.tangents = tangents.data();
        b.positions = positions.data();
        b.rgb = rgb.data();
        b.visibility = visibility.data();
        return b;
    }

    void set_frame(std::size_t i, const Eigen::Vector3d& normal, const Eigen::Vector3d& tangent) {
        for (int k = 0; k < 3; ++k) {
            normals[3 * i + k] = normal[k];
            tangents[3 * i + k] = tangent[k];
        }
    }

    void set_lobe(std::size_t i, int c, const Eigen::Vector3d& axis, const std::vector<double>& g) {
        const std::size_t at = i * lobes + c;
        for (int k = 0; k < 3; ++k) axes[3 * at + k] = axis[k];
        for (int l = 0; l < order; ++l) bands[order * at + l] = g[l];
    }

    Eigen::Vector3d normal(std::size_t i) const { return {normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]}; }
    Eigen::Vector3d position(std::size_t i) const { return {positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]}; }
    Eigen::Matrix3d frame(std::size_t i) const {
        const Eigen::Vector3d n = normal(i).normalized();
        Eigen::Vector3d t(tangents[3 * i], tangents[3 * i + 1], tangents[3 * i + 2]);
        t = (t - t.dot(n) * n).normalized();
        Eigen::Matrix3d f;
        f << t, n.cross(t), n;
        return f;
    }
};

// Random frames (tangents deliberately not orthogonal to the normals, and of
// any length), lobes, positions around the origin.
Pose random_pose(int order, int lobes, std::size_t n, std::mt19937_64& rng) {
    Pose pose(order, lobes, n);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
        pose.set_frame(i, random_direction(rng) * (0.5 + uniform(rng) * uniform(rng)),
                       random_direction(rng) * 2.0);
        for (int k = 0; k < 3; ++k) pose.positions[3 * i + k] = uniform(rng);
        for (int c = 0; c < lobes; ++c) {
            std::vector<double> g(order);
            for (double& e : g) e = uniform(rng);
            pose.set_lobe(i, c, random_direction(rng) * 1.5, g);
        }
    }
    return pose;
}

Eigen::MatrixXd random_lighting(int order, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Eigen::MatrixXd l(coefficient_count(order), 3);
    for (Eigen::Index i = 0; i < l.size(); ++i) l.data()[i] = uniform(rng);
    return l;
}

Eigen::MatrixXd unit_radiance(int order) {
    Eigen::MatrixXd l = Eigen::MatrixXd::Zero(coefficient_count(order), 3);
    l.row(0).setConstant(std::sqrt(4.0 * std::numbers::pi));
    return l;
}

// A lobe that is the constant 1 (fully visible): g_0 = √(4π), axis arbitrary.
std::vector<double> fully_visible_band(int order) {
    std::vector<double> g(order, 0.0);
    g[0] = std::sqrt(4.0 * std::numbers::pi);
    return g;
}

// ---- Brute force: world-space quadrature, no SH rotation, no operator -----

// Σ_i l_i y_i(ω) with the angle-based reference basis of sh_test_util.hpp.
double lighting_at(int order, const Eigen::MatrixXd& lighting, int channel, const Eigen::Vector3d& w) {
    double sum = 0.0;
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) sum += lighting(sh_index(l, m), channel) * testing::reference_y(l, m, w);
    return sum;
}

// Σ_lobes Σ_l g_l sqrt((2l+1)/4π) P_l(axis_world · ω).
double visibility_at(const Pose& pose, std::size_t i, const Eigen::Vector3d& w) {
    const Eigen::Matrix3d frame = pose.frame(i);
    double sum = 0.0;
    for (int c = 0; c < pose.lobes; ++c) {
        const std::size_t at = i * pose.lobes + c;
        const Eigen::Vector3d local(pose.axes[3 * at], pose.axes[3 * at + 1], pose.axes[3 * at + 2]);
        if (local.norm() == 0.0) continue;
        const double mu = (frame * local.normalized()).dot(w);
        for (int l = 0; l < pose.order; ++l)
            sum += pose.bands[pose.order * at + l] * std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi)) *
                   std::legendre(l, std::clamp(mu, -1.0, 1.0));
    }
    return sum;
}

// ∫_{ω·axis > 0} kernel(ω·axis) f(ω) dω by Gauss–Legendre in μ ∈ [0, 1] and
// equal steps in φ: exact for the polynomials here (degree <= 2·order − 2 +
// integer exponent; odd powers of sinθ come with odd cos/sin φ and vanish).
template <typename Kernel, typename F>
double hemisphere_integral(const Eigen::Vector3d& axis, Kernel kernel, F f, int mu_nodes = 40, int phi_steps = 64) {
    std::vector<double> nodes, weights;
    gauss_legendre(mu_nodes, nodes, weights);
    Eigen::Vector3d e1 = (std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
    e1 = (e1 - e1.dot(axis) * axis).normalized();
    const Eigen::Vector3d e2 = axis.cross(e1);
    double sum = 0.0;
    for (int k = 0; k < mu_nodes; ++k) {
        const double mu = 0.5 * (nodes[k] + 1.0), weight = 0.5 * weights[k] * 2.0 * std::numbers::pi / phi_steps;
        const double sine = std::sqrt(1.0 - mu * mu);
        for (int j = 0; j < phi_steps; ++j) {
            const double phi = 2.0 * std::numbers::pi * (j + 0.5) / phi_steps;
            const Eigen::Vector3d w = mu * axis + sine * (std::cos(phi) * e1 + std::sin(phi) * e2);
            sum += weight * kernel(mu) * f(w);
        }
    }
    return sum;
}

double brute_force_shade(const Pose& pose, std::size_t i, const Eigen::MatrixXd& lighting,
                         const ShadingParameters& p, int channel) {
    const Eigen::Vector3d n = pose.normal(i).normalized();
    const Eigen::Vector3d axis = testing::reference_frame_axis(p.model, n, pose.position(i), p.camera);
    const auto product = [&](const Eigen::Vector3d& w) {
        return visibility_at(pose, i, w) * lighting_at(pose.order, lighting, channel, w);
    };
    double shade;
    if (p.model == ShadingModel::phong) {
        const double a = p.phong_exponent;
        shade = hemisphere_integral(axis, [a](double mu) { return (a + 1.0) / (2.0 * std::numbers::pi) * std::pow(mu, a); }, product);
    } else {
        shade = hemisphere_integral(axis, [](double mu) { return mu / std::numbers::pi; }, product);
    }
    if (p.model == ShadingModel::translucent)
        shade += p.transmission[channel] *
                 hemisphere_integral(Eigen::Vector3d(-n), [](double mu) { return mu / std::numbers::pi; },
                                     [&](const Eigen::Vector3d& w) { return lighting_at(pose.order, lighting, channel, w); });
    return shade;
}

// ---- Tests -------------------------------------------------------------------

TEST(PoseShading, fully_visible_vertex_under_unit_radiance_shades_to_one_diffuse) {
    std::mt19937_64 rng(1);
    for (int order : {1, 2, 4, 6, 9}) {
        Pose pose = random_pose(order, 2, 37, rng);
        for (std::size_t i = 0; i < pose.n; ++i) {
            pose.set_lobe(i, 0, random_direction(rng), fully_visible_band(order));
            pose.set_lobe(i, 1, random_direction(rng), std::vector<double>(order, 0.0));
        }
        PoseShader shader(order);
        const ShadingStats stats = shader.shade(unit_radiance(order), {}, pose.buffers());
        EXPECT_EQ(stats.invalid_vertices, 0u);
        for (std::size_t i = 0; i < pose.n; ++i) {
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(pose.rgb[3 * i + c], 1.0, 1e-13) << "order " << order;
            EXPECT_NEAR(pose.visibility[i], 1.0, 1e-13);
        }
    }
}

TEST(PoseShading, fully_occluded_vertex_shades_to_zero) {
    std::mt19937_64 rng(2);
    Pose pose = random_pose(4, 2, 20, rng);
    std::fill(pose.bands.begin(), pose.bands.end(), 0.0);
    const Eigen::MatrixXd lighting = random_lighting(4, rng);
    PoseShader shader(4);
    for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong}) {
        ShadingParameters p;
        p.model = model;
        p.phong_exponent = 12.5;
        p.camera = Eigen::Vector3d(3, -2, 5);
        shader.shade(lighting, p, pose.buffers());
        for (double e : pose.rgb) EXPECT_EQ(e, 0.0);
        for (double e : pose.visibility) EXPECT_EQ(e, 0.0);
    }
    // Translucent: only the unshadowed back lobe is left, τ_c E(−n)/π.
    ShadingParameters p;
    p.model = ShadingModel::translucent;
    p.transmission = {0.25, 0.5, 2.0};
    shader.shade(lighting, p, pose.buffers());
    for (std::size_t i = 0; i < pose.n; ++i)
        for (int c = 0; c < 3; ++c) {
            const double expected = p.transmission[c] *
                hemisphere_integral(Eigen::Vector3d(-pose.normal(i).normalized()), [](double mu) { return mu / std::numbers::pi; },
                                    [&](const Eigen::Vector3d& w) { return lighting_at(4, lighting, c, w); });
            EXPECT_NEAR(pose.rgb[3 * i + c], expected, 1e-12);
        }
}

TEST(PoseShading, unoccluded_diffuse_vertex_gives_irradiance_of_truncated_environment) {
    // A sky: bright zenith, a warm band near the horizon towards +x, dark ground.
    const PointSet sphere = gauss_product_sphere(96, 192);
    Eigen::MatrixXd radiance(sphere.directions.size(), 3);
    for (std::size_t i = 0; i < sphere.directions.size(); ++i) {
        const Eigen::Vector3d& d = sphere.directions[i];
        const double sky = d.z() > 0.0 ? 1.0 + 3.0 * d.z() * d.z() : 0.2;
        const double sun = std::exp(8.0 * (d.dot(Eigen::Vector3d(0.8, 0.0, 0.6)) - 1.0));
        radiance.row(Eigen::Index(i)) << sky + 4.0 * sun, sky + 2.0 * sun, 1.5 * sky;
    }
    std::mt19937_64 rng(3);
    for (int order : {2, 3, 4, 5}) {
        const Eigen::MatrixXd lighting = project_samples(order, sphere, radiance);
        Pose pose = random_pose(order, 1, 50, rng);
        for (std::size_t i = 0; i < pose.n; ++i) pose.set_lobe(i, 0, random_direction(rng), fully_visible_band(order));
        PoseShader(order).shade(lighting, {}, pose.buffers());
        for (std::size_t i = 0; i < pose.n; ++i)
            for (int c = 0; c < 3; ++c) {
                // E(n)/π of the order-limited radiance, by direct quadrature.
                const double irradiance_over_pi = hemisphere_integral(
                    pose.normal(i).normalized(), [](double mu) { return mu / std::numbers::pi; },
                    [&](const Eigen::Vector3d& w) { return lighting_at(order, lighting, c, w); });
                EXPECT_NEAR(pose.rgb[3 * i + c], irradiance_over_pi, 1e-12 * std::max(1.0, irradiance_over_pi))
                    << "order " << order << " vertex " << i;
            }
    }
}

TEST(PoseShading, normalized_phong_conserves_energy_for_any_exponent) {
    std::mt19937_64 rng(4);
    const int order = 4;
    Pose pose = random_pose(order, 1, 64, rng);
    for (std::size_t i = 0; i < pose.n; ++i) pose.set_lobe(i, 0, random_direction(rng), fully_visible_band(order));
    PoseShader shader(order);
    for (double alpha : {0.0, 0.5, 1.0, 7.0, 1000.0, 1e6, std::numeric_limits<double>::infinity()}) {
        ShadingParameters p;
        p.model = ShadingModel::phong;
        p.phong_exponent = alpha;
        p.camera = Eigen::Vector3d(0.3, -4.0, 2.0);  // some vertices see it from behind: clamped r
        shader.shade(unit_radiance(order), p, pose.buffers());
        for (std::size_t i = 0; i < pose.n; ++i)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(pose.rgb[3 * i + c], 1.0, 1e-12) << "alpha " << alpha;
    }
}

TEST(PoseShading, matches_brute_force_hemisphere_quadrature) {
    std::mt19937_64 rng(5);
    for (int order : {1, 3, 4, 5}) {
        Pose pose = random_pose(order, 2, 12, rng);
        const Eigen::MatrixXd lighting = random_lighting(order, rng);
        PoseShader shader(order);
        for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong, ShadingModel::translucent}) {
            for (double alpha : {1.0, 4.0, 20.0}) {
                if (model != ShadingModel::phong && alpha != 1.0) continue;
                ShadingParameters p;
                p.model = model;
                p.phong_exponent = alpha;
                p.camera = Eigen::Vector3d(0.5, 2.0, 1.0);
                p.transmission = {0.3, 0.6, 0.9};
                shader.shade(lighting, p, pose.buffers());
                for (std::size_t i = 0; i < pose.n; ++i)
                    for (int c = 0; c < 3; ++c)
                        EXPECT_NEAR(pose.rgb[3 * i + c], brute_force_shade(pose, i, lighting, p, c), 1e-11)
                            << "order " << order << " model " << int(model) << " alpha " << alpha << " vertex " << i;
            }
        }
    }
}

// Shades a random pose with each BRDF and checks every vertex against the
// straightforward reference to 1e-10; `label` names the case on failure.
void expect_every_model_matches_reference(int order, int lobes, std::size_t vertices, double phong_exponent,
                                          const Eigen::Vector3d& camera, const std::array<double, 3>& transmission,
                                          std::mt19937_64& rng, const std::string& label) {
    Pose pose = random_pose(order, lobes, vertices, rng);
    Pose reference = pose;
    const Eigen::MatrixXd lighting = random_lighting(order, rng);
    PoseShader shader(order);
    for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong, ShadingModel::translucent}) {
        ShadingParameters p;
        p.model = model;
        p.phong_exponent = phong_exponent;
        p.camera = camera;
        p.transmission = {transmission[0], transmission[1], transmission[2]};
        EXPECT_EQ(shader.shade(lighting, p, pose.buffers()).invalid_vertices, 0u);
        testing::shade_pose_reference(order, lighting, p, reference.buffers());
        for (std::size_t k = 0; k < pose.rgb.size(); ++k)
            ASSERT_NEAR(pose.rgb[k], reference.rgb[k], 1e-10) << label << " model " << int(model);
        for (std::size_t k = 0; k < pose.n; ++k)
            ASSERT_NEAR(pose.visibility[k], reference.visibility[k], 1e-10) << label;
    }
}

TEST(PoseShading, agrees_with_straightforward_reference_to_1e_10) {
    std::mt19937_64 rng(6);
    // Orders 1–8 take the unrolled kernels, 10 and 16 the runtime-order one;
    // 29 vertices: a partial batch at the end; the camera inside the positions.
    for (int order : {1, 2, 3, 4, 5, 6, 7, 8, 10, 16})
        for (int lobes : {1, 2, 3})
            expect_every_model_matches_reference(order, lobes, 29, 37.25, Eigen::Vector3d(-1.0, 0.5, 0.8),
                                                 {0.7, 0.2, 1.3}, rng,
                                                 "order " + std::to_string(order) + " lobes " + std::to_string(lobes));
}

// Every SIMD target compiled in and supported here (AVX-512, AVX2, SSE4 and
// the one-lane scalar reference on an AVX-512 machine) runs its own copy of
// the kernel: each must agree with the straightforward reference, so a
// target that computes wrongly fails here even when the CPU's best is fine.
TEST(PoseShading, every_simd_target_agrees_with_straightforward_reference_to_1e_10) {
    const std::vector<std::string> targets = simd_targets();
    ASSERT_GE(targets.size(), 2u) << "expected the scalar reference and at least one SIMD target";
    EXPECT_EQ(simd_target(), targets.front());
    const std::map<std::string, int> lanes{{"SCALAR", 1}, {"EMU128", 1}, {"SSE4", 2}, {"AVX2", 4}, {"AVX3", 8}};
    std::mt19937_64 rng(61);
    for (const std::string& target : targets) {
        force_simd_target(target);
        ASSERT_EQ(simd_target(), target);
        // The dispatch really runs that target's code: its batch width.
        if (lanes.count(target)) EXPECT_EQ(detail::simd_lanes(), lanes.at(target)) << target;
        for (int order : {2, 4, 8, 10})  // 37 vertices: a partial batch on every width
            expect_every_model_matches_reference(order, 2, 37, 12.5, Eigen::Vector3d(0.3, -0.8, 0.4), {0.4, 0.9, 0.1},
                                                 rng, target + " order " + std::to_string(order));
    }
    force_simd_target("");
    EXPECT_EQ(simd_target(), targets.front());
    EXPECT_THROW(force_simd_target("NEON"), ArgumentError);
}

TEST(PoseShading, turning_the_whole_scene_leaves_shades_unchanged) {
    std::mt19937_64 rng(7);
    const int order = 5;
    Pose pose = random_pose(order, 2, 40, rng);
    const Eigen::MatrixXd lighting = random_lighting(order, rng);
    const Eigen::Matrix3d r = random_rotation(rng);
    Pose turned = pose;
    for (std::size_t i = 0; i < pose.n; ++i)
        for (std::vector<double>* field : {&turned.normals, &turned.tangents, &turned.positions}) {
            const Eigen::Vector3d e = r * Eigen::Vector3d((*field)[3 * i], (*field)[3 * i + 1], (*field)[3 * i + 2]);
            for (int k = 0; k < 3; ++k) (*field)[3 * i + k] = e[k];
        }
    // Lobes are in the vertex frames, which turn with the normals and tangents.
    const Eigen::MatrixXd turned_lighting = ShRotation(order, r).apply(lighting);
    PoseShader shader(order);
    for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong, ShadingModel::translucent}) {
        ShadingParameters p;
        p.model = model;
        p.phong_exponent = 9.0;
        p.camera = Eigen::Vector3d(2.0, 1.0, -3.0);
        shader.shade(lighting, p, pose.buffers());
        p.camera = r * p.camera;
        shader.shade(turned_lighting, p, turned.buffers());
        for (std::size_t k = 0; k < pose.rgb.size(); ++k) EXPECT_NEAR(pose.rgb[k], turned.rgb[k], 1e-12);
        for (std::size_t k = 0; k < pose.n; ++k) EXPECT_NEAR(pose.visibility[k], turned.visibility[k], 1e-12);
    }
}

TEST(PoseShading, results_do_not_depend_on_thread_count) {
    std::mt19937_64 rng(8);
    Pose pose = random_pose(4, 2, 10007, rng);  // several 2048-vertex ranges, odd tail
    const Eigen::MatrixXd lighting = random_lighting(4, rng);
    PoseShader shader(4);
    ShadingParameters p;
    p.model = ShadingModel::phong;
    p.phong_exponent = 30.0;
    p.camera = Eigen::Vector3d(0.0, -3.0, 1.0);
    p.threads = 1;
    shader.shade(lighting, p, pose.buffers());
    const std::vector<double> single = pose.rgb, single_visibility = pose.visibility;
    for (int threads : {0, 2, 3, 5, 64}) {
        p.threads = threads;
        std::fill(pose.rgb.begin(), pose.rgb.end(), -1.0);
        shader.shade(lighting, p, pose.buffers());
        EXPECT_EQ(pose.rgb, single) << threads << " threads";
        EXPECT_EQ(pose.visibility, single_visibility) << threads << " threads";
    }
}

// Float buffers are shaded in float (twice the lanes of double); the
// largest difference from the double kernel on the same (float-rounded)
// inputs, relative to the largest shade of the pose, per model.
double largest_float_error(int order, ShadingModel model, std::mt19937_64& rng) {
    Pose pose = random_pose(order, 2, 203, rng);
    for (std::vector<double>* field : {&pose.axes, &pose.bands, &pose.normals, &pose.tangents, &pose.positions})
        for (double& e : *field) e = double(float(e));
    std::vector<float> axes(pose.axes.begin(), pose.axes.end()), bands(pose.bands.begin(), pose.bands.end()),
        normals(pose.normals.begin(), pose.normals.end()), tangents(pose.tangents.begin(), pose.tangents.end()),
        positions(pose.positions.begin(), pose.positions.end()), rgb(pose.n * 3), visibility(pose.n);
    PoseBuffers<float> b{pose.n, 2, axes.data(), bands.data(), normals.data(), tangents.data(), positions.data(),
                         rgb.data(), visibility.data()};
    Eigen::MatrixXd lighting = random_lighting(order, rng);
    for (Eigen::Index i = 0; i < lighting.size(); ++i) lighting.data()[i] = double(float(lighting.data()[i]));
    ShadingParameters p;
    p.model = model;
    p.phong_exponent = 40.0;
    p.camera = Eigen::Vector3d(1, 2, 3);
    p.transmission = {0.5, 0.25, 1.0};
    PoseShader shader(order);
    shader.shade(lighting, p, pose.buffers());
    EXPECT_EQ(shader.shade(lighting, p, b).invalid_vertices, 0u);
    double largest = 0.0, scale = 0.0;
    for (std::size_t k = 0; k < rgb.size(); ++k) {
        largest = std::max(largest, std::abs(double(rgb[k]) - pose.rgb[k]));
        scale = std::max(scale, std::abs(pose.rgb[k]));
    }
    for (std::size_t k = 0; k < visibility.size(); ++k) {
        largest = std::max(largest, std::abs(double(visibility[k]) - pose.visibility[k]));
        scale = std::max(scale, std::abs(pose.visibility[k]));
    }
    return largest / scale;
}

// Measured on every target (AVX3, AVX2, SSE4, scalar): at most 1.7e-6 of
// the largest shade at order 4 and 3.1e-6 at order 8 (float rounding,
// 6e-8, grown through the rotation and the operator); the bound is 10× the
// largest. The scalar reference computes in float too.
TEST(PoseShading, float_buffers_are_shaded_in_float_within_3e_5_of_double_on_every_target) {
    std::mt19937_64 rng(9);
    for (const std::string& target : simd_targets()) {
        force_simd_target(target);
        for (int order : {2, 4, 8})
            for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong, ShadingModel::translucent}) {
                const double error = largest_float_error(order, model, rng);
                EXPECT_LT(error, 3e-5) << target << " order " << order << " model " << int(model);
                EXPECT_GT(error, 0.0) << "float arithmetic must differ from double somewhere";
            }
    }
    force_simd_target("");
}

TEST(PoseShading, invalid_vertices_shade_to_zero_and_are_counted) {
    std::mt19937_64 rng(10);
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    Pose pose = random_pose(3, 2, 12, rng);
    Pose clean = pose;
    pose.set_frame(1, Eigen::Vector3d(nan, 0, 1), Eigen::Vector3d(1, 0, 0));      // NaN normal
    pose.set_frame(2, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0));        // zero normal
    pose.set_frame(3, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 5));        // tangent along the normal
    pose.set_frame(4, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(inf, 0, 0));      // infinite tangent
    pose.bands[(5 * 2 + 1) * 3 + 2] = nan;                                        // NaN band
    pose.set_lobe(6, 1, Eigen::Vector3d::Zero(), {0.5, 0.0, 0.0});                // zero axis, non-zero band
    pose.positions[3 * 7] = nan;                                                  // NaN position (phong only)
    // Vertex 8: an unused lobe (zero axis and bands) is skipped, not invalid.
    pose.set_lobe(8, 1, Eigen::Vector3d::Zero(), {0.0, 0.0, 0.0});
    clean.set_lobe(8, 1, Eigen::Vector3d(0, 0, 1), {0.0, 0.0, 0.0});
    const Eigen::MatrixXd lighting = random_lighting(3, rng);
    PoseShader shader(3);
    for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong, ShadingModel::translucent}) {
        ShadingParameters p;
        p.model = model;
        p.camera = Eigen::Vector3d(0, 0, 4);
        const ShadingStats stats = shader.shade(lighting, p, pose.buffers());
        shader.shade(lighting, p, clean.buffers());
        const bool phong = model == ShadingModel::phong;
        EXPECT_EQ(stats.invalid_vertices, phong ? 7u : 6u);
        for (std::size_t i = 0; i < pose.n; ++i) {
            const bool bad = (i >= 1 && i <= 6) || (phong && i == 7);
            for (int c = 0; c < 3; ++c) {
                const double expected = bad ? 0.0 : clean.rgb[3 * i + c];
                EXPECT_EQ(pose.rgb[3 * i + c], expected) << i;
            }
            if (bad) {
                EXPECT_EQ(pose.visibility[i], 0.0);
            }
        }
    }
}

TEST(PoseShading, camera_behind_the_surface_clamps_reflection_to_the_horizon) {
    std::mt19937_64 rng(11);
    Pose behind = random_pose(4, 2, 1, rng);
    behind.set_frame(0, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0.2, 0));
    for (int k = 0; k < 3; ++k) behind.positions[k] = 0.0;
    Pose horizon = behind;
    const Eigen::MatrixXd lighting = random_lighting(4, rng);
    PoseShader shader(4);
    ShadingParameters p;
    p.model = ShadingModel::phong;
    p.phong_exponent = 15.0;
    // Camera below the tangent plane vs. the same azimuth on the horizon:
    // both give r = −(0.6, 0.8, 0) normalized.
    p.camera = Eigen::Vector3d(0.6, 0.8, -0.9);
    shader.shade(lighting, p, behind.buffers());
    p.camera = Eigen::Vector3d(0.6, 0.8, 0.0) * 7.0;
    shader.shade(lighting, p, horizon.buffers());
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(behind.rgb[c], horizon.rgb[c], 1e-12);
    // And continuous: just above the horizon is close.
    p.camera = Eigen::Vector3d(0.6, 0.8, 1e-7);
    shader.shade(lighting, p, horizon.buffers());
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(behind.rgb[c], horizon.rgb[c], 1e-5);
}

TEST(PoseShading, rejects_bad_arguments) {
    std::mt19937_64 rng(12);
    Pose pose = random_pose(4, 1, 3, rng);
    PoseShader shader(4);
    const Eigen::MatrixXd good = random_lighting(4, rng);
    EXPECT_THROW(shader.shade(random_lighting(3, rng), {}, pose.buffers()), ArgumentError);
    EXPECT_THROW(shader.shade(Eigen::MatrixXd::Zero(16, 4), {}, pose.buffers()), ArgumentError);
    Eigen::MatrixXd nan_light = good;
    nan_light(5, 1) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(shader.shade(nan_light, {}, pose.buffers()), ArgumentError);
    ShadingParameters p;
    p.model = ShadingModel::phong;
    p.phong_exponent = -1.0;
    EXPECT_THROW(shader.shade(good, p, pose.buffers()), ArgumentError);
    p.phong_exponent = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(shader.shade(good, p, pose.buffers()), ArgumentError);
    p.phong_exponent = 2.0;
    p.camera.x() = std::numeric_limits<double>::infinity();
    EXPECT_THROW(shader.shade(good, p, pose.buffers()), ArgumentError);
    p = {};
    p.threads = -1;
    EXPECT_THROW(shader.shade(good, p, pose.buffers()), ArgumentError);
    PoseBuffers<double> b = pose.buffers();
    b.lobes_per_vertex = 0;
    EXPECT_THROW(shader.shade(good, {}, b), ArgumentError);
    b = pose.buffers();
    b.positions = nullptr;
    p = {};
    p.model = ShadingModel::phong;
    EXPECT_THROW(shader.shade(good, p, b), ArgumentError);
    EXPECT_NO_THROW(shader.shade(good, {}, b));  // diffuse needs no positions
    EXPECT_THROW(PoseShader(0), ArgumentError);
    EXPECT_THROW(PoseShader(max_order + 1), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
