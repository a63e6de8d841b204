#include "sh/zonal.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "sh/legendre.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::sh {

void zh_to_sh_accumulate(int order, const Eigen::Vector3d& axis, const double* band, double* sh) {
    check_order(order);
    double y[max_order * max_order];
    eval_unit(order, unit_direction(axis, "ZH lobe axis"), y);
    // Eq. 1: v_l^m += sqrt(4π/(2l+1)) v_l y_l^m(s).
    for (int l = 0; l < order; ++l) {
        const double scale = std::sqrt(4.0 * std::numbers::pi / (2.0 * l + 1.0)) * band[l];
        for (int m = -l; m <= l; ++m) sh[sh_index(l, m)] += scale * y[sh_index(l, m)];
    }
}

void zh_to_sh_accumulate(int order, const ZhLobe& lobe, double* sh) {
    zh_to_sh_accumulate(order, lobe.axis, lobe.band.data(), sh);
}

ZhLobe rotate_lobe(const ZhLobe& lobe, const Eigen::Matrix3d& rotation) {
    ZhLobe turned = lobe;
    turned.axis = unit_direction(rotation * lobe.axis, "rotated ZH lobe axis");
    return turned;
}

std::array<double, max_order> project_zonal(int order, const std::function<double(double)>& f,
                                            int quadrature_nodes) {
    check_order(order);
    std::vector<double> mu, w;
    gauss_legendre(quadrature_nodes, mu, w);
    std::array<double, max_order> band{};
    double p[max_order * max_order];
    for (int k = 0; k < quadrature_nodes; ++k) {
        const double value = f(mu[k]);
        legendre_scaled(order, mu[k], p);  // p̄_l0 = y_l0
        for (int l = 0; l < order; ++l) band[l] += 2.0 * std::numbers::pi * w[k] * value * p[sh_index(l, 0)];
    }
    return band;
}

}  // namespace penumbra::sh
