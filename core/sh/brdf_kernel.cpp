// Operator of a tabulated 1D kernel (brdf_operator.hpp):
//   T[l'm, lm] = ∫_0^1 k(μ) p̄_l'|m|(μ) p̄_l|m|(μ) dμ,
// k piecewise linear between the samples. On each segment the integrand is a
// polynomial of degree ≤ 1 + 2(max_order − 1) = 31, which a 16-point
// Gauss–Legendre rule integrates exactly, so a new 1D BRDF needs no new
// derivation, only samples of its kernel.
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_operator.hpp"

namespace penumbra::sh {
namespace {

constexpr int rule_points = 16;  // exact to degree 2·16 − 1 = 31

struct GaussLegendreRule {
    std::array<double, rule_points> nodes{};    // on [−1, 1]
    std::array<double, rule_points> weights{};
};

// Newton on P_n from the Chebyshev-like first guess cos(π(i − ¼)/(n + ½))
// (Numerical Recipes' gauleg); converges to full precision in a few steps.
GaussLegendreRule make_gauss_legendre() {
    GaussLegendreRule rule;
    const int n = rule_points;
    for (int i = 0; i < n; ++i) {
        double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
        double derivative = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            double p = 1.0, p_previous = 0.0;
            for (int j = 1; j <= n; ++j) {
                const double p_before = p_previous;
                p_previous = p;
                p = ((2.0 * j - 1.0) * x * p_previous - (j - 1.0) * p_before) / j;
            }
            derivative = n * (x * p - p_previous) / (x * x - 1.0);
            const double step = p / derivative;
            x -= step;
            if (std::abs(step) < 1e-16)
                break;
        }
        rule.nodes[i] = x;
        rule.weights[i] = 2.0 / ((1.0 - x * x) * derivative * derivative);
    }
    return rule;
}

// p̄_lm(μ) = sqrt((2l+1)/2 · (l−m)!/(l+m)!) P_l^m(μ), orthonormal on [−1, 1],
// at out[m * order + l] for 0 <= m <= l < order. Forward recurrence in l at
// fixed m, stable for the normalized functions:
//   p̄_mm = sqrt((2m+1)/(2m)) sinθ p̄_{m−1,m−1},   p̄_00 = 1/√2,
//   p̄_lm = a_lm (μ p̄_{l−1,m} − b_lm p̄_{l−2,m}),
//   a_lm = sqrt((4l²−1)/(l²−m²)),  b_lm = sqrt(((l−1)²−m²)/(4(l−1)²−1)).
void normalized_legendre(int order, double mu, double* out) {
    const double sine = std::sqrt((1.0 - mu) * (1.0 + mu));  // accurate near μ = 1
    double diagonal = std::sqrt(0.5);
    for (int m = 0; m < order; ++m) {
        if (m > 0)
            diagonal *= std::sqrt((2.0 * m + 1.0) / (2.0 * m)) * sine;
        double* column = out + m * order;
        column[m] = diagonal;
        if (m + 1 < order)
            column[m + 1] = std::sqrt(2.0 * m + 3.0) * mu * diagonal;
        for (int l = m + 2; l < order; ++l) {
            const double a = std::sqrt((4.0 * l * l - 1.0) / (double(l) * l - double(m) * m));
            const double b = std::sqrt((double(l - 1) * (l - 1) - double(m) * m) / (4.0 * (l - 1) * (l - 1) - 1.0));
            column[l] = a * (mu * column[l - 1] - b * column[l - 2]);
        }
    }
}

}  // namespace

ZonalOperator kernel_zonal_operator(int order, const std::vector<double>& k_of_mu) {
    check_order(order);
    if (k_of_mu.size() < 2)
        throw ArgumentError("kernel_operator: the kernel needs at least 2 samples k(mu_i), mu_i = i/(n-1) (got " +
                            std::to_string(k_of_mu.size()) + ")");
    for (std::size_t i = 0; i < k_of_mu.size(); ++i)
        if (!std::isfinite(k_of_mu[i]))
            throw ArgumentError("kernel_operator: kernel sample " + std::to_string(i) + " is not finite");

    static const GaussLegendreRule rule = make_gauss_legendre();
    const int segments = int(k_of_mu.size()) - 1;
    const double width = 1.0 / segments;

    ZonalOperator op{order, {}};
    for (int m = 0; m < order; ++m)
        op.blocks.push_back(Eigen::MatrixXd::Zero(order - m, order - m));

    std::array<double, max_order * max_order> legendre{};
    for (int s = 0; s < segments; ++s) {
        const double k0 = k_of_mu[s], k1 = k_of_mu[s + 1];
        if (k0 == 0.0 && k1 == 0.0)
            continue;
        for (int q = 0; q < rule_points; ++q) {
            const double x = 0.5 * (rule.nodes[q] + 1.0);  // position in the segment, [0, 1]
            const double mu = (s + x) * width;
            const double weight = 0.5 * width * rule.weights[q] * ((1.0 - x) * k0 + x * k1);
            normalized_legendre(order, mu, legendre.data());
            // Upper triangle only; mirrored below.
            for (int m = 0; m < order; ++m) {
                const double* column = legendre.data() + m * order;
                Eigen::MatrixXd& block = op.blocks[m];
                for (int lp = m; lp < order; ++lp) {
                    const double scaled = weight * column[lp];
                    for (int l = m; l <= lp; ++l)
                        block(l - m, lp - m) += scaled * column[l];
                }
            }
        }
    }
    for (auto& block : op.blocks)
        for (int lp = 0; lp < block.cols(); ++lp)
            for (int l = 0; l < lp; ++l)
                block(lp, l) = block(l, lp);
    return op;
}

}  // namespace penumbra::sh
