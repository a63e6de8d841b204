// Zonal harmonics: Eq. 1 against direct projection of the zonal function by
// quadrature, lobe rotation against SH rotation, zonal projection against
// closed forms.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/rotation.hpp"
#include "sh/zonal.hpp"
#include "sh_test_util.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

ZhLobe random_lobe(int order, std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    ZhLobe lobe;
    lobe.axis = testing::random_direction(rng);
    for (int l = 0; l < order; ++l) lobe.band[l] = normal(rng);
    return lobe;
}

// f(ω) = Σ_l g_l sqrt((2l+1)/4π) P_l(axis·ω), with std::legendre: independent
// of both Eq. 1 and the Cartesian basis recurrence.
double zonal_function(int order, const ZhLobe& lobe, const Eigen::Vector3d& w) {
    const double mu = std::clamp(lobe.axis.normalized().dot(w), -1.0, 1.0);
    double f = 0.0;
    for (int l = 0; l < order; ++l) f += lobe.band[l] * std::sqrt((2.0 * l + 1.0) / (4.0 * pi)) * std::legendre(l, mu);
    return f;
}

TEST(Zonal, eq1_equals_direct_projection_of_the_zonal_function) {
    constexpr int order = 8;
    std::mt19937_64 rng(21);
    const PointSet q = exact_sphere_quadrature(2 * order - 2);
    for (int trial = 0; trial < 5; ++trial) {
        const ZhLobe lobe = random_lobe(order, rng);
        std::vector<double> sh(coefficient_count(order), 0.0);
        zh_to_sh_accumulate(order, lobe, sh.data());

        std::vector<double> direct(coefficient_count(order), 0.0), y(coefficient_count(order));
        for (std::size_t k = 0; k < q.directions.size(); ++k) {
            eval_unit(order, q.directions[k], y.data());
            const double f = zonal_function(order, lobe, q.directions[k]);
            for (int i = 0; i < coefficient_count(order); ++i) direct[i] += q.weights[k] * f * y[i];
        }
        for (int i = 0; i < coefficient_count(order); ++i) EXPECT_NEAR(sh[i], direct[i], 1e-12) << "index " << i;
    }
}

TEST(Zonal, lobe_about_z_keeps_only_the_m_0_terms) {
    constexpr int order = 6;
    ZhLobe lobe;
    for (int l = 0; l < order; ++l) lobe.band[l] = 1.0 + l;
    std::vector<double> sh(coefficient_count(order), 0.0);
    zh_to_sh_accumulate(order, lobe, sh.data());
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) EXPECT_NEAR(sh[sh_index(l, m)], m == 0 ? lobe.band[l] : 0.0, 1e-14);
}

TEST(Zonal, accumulates_several_lobes) {
    constexpr int order = 4;
    std::mt19937_64 rng(2);
    const ZhLobe a = random_lobe(order, rng), b = random_lobe(order, rng);
    std::vector<double> both(16, 0.0), only_a(16, 0.0), only_b(16, 0.0);
    zh_to_sh_accumulate(order, a, both.data());
    zh_to_sh_accumulate(order, b, both.data());
    zh_to_sh_accumulate(order, a, only_a.data());
    zh_to_sh_accumulate(order, b, only_b.data());
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(both[i], only_a[i] + only_b[i], 1e-14);
}

TEST(Zonal, rotating_the_lobe_equals_rotating_its_sh_expansion) {
    constexpr int order = 8;
    std::mt19937_64 rng(99);
    for (int trial = 0; trial < 5; ++trial) {
        const ZhLobe lobe = random_lobe(order, rng);
        const Eigen::Matrix3d r = testing::random_rotation(rng);
        std::vector<double> turned_then_expanded(coefficient_count(order), 0.0);
        zh_to_sh_accumulate(order, rotate_lobe(lobe, r), turned_then_expanded.data());
        std::vector<double> expanded(coefficient_count(order), 0.0), expanded_then_turned(coefficient_count(order));
        zh_to_sh_accumulate(order, lobe, expanded.data());
        ShRotation(order, r).apply(expanded.data(), expanded_then_turned.data());
        for (int i = 0; i < coefficient_count(order); ++i)
            EXPECT_NEAR(turned_then_expanded[i], expanded_then_turned[i], 1e-12);
    }
}

TEST(Zonal, projects_polynomials_of_cos_theta_exactly) {
    // f = μ²: g_0 = 2π·(2/3)/√(4π), g_2 = 2π·√(5/4π)·½(6/5 − 2/3), the rest 0.
    const auto band = project_zonal(6, [](double mu) { return mu * mu; }, 16);
    EXPECT_NEAR(band[0], 2.0 * pi * (2.0 / 3.0) / std::sqrt(4.0 * pi), 1e-14);
    EXPECT_NEAR(band[1], 0.0, 1e-14);
    EXPECT_NEAR(band[2], 2.0 * pi * std::sqrt(5.0 / (4.0 * pi)) * 0.5 * (6.0 / 5.0 - 2.0 / 3.0), 1e-14);
    for (int l = 3; l < max_order; ++l) EXPECT_NEAR(band[l], 0.0, 1e-14);
}

TEST(Zonal, projects_the_clamped_cosine_to_its_known_coefficients) {
    // Ramamoorthy & Hanrahan 2001: max(cosθ, 0) -> √π/2, √(π/3), √(5π)/8, 0.
    // The kink at μ = 0 limits Gauss–Legendre to O(n^-2) convergence.
    const auto band = project_zonal(4, [](double mu) { return std::max(mu, 0.0); }, 256);
    EXPECT_NEAR(band[0], std::sqrt(pi) / 2.0, 1e-4);
    EXPECT_NEAR(band[1], std::sqrt(pi / 3.0), 1e-4);
    EXPECT_NEAR(band[2], std::sqrt(5.0 * pi) / 8.0, 1e-4);
    EXPECT_NEAR(band[3], 0.0, 1e-4);
}

TEST(Zonal, zero_axis_throws) {
    std::vector<double> sh(4, 0.0);
    const double band[2] = {1.0, 1.0};
    EXPECT_THROW(zh_to_sh_accumulate(2, Eigen::Vector3d::Zero(), band, sh.data()), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
