// Phong and diffuse operators and the block form (derivation in the header;
// the numerics of one entry in brdf_moments.cpp; tabulated kernels in
// brdf_kernel.cpp).
#include "sh/brdf_operator.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_moments.hpp"

namespace penumbra::sh {

void ZonalOperator::apply(const double* v, double* t) const {
    // Gather each m's coefficients first, so that t may alias v.
    double gathered[max_order];
    for (int m = -(order - 1); m < order; ++m) {
        const int a = std::abs(m);
        const Eigen::MatrixXd& block = blocks[a];
        for (int l = a; l < order; ++l)
            gathered[l - a] = v[sh_index(l, m)];
        for (int l = a; l < order; ++l) {
            double sum = 0.0;
            for (int lp = a; lp < order; ++lp)
                sum += block(l - a, lp - a) * gathered[lp - a];
            t[sh_index(l, m)] = sum;
        }
    }
}

Eigen::MatrixXd ZonalOperator::dense() const {
    const int n = coefficient_count(order);
    Eigen::MatrixXd t = Eigen::MatrixXd::Zero(n, n);
    for (int m = -(order - 1); m < order; ++m) {
        const int a = std::abs(m);
        for (int l = a; l < order; ++l)
            for (int lp = a; lp < order; ++lp)
                t(sh_index(l, m), sh_index(lp, m)) = blocks[a](l - a, lp - a);
    }
    return t;
}

ZonalOperator phong_zonal_operator(int order, double alpha) {
    check_order(order);
    if (!(alpha >= 0.0))
        throw ArgumentError("phong_operator: the exponent alpha must be >= 0 (got " + std::to_string(alpha) + ")");

    ZonalOperator op{order, {}};
    for (int m = 0; m < order; ++m) {
        Eigen::MatrixXd block(order - m, order - m);
        for (int l = m; l < order; ++l) {
            for (int lp = l; lp < order; ++lp) {
                double value = 0.0;
                if (std::isinf(alpha)) {
                    // α → ∞: (α+1)∫μ^α f → f(1); p̄_lm(1) = sqrt((2l+1)/2) δ_m0.
                    if (m == 0)
                        value = std::sqrt((2 * l + 1) * (2 * lp + 1)) / (4.0 * std::numbers::pi);
                } else {
                    value = detail::phong_entry(l, lp, m, alpha).value;
                }
                block(l - m, lp - m) = block(lp - m, l - m) = value;
            }
        }
        op.blocks.push_back(std::move(block));
    }
    return op;
}

Eigen::MatrixXd phong_operator(int order, double alpha) { return phong_zonal_operator(order, alpha).dense(); }

ZonalOperator diffuse_zonal_operator(int order) { return phong_zonal_operator(order, 1.0); }

Eigen::MatrixXd diffuse_operator(int order) { return phong_operator(order, 1.0); }

Eigen::MatrixXd kernel_operator(int order, const std::vector<double>& k_of_mu) {
    return kernel_zonal_operator(order, k_of_mu).dense();
}

}  // namespace penumbra::sh
