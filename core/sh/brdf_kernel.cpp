// Operator of a tabulated 1D kernel (brdf_operator.hpp):
//   T[l'm, lm] = ∫_0^1 k(μ) p̄_l'|m|(μ) p̄_l|m|(μ) dμ,
// k piecewise linear between the samples. On each segment the integrand is a
// polynomial of degree ≤ 1 + 2(max_order − 1) = 31, which a 16-point
// Gauss–Legendre rule (point_sets.hpp) integrates exactly, so a new 1D BRDF needs no new
// derivation, only samples of its kernel.
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_operator.hpp"
#include "sh/legendre.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::sh {
namespace {

constexpr int rule_points = 16;  // exact to degree 2·16 − 1 = 31

struct GaussLegendreRule {
    std::vector<double> nodes, weights;  // on [−1, 1]
    GaussLegendreRule() { gauss_legendre(rule_points, nodes, weights); }
};

// p̄_lm(μ) = sqrt((2l+1)/2 · (l−m)!/(l+m)!) P_l^m(μ), orthonormal on [−1, 1],
// at out[m * order + l] for 0 <= m <= l < order: legendre.hpp's p̄_lm times
// sqrt(2π) sin^mθ, by the same recurrence in l at fixed m with the diagonal
//   p̄_mm = sqrt((2m+1)/(2m)) sinθ p̄_{m−1,m−1},   p̄_00 = 1/√2.
void normalized_legendre(int order, double mu, double* out) {
    const LegendreRecurrence& t = legendre_recurrence();
    const double sine = std::sqrt((1.0 - mu) * (1.0 + mu));  // accurate near μ = 1
    double diagonal = std::sqrt(0.5);
    for (int m = 0; m < order; ++m) {
        if (m > 0)
            diagonal *= std::sqrt((2.0 * m + 1.0) / (2.0 * m)) * sine;
        double* column = out + m * order;
        column[m] = diagonal;
        if (m + 1 < order)
            column[m + 1] = t.first[m] * mu * diagonal;
        for (int l = m + 2; l < order; ++l) {
            const int i = sh_index(l, m);
            column[l] = t.a[i] * (mu * column[l - 1] - t.b[i] * column[l - 2]);
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

    static const GaussLegendreRule rule;
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
