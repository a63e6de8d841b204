#include "sh/basis.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"

namespace penumbra::sh {
namespace {

// Coefficients of the fully normalized Legendre recurrence in l at fixed m:
//   p̄_mm      = sqrt((2m+1)/4π) · Π_{k=1..m} sqrt((2k−1)/(2k))
//   p̄_(m+1)m  = sqrt(2m+3) · z · p̄_mm
//   p̄_lm      = a_lm (z p̄_(l−1)m − b_lm p̄_(l−2)m),
//   a_lm = sqrt((4l²−1)/(l²−m²)),  b_lm = sqrt(((l−1)²−m²)/(4(l−1)²−1)).
// Normalizing inside the recurrence keeps every term O(1), where the textbook
// form multiplies (2m−1)!! by a tiny K_lm.
struct LegendreTable {
    std::array<double, max_order> diagonal{};
    std::array<double, max_order * max_order> a{};
    std::array<double, max_order * max_order> b{};

    LegendreTable() {
        double product = 1.0;
        for (int m = 0; m < max_order; ++m) {
            if (m > 0) product *= std::sqrt((2.0 * m - 1.0) / (2.0 * m));
            diagonal[m] = std::sqrt((2.0 * m + 1.0) / (4.0 * std::numbers::pi)) * product;
            for (int l = m + 2; l < max_order; ++l) {
                const double l2 = double(l) * l, m2 = double(m) * m, lm1 = l - 1.0;
                a[sh_index(l, m)] = std::sqrt((4.0 * l2 - 1.0) / (l2 - m2));
                b[sh_index(l, m)] = std::sqrt((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0));
            }
        }
    }
};

const LegendreTable& legendre_table() {
    static const LegendreTable table;
    return table;
}

}  // namespace

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

namespace detail {

void legendre_scaled(int order, double z, double* out) {
    const LegendreTable& t = legendre_table();
    for (int m = 0; m < order; ++m) {
        double before = t.diagonal[m];  // p̄_(l−2)m
        out[sh_index(m, m)] = before;
        if (m + 1 >= order) break;
        double last = std::sqrt(2.0 * m + 3.0) * z * before;  // p̄_(l−1)m
        out[sh_index(m + 1, m)] = last;
        for (int l = m + 2; l < order; ++l) {
            const int i = sh_index(l, m);
            const double next = t.a[i] * (z * last - t.b[i] * before);
            out[i] = next;
            before = last;
            last = next;
        }
    }
}

}  // namespace detail

void eval_unit(int order, const Eigen::Vector3d& d, double* out) {
    // p̄_lm for m >= 0 goes to the m >= 0 slots; the m < 0 slots are then
    // filled from them before the m > 0 slots are overwritten.
    detail::legendre_scaled(order, d.z(), out);

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
