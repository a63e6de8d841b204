// 1D-BRDF operators (brdf_operator.hpp) against references that share no code
// with them: a brute-force 2D quadrature of Eq. 2 over the hemisphere with
// the angle-based y_lm, a 1D quadrature with std::assoc_legendre, and closed
// forms (α = 0 hemisphere integrals, the l = 0 row, the sectoral diagonal).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_moments.hpp"
#include "sh/brdf_operator.hpp"
#include "sh_test_util.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

// n-point Gauss–Legendre on [−1, 1], Newton on P_n in long double (the rule
// in brdf_kernel.cpp is a separate double-precision 16-point one).
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
    nodes.resize(n);
    weights.resize(n);
    for (int i = 0; i < n; ++i) {
        long double x = std::cos(pi * (i + 0.75) / (n + 0.5));
        long double dp = 1;
        for (int it = 0; it < 100; ++it) {
            long double p0 = 1, p1 = x;
            for (int j = 2; j <= n; ++j) {
                const long double p2 = ((2 * j - 1) * x * p1 - (j - 1) * p0) / j;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (x * p1 - p0) / (x * x - 1);
            const long double step = p1 / dp;
            x -= step;
            if (std::abs(step) < 1e-19L)
                break;
        }
        nodes[i] = double(x);
        weights[i] = double(2 / ((1 - x * x) * dp * dp));
    }
}

// (α+1)/(2π) ∫_0^1 μ^α f(μ) dμ with μ = exp(−x/(α+1)), which turns the weight
// into e^{−x} dx / (2π): smooth for every α, concentrated near μ = 1 for large
// α. Composite 20-point Gauss–Legendre on x ∈ [0, ≥ 80] (e^{−80} ≈ 2e−35
// lost), panels growing geometrically from 0.05 because the terms μ^k of f
// become e^{−(k+1)x/(α+1)}, steep near x = 0 for small α.
template <class F>
void phong_quadrature(double alpha, F&& visit) {
    std::vector<double> nodes, weights;
    gauss_legendre(20, nodes, weights);
    double start = 0.0, width = 0.05;
    while (start < 80.0) {
        for (int q = 0; q < 20; ++q) {
            const double x = start + 0.5 * width * (nodes[q] + 1.0);
            const double mu = std::exp(-x / (alpha + 1.0));
            visit(mu, 0.5 * width * weights[q] * std::exp(-x) / (2.0 * pi));
        }
        start += width;
        width *= 1.25;
    }
}

// p̄_lm(μ) = sqrt((2l+1)/2 · (l−m)!/(l+m)!) P_l^m(μ) via std::assoc_legendre.
double reference_normalized_legendre(int l, int m, double mu) {
    const double n = std::sqrt((2.0 * l + 1.0) / 2.0 * std::exp(std::lgamma(l - m + 1.0) - std::lgamma(l + m + 1.0)));
    return n * std::assoc_legendre(l, m, mu);
}

// Cauchy–Schwarz scale of an entry (the kernels are non-negative).
double entry_scale(const Eigen::MatrixXd& t, int i, int j) { return std::sqrt(t(i, i) * t(j, j)); }

class PhongOperatorAlpha : public ::testing::TestWithParam<double> {};

TEST_P(PhongOperatorAlpha, matches_brute_force_integral_over_the_hemisphere) {
    // Eq. 2 as written: a 2D quadrature in (μ, φ) of μ^α y_i y_j with the
    // angle-based y_lm, so the m-structure is checked too, not assumed.
    const double alpha = GetParam();
    const int order = 6, n = order * order, phi_steps = 32;  // trapezoid exact to frequency 31
    Eigen::MatrixXd brute = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd y(n);
    phong_quadrature(alpha, [&](double mu, double weight) {
        const double sine = std::sqrt((1.0 - mu) * (1.0 + mu));
        for (int k = 0; k < phi_steps; ++k) {
            const double phi = 2.0 * pi * (k + 0.5) / phi_steps;
            const Eigen::Vector3d d(sine * std::cos(phi), sine * std::sin(phi), mu);
            for (int l = 0; l < order; ++l)
                for (int m = -l; m <= l; ++m)
                    y[sh_index(l, m)] = testing::reference_y(l, m, d);
            brute.noalias() += (weight * 2.0 * pi / phi_steps) * y * y.transpose();
        }
    });
    const Eigen::MatrixXd t = phong_operator(order, alpha);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            EXPECT_NEAR(t(i, j), brute(i, j), 1e-13 + 1e-12 * entry_scale(brute, i, j))
                << "alpha " << alpha << " entry " << i << ", " << j;
}

TEST_P(PhongOperatorAlpha, matches_legendre_quadrature_up_to_order_16) {
    // All 16 bands: (α+1)/(2π) ∫ μ^α p̄_l'm p̄_lm by quadrature, std::assoc_legendre.
    const double alpha = GetParam();
    const int order = max_order;
    std::vector<Eigen::MatrixXd> reference;
    for (int m = 0; m < order; ++m)
        reference.push_back(Eigen::MatrixXd::Zero(order - m, order - m));
    phong_quadrature(alpha, [&](double mu, double weight) {
        for (int m = 0; m < order; ++m) {
            Eigen::VectorXd p(order - m);
            for (int l = m; l < order; ++l)
                p[l - m] = reference_normalized_legendre(l, m, mu);
            reference[m].noalias() += weight * p * p.transpose();
        }
    });
    const ZonalOperator op = phong_zonal_operator(order, alpha);
    for (int m = 0; m < order; ++m)
        for (int i = 0; i < order - m; ++i)
            for (int j = 0; j < order - m; ++j) {
                const double scale = std::sqrt(reference[m](i, i) * reference[m](j, j));
                EXPECT_NEAR(op.blocks[m](i, j), reference[m](i, j), 1e-300 + 1e-11 * scale)
                    << "alpha " << alpha << " m " << m << " l " << i + m << " l' " << j + m;
            }
}

INSTANTIATE_TEST_SUITE_P(Exponents, PhongOperatorAlpha, ::testing::Values(0.0, 0.5, 1.0, 8.0, 64.0, 1000.0));

TEST(PhongOperator, vanishes_unless_m_equal_and_repeats_for_plus_and_minus_m) {
    const int order = 8;
    const Eigen::MatrixXd t = phong_operator(order, 3.7);
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m)
            for (int lp = 0; lp < order; ++lp)
                for (int mp = -lp; mp <= lp; ++mp) {
                    const double value = t(sh_index(l, m), sh_index(lp, mp));
                    EXPECT_EQ(value, t(sh_index(lp, mp), sh_index(l, m)));
                    if (mp != m) {
                        EXPECT_EQ(value, 0.0);
                    } else {
                        EXPECT_NE(value, 0.0) << l << " " << lp << " " << m;  // l + l' of either parity
                        EXPECT_EQ(value, t(sh_index(l, -m), sh_index(lp, -m)));
                    }
                }
}

TEST(PhongOperator, order_4_has_44_non_zero_and_20_distinct_entries) {
    // The paper's "17.1 % non-zero" (44/256); its "5.9 % unique" would be 15.
    const Eigen::MatrixXd t = phong_operator(4, 2.5);
    int non_zero = 0;
    std::set<double> distinct;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j)
            if (t(i, j) != 0.0) {
                ++non_zero;
                distinct.insert(t(i, j));
            }
    EXPECT_EQ(non_zero, 44);
    EXPECT_EQ(distinct.size(), 20u);
}

TEST(PhongOperator, at_alpha_0_is_the_hemisphere_gram_matrix) {
    // (1/2π)∫_H y_i y_j: diagonal 1/(4π) (y² is even under μ → −μ); zero
    // between different bands of equal parity (half of the full-sphere
    // orthogonality integral); for m = 0 and l even, l' odd the closed form
    // ∫_0^1 P_l P_l' dμ = (−1)^((l+l'+1)/2) l! l'! /
    //     (2^(l+l'−1) (l−l') (l+l'+1) ((l/2)!)² (((l'−1)/2)!)²).
    const int order = max_order;
    const Eigen::MatrixXd t = phong_operator(order, 0.0);
    for (int l = 0; l < order; ++l)
        for (int lp = 0; lp < order; ++lp)
            for (int m = -std::min(l, lp); m <= std::min(l, lp); ++m) {
                const double value = t(sh_index(l, m), sh_index(lp, m));
                if (l == lp) {
                    EXPECT_NEAR(value, 1.0 / (4.0 * pi), 1e-15);
                } else if ((l + lp) % 2 == 0) {
                    EXPECT_EQ(value, 0.0);
                }
            }
    for (int l = 0; l < order; l += 2)
        for (int lp = 1; lp < order; lp += 2) {
            const double log_magnitude = std::lgamma(l + 1.0) + std::lgamma(lp + 1.0) -
                                         (l + lp - 1) * std::log(2.0) - 2 * std::lgamma(l / 2 + 1.0) -
                                         2 * std::lgamma((lp - 1) / 2 + 1.0);
            const double sign = ((l + lp + 1) / 2) % 2 ? -1.0 : 1.0;
            const double integral = sign * std::exp(log_magnitude) / ((l - lp) * (l + lp + 1.0));
            const double expected = std::sqrt((2.0 * l + 1.0) * (2.0 * lp + 1.0)) / 2.0 * integral / (2.0 * pi);
            EXPECT_NEAR(t(sh_index(l, 0), sh_index(lp, 0)), expected, 1e-13 * std::abs(expected)) << l << " " << lp;
        }
}

TEST(PhongOperator, keeps_relative_accuracy_of_the_l0_row_for_tiny_and_huge_alpha) {
    // ∫_0^1 μ^α P_2 = α/((α+1)(α+3)) and ∫_0^1 μ^α P_3 = (α−1)/((α+2)(α+4)):
    // entries that vanish at α = 0 resp. α = 1 and must keep their digits
    // next to those zeros.
    for (double alpha : {1e-12, 1e-6, 0.5, 1.0 + 1e-9, 2.5, 12345.678, 1e6, 1e9}) {
        const Eigen::MatrixXd t = phong_operator(4, alpha);
        const double t02 = std::sqrt(5.0) * alpha / (4.0 * pi * (alpha + 3.0));
        const double t03 = std::sqrt(7.0) * (alpha + 1.0) * (alpha - 1.0) / (4.0 * pi * (alpha + 2.0) * (alpha + 4.0));
        EXPECT_NEAR(t(0, sh_index(2, 0)), t02, 1e-14 * std::abs(t02)) << alpha;
        EXPECT_NEAR(t(0, sh_index(3, 0)), t03, 1e-14 * std::abs(t03) + (alpha == 1.0 + 1e-9 ? 1e-22 : 0.0))
            << alpha;
    }
    EXPECT_EQ(phong_operator(4, 1.0)(0, sh_index(3, 0)), 0.0);
}

TEST(PhongOperator, keeps_relative_accuracy_of_equal_parity_entries_at_tiny_alpha) {
    // For l ≠ l' of equal parity the entry is 0 at α = 0 and its slope there is
    // (1/2π) ∫_0^1 ln μ · p̄_l'm p̄_lm dμ (differentiate (α+1)∫μ^α Q, ∫Q = 0),
    // so at α = 1e−25 the entry must be α times that slope to ~1e−13: the
    // digits come from the α-factored sum, not from a difference of O(1) terms.
    const double alpha = 1e-25;
    const int order = max_order;
    std::vector<Eigen::MatrixXd> slope;
    for (int m = 0; m < order; ++m)
        slope.push_back(Eigen::MatrixXd::Zero(order - m, order - m));
    phong_quadrature(0.0, [&](double mu, double weight) {
        for (int m = 0; m < order; ++m) {
            Eigen::VectorXd p(order - m);
            for (int l = m; l < order; ++l)
                p[l - m] = reference_normalized_legendre(l, m, mu);
            slope[m].noalias() += weight * std::log(mu) * p * p.transpose();
        }
    });
    const ZonalOperator op = phong_zonal_operator(order, alpha);
    int checked = 0;
    for (int m = 0; m < order; ++m)
        for (int l = m; l < order; ++l)
            for (int lp = l + 2; lp < order; lp += 2) {
                const double expected = alpha * slope[m](l - m, lp - m);
                EXPECT_NEAR(op.blocks[m](l - m, lp - m), expected, 1e-12 * std::abs(expected)) << m << " " << l << " " << lp;
                ++checked;
            }
    EXPECT_EQ(checked, 308);  // every pair l < l' of equal parity, all m
}

TEST(PhongOperator, keeps_relative_accuracy_of_sectoral_entries_at_alpha_1e6) {
    // p̄_ll² = (2l+1)/2 · (2l−1)!!²/(2l)! (1−μ²)^l and, with ν = μ²,
    // (α+1)∫_0^1 μ^α (1−μ²)^l dμ = (α+1)/2 · l! / ∏_{i=0}^{l} ((α+1)/2 + i).
    // At α = 1e6 the l = 15 entry is ~1e−90, far below any cancellation in a
    // power-basis sum.
    for (double alpha : {1e-12, 2.5, 12345.678, 1e6, 1e9}) {
        const ZonalOperator op = phong_zonal_operator(max_order, alpha);
        for (int l = 0; l < max_order; ++l) {
            long double value = (2.0L * l + 1) / 2 * (alpha + 1.0L) / 2 / (2 * pi);
            for (int i = 1; i <= 2 * l; ++i)  // (2l−1)!!² / (2l)! = ∏ odd/even
                value *= (i % 2 ? i : 1.0L / i);
            for (int i = 0; i <= l; ++i)
                value *= (i == 0 ? 1.0L : i) / ((alpha + 1.0L) / 2 + i);
            EXPECT_NEAR(op.blocks[l](0, 0), double(value), 1e-13 * double(value)) << alpha << " " << l;
        }
    }
}

TEST(PhongOperator, approaches_yz_yz_transposed_as_one_over_alpha) {
    const int order = max_order, n = order * order;
    Eigen::VectorXd yz(n);
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m)
            yz[sh_index(l, m)] = testing::reference_y(l, m, Eigen::Vector3d(0, 0, 1));
    const Eigen::MatrixXd limit = yz * yz.transpose();
    const double error_1e6 = (phong_operator(order, 1e6) - limit).cwiseAbs().maxCoeff();
    const double error_1e9 = (phong_operator(order, 1e9) - limit).cwiseAbs().maxCoeff();
    EXPECT_LT(error_1e6, 1e-3);
    EXPECT_NEAR(error_1e6 * 1e6, error_1e9 * 1e9, 1e-2 * error_1e6 * 1e6);  // same O(1/α) constant
    EXPECT_LT((phong_operator(order, std::numeric_limits<double>::infinity()) - limit).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(PhongOperator, chosen_sum_is_well_conditioned_for_all_exponents) {
    // The worst case measured while designing brdf_moments.cpp was 2e10:
    // double-double then leaves ~1e−21 relative error. Exponents chosen off
    // the integers, where individual entries cross zero.
    for (double alpha : {1e-12, 1e-3, 0.37, 2.5, 7.9, 33.3, 150.5, 1234.5, 12345.678, 1e6, 1e9}) {
        double worst = 0.0;
        for (int m = 0; m < max_order; ++m)
            for (int l = m; l < max_order; ++l)
                for (int lp = l; lp < max_order; ++lp)
                    worst = std::max(worst, detail::phong_entry(l, lp, m, alpha).condition);
        EXPECT_LT(worst, 1e11) << alpha;
    }
}

TEST(DiffuseOperator, shades_a_fully_visible_vertex_under_unit_radiance_to_one) {
    for (int order : {1, 2, 4, max_order}) {
        const Eigen::MatrixXd t = diffuse_operator(order);
        Eigen::VectorXd unit = Eigen::VectorXd::Zero(order * order);
        unit[0] = std::sqrt(4.0 * pi);  // radiance 1 and visibility 1 everywhere
        EXPECT_NEAR(unit.dot(t * unit), 1.0, 1e-15);
        EXPECT_EQ(t, phong_operator(order, 1.0));
    }
}

TEST(DiffuseOperator, gives_lambert_shading_of_a_linear_radiance) {
    // Radiance L(s) = z (the y_10 direction): unshadowed Lambert irradiance/π
    // = (1/π)∫_H z·z ds = 2/3.
    const Eigen::MatrixXd t = diffuse_operator(3);
    Eigen::VectorXd light = Eigen::VectorXd::Zero(9), visible = Eigen::VectorXd::Zero(9);
    light[sh_index(1, 0)] = std::sqrt(4.0 * pi / 3.0);
    visible[0] = std::sqrt(4.0 * pi);
    EXPECT_NEAR(light.dot(t * visible), 2.0 / 3.0, 1e-15);
}

std::vector<double> sample_kernel(int samples, double alpha) {
    std::vector<double> k(samples);
    for (int i = 0; i < samples; ++i)
        k[i] = (alpha + 1.0) / (2.0 * pi) * std::pow(double(i) / (samples - 1), alpha);
    return k;
}

TEST(KernelOperator, reproduces_linear_kernels_exactly) {
    // k = μ/π is the diffuse kernel and k = 1/(2π) is Phong at α = 0: both
    // linear, so two samples already define them exactly.
    EXPECT_LT((kernel_operator(max_order, sample_kernel(2, 1.0)) - diffuse_operator(max_order)).cwiseAbs().maxCoeff(),
              1e-14);
    EXPECT_LT((kernel_operator(max_order, sample_kernel(7, 1.0)) - diffuse_operator(max_order)).cwiseAbs().maxCoeff(),
              1e-14);
    EXPECT_LT((kernel_operator(max_order, {0.5 / pi, 0.5 / pi}) - phong_operator(max_order, 0.0)).cwiseAbs().maxCoeff(),
              1e-14);
}

TEST(KernelOperator, converges_to_phong_at_the_piecewise_linear_rate) {
    // |ΔT| ≤ max|k − k_h| ∫|p̄ p̄'| ≤ h²/8 · max|k''| (Cauchy–Schwarz), and
    // halving h quarters the error.
    const double alpha = 8.0;
    const Eigen::MatrixXd phong = phong_operator(8, alpha);
    const double k2 = (alpha + 1.0) / (2.0 * pi) * alpha * (alpha - 1.0);
    double previous = 0.0;
    for (int samples : {501, 1001, 2001}) {
        const double h = 1.0 / (samples - 1);
        const double error = (kernel_operator(8, sample_kernel(samples, alpha)) - phong).cwiseAbs().maxCoeff();
        EXPECT_LT(error, h * h / 8.0 * k2);
        if (previous > 0.0) {
            EXPECT_GT(previous / error, 3.9);
            EXPECT_LT(previous / error, 4.1);
        }
        previous = error;
    }
}

TEST(ZonalOperator, applies_like_the_dense_matrix_even_in_place) {
    const int order = 7, n = order * order;
    const ZonalOperator op = phong_zonal_operator(order, 20.0);
    const Eigen::MatrixXd dense = op.dense();
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i)
        v[i] = std::sin(1.0 + 3.0 * i);
    Eigen::VectorXd t(n);
    op.apply(v.data(), t.data());
    const Eigen::VectorXd expected = dense * v;
    EXPECT_LT((t - expected).cwiseAbs().maxCoeff(), 1e-15);
    op.apply(v.data(), v.data());
    EXPECT_LT((v - expected).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(BrdfOperators, reject_invalid_arguments) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(phong_operator(0, 1.0), ArgumentError);
    EXPECT_THROW(phong_operator(max_order + 1, 1.0), ArgumentError);
    EXPECT_THROW(phong_operator(4, -1e-300), ArgumentError);
    EXPECT_THROW(phong_operator(4, nan), ArgumentError);
    EXPECT_THROW(diffuse_operator(0), ArgumentError);
    EXPECT_THROW(kernel_operator(4, {}), ArgumentError);
    EXPECT_THROW(kernel_operator(4, {1.0}), ArgumentError);
    EXPECT_THROW(kernel_operator(4, {1.0, nan}), ArgumentError);
    EXPECT_THROW(kernel_operator(4, {std::numeric_limits<double>::infinity(), 1.0}), ArgumentError);
    EXPECT_THROW(kernel_operator(17, {1.0, 1.0}), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
