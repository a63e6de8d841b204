// SH rotation: checked against projecting the rotated function by exact
// quadrature (independent of the recurrence), plus group properties.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/rotation.hpp"
#include "sh_test_util.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

// Coefficients of g(ω) = f(Rᵀω), f = Σ c_i y_i, by exact quadrature of
// degree 2(order−1): uses only basis evaluation, not the rotation code.
Eigen::VectorXd project_rotated(int order, const Eigen::VectorXd& c, const Eigen::Matrix3d& r) {
    const PointSet q = exact_sphere_quadrature(2 * order - 2);
    const int n = coefficient_count(order);
    Eigen::VectorXd out = Eigen::VectorXd::Zero(n), y(n), y_back(n);
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
        eval_unit(order, q.directions[k], y.data());
        eval_unit(order, r.transpose() * q.directions[k], y_back.data());
        out += q.weights[k] * c.dot(y_back) * y;
    }
    return out;
}

Eigen::VectorXd random_coefficients(int order, std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    Eigen::VectorXd c(coefficient_count(order));
    for (auto& v : c) v = normal(rng);
    return c;
}

Eigen::Matrix3d axis_angle(double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

TEST(ShRotation, rotating_coefficients_equals_projecting_the_rotated_function) {
    constexpr int order = 8;
    std::mt19937_64 rng(42);
    for (int trial = 0; trial < 10; ++trial) {
        const Eigen::Matrix3d r = testing::random_rotation(rng);
        const Eigen::VectorXd c = random_coefficients(order, rng);
        Eigen::VectorXd rotated(c.size());
        ShRotation(order, r).apply(c.data(), rotated.data());
        EXPECT_LT((rotated - project_rotated(order, c, r)).cwiseAbs().maxCoeff(), 1e-10) << "trial " << trial;
    }
}

TEST(ShRotation, half_turns_and_near_identity_match_quadrature) {
    constexpr int order = 8;
    std::mt19937_64 rng(5);
    const std::vector<Eigen::Matrix3d> rotations = {
        axis_angle(pi, Eigen::Vector3d::UnitX()), axis_angle(pi, Eigen::Vector3d::UnitY()),
        axis_angle(pi, Eigen::Vector3d::UnitZ()), axis_angle(pi, Eigen::Vector3d(1, 1, 1)),
        axis_angle(pi, Eigen::Vector3d(1, -2, 0.5)), axis_angle(1e-9, Eigen::Vector3d(0.3, 0.1, -1)),
        axis_angle(-1e-7, Eigen::Vector3d::UnitX())};
    for (const Eigen::Matrix3d& r : rotations) {
        const Eigen::VectorXd c = random_coefficients(order, rng);
        const Eigen::VectorXd rotated = ShRotation(order, r).apply(Eigen::MatrixXd(c));
        EXPECT_LT((rotated - project_rotated(order, c, r)).cwiseAbs().maxCoeff(), 1e-10);
    }
}

TEST(ShRotation, about_z_mixes_cos_and_sin_terms_by_m_alpha) {
    // f = cos(mφ)-type term; g(φ) = f(φ − α) = cos mα · cos mφ + sin mα · sin mφ.
    constexpr int order = 6;
    const double alpha = 0.7;
    const ShRotation rotation(order, axis_angle(alpha, Eigen::Vector3d::UnitZ()));
    for (int l = 1; l < order; ++l)
        for (int m = 1; m <= l; ++m) {
            Eigen::VectorXd c = Eigen::VectorXd::Zero(coefficient_count(order)), out(c.size());
            c[sh_index(l, m)] = 1.0;
            rotation.apply(c.data(), out.data());
            EXPECT_NEAR(out[sh_index(l, m)], std::cos(m * alpha), 1e-13);
            EXPECT_NEAR(out[sh_index(l, -m)], std::sin(m * alpha), 1e-13);
            EXPECT_NEAR(out.norm(), 1.0, 1e-13);
        }
}

TEST(ShRotation, band_1_is_the_rotation_matrix_in_y_z_x_order) {
    std::mt19937_64 rng(9);
    const Eigen::Matrix3d r = testing::random_rotation(rng);
    const ShRotation rotation(2, r);
    const Eigen::MatrixXd& d1 = rotation.band(1);
    const int axis_of[3] = {1, 2, 0};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_DOUBLE_EQ(d1(i, j), r(axis_of[i], axis_of[j]));
}

TEST(ShRotation, composes_as_a_representation) {
    std::mt19937_64 rng(123);
    for (int trial = 0; trial < 5; ++trial) {
        const Eigen::Matrix3d r1 = testing::random_rotation(rng), r2 = testing::random_rotation(rng);
        const Eigen::MatrixXd d12 = ShRotation(max_order, r1 * r2).matrix();
        const Eigen::MatrixXd d1_d2 = ShRotation(max_order, r1).matrix() * ShRotation(max_order, r2).matrix();
        EXPECT_LT((d12 - d1_d2).cwiseAbs().maxCoeff(), 1e-10);
    }
}

TEST(ShRotation, is_orthogonal_and_identity_maps_to_identity) {
    std::mt19937_64 rng(77);
    const int n = coefficient_count(max_order);
    const Eigen::MatrixXd d = ShRotation(max_order, testing::random_rotation(rng)).matrix();
    EXPECT_LT((d.transpose() * d - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-11);
    const Eigen::MatrixXd id = ShRotation(max_order, Eigen::Matrix3d::Identity()).matrix();
    EXPECT_LT((id - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ShRotation, applies_to_rgb_columns_independently) {
    constexpr int order = 5;
    std::mt19937_64 rng(8);
    const ShRotation rotation(order, testing::random_rotation(rng));
    Eigen::MatrixXd rgb(coefficient_count(order), 3);
    for (int ch = 0; ch < 3; ++ch) rgb.col(ch) = random_coefficients(order, rng);
    const Eigen::MatrixXd out = rotation.apply(rgb);
    for (int ch = 0; ch < 3; ++ch) {
        Eigen::VectorXd single(rgb.rows());
        const Eigen::VectorXd in = rgb.col(ch);
        rotation.apply(in.data(), single.data());
        EXPECT_LT((out.col(ch) - single).cwiseAbs().maxCoeff(), 1e-15);
    }
    EXPECT_THROW(rotation.apply(Eigen::MatrixXd::Zero(10, 3)), ArgumentError);
}

TEST(ShRotation, rejects_reflections_scalings_and_bad_orders) {
    Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
    mirror(0, 0) = -1.0;
    EXPECT_THROW(ShRotation(4, mirror), ArgumentError);
    EXPECT_THROW(ShRotation(4, 2.0 * Eigen::Matrix3d::Identity()), ArgumentError);
    EXPECT_THROW(ShRotation(0, Eigen::Matrix3d::Identity()), ArgumentError);
    EXPECT_THROW(ShRotation(max_order + 1, Eigen::Matrix3d::Identity()), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
