#include "sh/legendre.hpp"

#include <cmath>
#include <numbers>

namespace penumbra::sh {
namespace {

LegendreRecurrence make_recurrence() {
    LegendreRecurrence t;
    double product = 1.0;
    for (int m = 0; m < max_order; ++m) {
        if (m > 0) product *= std::sqrt((2.0 * m - 1.0) / (2.0 * m));
        t.diagonal[m] = std::sqrt((2.0 * m + 1.0) / (4.0 * std::numbers::pi)) * product;
        t.first[m] = std::sqrt(2.0 * m + 3.0);
        for (int l = m + 2; l < max_order; ++l) {
            const double l2 = double(l) * l, m2 = double(m) * m, lm1 = l - 1.0;
            t.a[sh_index(l, m)] = std::sqrt((4.0 * l2 - 1.0) / (l2 - m2));
            t.b[sh_index(l, m)] = std::sqrt((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0));
        }
    }
    return t;
}

}  // namespace

const LegendreRecurrence& legendre_recurrence() {
    static const LegendreRecurrence table = make_recurrence();
    return table;
}

void legendre_scaled(int order, double z, double* out) {
    const LegendreRecurrence& t = legendre_recurrence();
    for (int m = 0; m < order; ++m) {
        double before = t.diagonal[m];  // p̄_(l−2)m
        out[sh_index(m, m)] = before;
        if (m + 1 >= order) break;
        double last = t.first[m] * z * before;  // p̄_(l−1)m
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

}  // namespace penumbra::sh
