// The SH basis: convention (closed forms, signs), orthonormality by exact
// quadrature, behaviour at the poles, input checks.
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh_test_util.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

std::vector<double> eval_vector(int order, const Eigen::Vector3d& d) {
    std::vector<double> y(coefficient_count(order));
    eval(order, d, y.data());
    return y;
}

// Closed forms for bands 0..3 in x, y, z, written out by hand from the
// convention in basis.hpp (no Condon–Shortley phase).
std::vector<double> closed_form_bands_0_to_3(const Eigen::Vector3d& d) {
    const double x = d.x(), y = d.y(), z = d.z();
    return {
        0.5 * std::sqrt(1.0 / pi),
        std::sqrt(3.0 / (4.0 * pi)) * y,
        std::sqrt(3.0 / (4.0 * pi)) * z,
        std::sqrt(3.0 / (4.0 * pi)) * x,
        0.5 * std::sqrt(15.0 / pi) * x * y,
        0.5 * std::sqrt(15.0 / pi) * y * z,
        0.25 * std::sqrt(5.0 / pi) * (3.0 * z * z - 1.0),
        0.5 * std::sqrt(15.0 / pi) * x * z,
        0.25 * std::sqrt(15.0 / pi) * (x * x - y * y),
        0.25 * std::sqrt(35.0 / (2.0 * pi)) * (3.0 * x * x - y * y) * y,
        0.5 * std::sqrt(105.0 / pi) * x * y * z,
        0.25 * std::sqrt(21.0 / (2.0 * pi)) * y * (5.0 * z * z - 1.0),
        0.25 * std::sqrt(7.0 / pi) * (5.0 * z * z * z - 3.0 * z),
        0.25 * std::sqrt(21.0 / (2.0 * pi)) * x * (5.0 * z * z - 1.0),
        0.25 * std::sqrt(105.0 / pi) * (x * x - y * y) * z,
        0.25 * std::sqrt(35.0 / (2.0 * pi)) * (x * x - 3.0 * y * y) * x,
    };
}

TEST(ShBasis, indexing_follows_l_l_plus_1_plus_m) {
    EXPECT_EQ(sh_index(0, 0), 0);
    EXPECT_EQ(sh_index(1, -1), 1);
    EXPECT_EQ(sh_index(1, 1), 3);
    EXPECT_EQ(sh_index(2, -2), 4);
    EXPECT_EQ(sh_index(15, 15), 255);
    EXPECT_EQ(coefficient_count(max_order), 256);
}

TEST(ShBasis, band_0_is_the_constant_one_over_sqrt_4pi) {
    const auto y = eval_vector(1, Eigen::Vector3d(0.3, -0.2, 0.9));
    EXPECT_NEAR(y[0], 1.0 / std::sqrt(4.0 * pi), 1e-16);
}

TEST(ShBasis, band_1_is_y_z_x_with_positive_signs) {
    const double k = std::sqrt(3.0 / (4.0 * pi));
    const auto at_x = eval_vector(2, Eigen::Vector3d::UnitX());
    const auto at_y = eval_vector(2, Eigen::Vector3d::UnitY());
    const auto at_z = eval_vector(2, Eigen::Vector3d::UnitZ());
    EXPECT_NEAR(at_y[sh_index(1, -1)], k, 1e-15);
    EXPECT_NEAR(at_z[sh_index(1, 0)], k, 1e-15);
    EXPECT_NEAR(at_x[sh_index(1, 1)], k, 1e-15);
    EXPECT_NEAR(at_x[sh_index(1, -1)], 0.0, 1e-15);
    EXPECT_NEAR(at_x[sh_index(1, 0)], 0.0, 1e-15);
}

TEST(ShBasis, bands_0_to_3_match_handwritten_closed_forms) {
    std::mt19937_64 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Vector3d d = testing::random_direction(rng);
        const auto y = eval_vector(4, d);
        const auto expected = closed_form_bands_0_to_3(d);
        for (int i = 0; i < 16; ++i) EXPECT_NEAR(y[i], expected[i], 1e-14) << "index " << i;
    }
}

TEST(ShBasis, all_16_bands_match_an_angle_based_reference) {
    std::mt19937_64 rng(11);
    for (int trial = 0; trial < 100; ++trial) {
        const Eigen::Vector3d d = testing::random_direction(rng);
        const auto y = eval_vector(max_order, d);
        for (int l = 0; l < max_order; ++l)
            for (int m = -l; m <= l; ++m)
                EXPECT_NEAR(y[sh_index(l, m)], testing::reference_y(l, m, d), 1e-12) << "l=" << l << " m=" << m;
    }
}

TEST(ShBasis, is_orthonormal_to_order_8_under_exact_quadrature) {
    constexpr int order = 8;
    const PointSet q = exact_sphere_quadrature(2 * order - 2);
    const int n = coefficient_count(order);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd y(n);
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
        eval_unit(order, q.directions[k], y.data());
        gram.noalias() += q.weights[k] * y * y.transpose();
    }
    EXPECT_LT((gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ShBasis, is_orthonormal_at_the_maximum_order) {
    const PointSet q = exact_sphere_quadrature(2 * max_order - 2);
    const int n = coefficient_count(max_order);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd y(n);
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
        eval_unit(max_order, q.directions[k], y.data());
        gram.noalias() += q.weights[k] * y * y.transpose();
    }
    EXPECT_LT((gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-11);
}

TEST(ShBasis, poles_give_only_zonal_terms_with_the_right_sign) {
    const auto north = eval_vector(max_order, Eigen::Vector3d::UnitZ());
    const auto south = eval_vector(max_order, -Eigen::Vector3d::UnitZ());
    for (int l = 0; l < max_order; ++l) {
        const double zonal = std::sqrt((2.0 * l + 1.0) / (4.0 * pi));  // y_l0 at θ = 0: P_l(1) = 1
        for (int m = -l; m <= l; ++m) {
            const double expected_north = (m == 0) ? zonal : 0.0;
            const double expected_south = (m == 0) ? ((l % 2) ? -zonal : zonal) : 0.0;
            EXPECT_NEAR(north[sh_index(l, m)], expected_north, 1e-13) << "l=" << l << " m=" << m;
            EXPECT_NEAR(south[sh_index(l, m)], expected_south, 1e-13) << "l=" << l << " m=" << m;
        }
    }
}

TEST(ShBasis, directions_1e_12_from_the_poles_are_finite_and_continuous) {
    const std::vector<Eigen::Vector3d> near_poles = {
        {1e-12, 0.0, 1.0}, {0.0, 1e-12, 1.0}, {-1e-12, -1e-12, 1.0},
        {1e-12, 0.0, -1.0}, {0.0, -1e-12, -1.0}, {std::sqrt(0.5) * 1e-12, std::sqrt(0.5) * 1e-12, -1.0}};
    for (const Eigen::Vector3d& d : near_poles) {
        const auto y = eval_vector(max_order, d);
        const auto pole = eval_vector(max_order, Eigen::Vector3d(0.0, 0.0, d.z()));
        for (int i = 0; i < coefficient_count(max_order); ++i) {
            ASSERT_TRUE(std::isfinite(y[i]));
            // |∇y| grows like l² for these bands; 1e-12 away the change is < 1e-9.
            EXPECT_NEAR(y[i], pole[i], 1e-9) << "index " << i;
        }
        const auto expected = closed_form_bands_0_to_3(d.normalized());
        for (int i = 0; i < 16; ++i) EXPECT_NEAR(y[i], expected[i], 1e-15) << "index " << i;
        // Band 1 keeps the sign of the tiny x, y offsets.
        EXPECT_EQ(std::signbit(y[sh_index(1, 1)]), std::signbit(d.x()));
    }
}

TEST(ShBasis, non_normalized_input_equals_normalized) {
    std::mt19937_64 rng(3);
    for (double scale : {1e-200, 1e-3, 7.5, 1e150}) {
        const Eigen::Vector3d d = testing::random_direction(rng);
        const auto unit = eval_vector(10, d);
        const auto scaled = eval_vector(10, scale * d);
        for (int i = 0; i < coefficient_count(10); ++i) EXPECT_NEAR(scaled[i], unit[i], 1e-14);
    }
}

TEST(ShBasis, zero_or_non_finite_direction_throws) {
    double out[16];
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_THROW(eval(4, Eigen::Vector3d::Zero(), out), ArgumentError);
    EXPECT_THROW(eval(4, Eigen::Vector3d(nan, 0, 1), out), ArgumentError);
    EXPECT_THROW(eval(4, Eigen::Vector3d(0, inf, 1), out), ArgumentError);
}

TEST(ShBasis, order_outside_1_to_16_throws) {
    double out[coefficient_count(max_order + 1)];
    EXPECT_THROW(eval(0, Eigen::Vector3d::UnitZ(), out), ArgumentError);
    EXPECT_THROW(eval(max_order + 1, Eigen::Vector3d::UnitZ(), out), ArgumentError);
    EXPECT_NO_THROW(eval(max_order, Eigen::Vector3d::UnitZ(), out));
}

}  // namespace
}  // namespace penumbra::sh
