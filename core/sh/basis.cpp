#include "sh/basis.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "sh/legendre.hpp"

namespace penumbra::sh {

void check_order(int order) {
    if (order < 1 || order > max_order)
        throw ArgumentError("SH order must be between 1 and " + std::to_string(max_order) +
                            ", got " + std::to_string(order));
}

Eigen::Vector3d unit_direction(const Eigen::Vector3d& direction, const char* what) {
    if (!direction.allFinite())
        throw ArgumentError(std::string(what) + " has a NaN or infinite component");
    // Divide by the largest component first so tiny (1e-200) or huge (1e200)
    // vectors neither underflow to zero nor overflow in the squared norm.
    const double largest = direction.cwiseAbs().maxCoeff();
    if (!(largest > 0.0)) throw ArgumentError(std::string(what) + " has zero length");
    const Eigen::Vector3d scaled = direction / largest;
    return scaled / scaled.norm();
}

void eval_unit(int order, const Eigen::Vector3d& d, double* out) {
    // p̄_lm for m >= 0 goes to the m >= 0 slots; the m < 0 slots are then
    // filled from them before the m > 0 slots are overwritten.
    legendre_scaled(order, d.z(), out);

    // C_m + i S_m = (x + iy)^m = sin^mθ (cos mφ + i sin mφ).
    double c = 1.0, s = 0.0;
    for (int m = 1; m < order; ++m) {
        const double c_next = d.x() * c - d.y() * s;
        s = d.x() * s + d.y() * c;
        c = c_next;
        for (int l = m; l < order; ++l) {
            const double p = std::numbers::sqrt2 * out[sh_index(l, m)];
            out[sh_index(l, -m)] = p * s;
            out[sh_index(l, m)] = p * c;
        }
    }
}

void eval(int order, const Eigen::Vector3d& direction, double* out) {
    check_order(order);
    eval_unit(order, unit_direction(direction), out);
}

}  // namespace penumbra::sh
