// The normalized Legendre recurrence (sh/legendre.hpp) against libstdc++'s
// std::assoc_legendre and factorials from lgamma, which share no code with it.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "sh/basis.hpp"
#include "sh/legendre.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

// K_lm P_l^m(z) / sin^mθ, angle-free only where sinθ > 0.
double reference_scaled(int l, int m, double z) {
    const double k =
        std::sqrt((2.0 * l + 1.0) / (4.0 * pi) * std::exp(std::lgamma(l - m + 1.0) - std::lgamma(l + m + 1.0)));
    return k * std::assoc_legendre(l, m, z) / std::pow(std::sqrt(1.0 - z * z), m);
}

TEST(Legendre, scaled_factors_match_assoc_legendre_up_to_max_order) {
    std::vector<double> p(coefficient_count(max_order));
    for (double z : {-0.93, -0.5, -0.1, 0.0, 0.27, 0.6, 0.88}) {
        legendre_scaled(max_order, z, p.data());
        for (int l = 0; l < max_order; ++l)
            for (int m = 0; m <= l; ++m) {
                const double expected = reference_scaled(l, m, z);
                EXPECT_NEAR(p[sh_index(l, m)], expected, 1e-12 * std::max(1.0, std::abs(expected)))
                    << "l=" << l << " m=" << m << " z=" << z;
            }
    }
}

TEST(Legendre, zonal_factors_at_the_poles_are_exact) {
    // p̄_l0(±1) = (±1)^l sqrt((2l+1)/4π): the recurrence is a polynomial in z.
    std::vector<double> up(coefficient_count(max_order)), down(coefficient_count(max_order));
    legendre_scaled(max_order, 1.0, up.data());
    legendre_scaled(max_order, -1.0, down.data());
    for (int l = 0; l < max_order; ++l) {
        const double expected = std::sqrt((2.0 * l + 1.0) / (4.0 * pi));
        EXPECT_NEAR(up[sh_index(l, 0)], expected, 1e-13) << l;
        EXPECT_NEAR(down[sh_index(l, 0)], (l % 2 ? -1.0 : 1.0) * expected, 1e-13) << l;
    }
}

TEST(Legendre, lower_orders_are_a_prefix_and_negative_m_slots_are_left_alone) {
    std::vector<double> full(coefficient_count(max_order)), part(coefficient_count(5), -7.0);
    legendre_scaled(max_order, 0.3, full.data());
    legendre_scaled(5, 0.3, part.data());
    for (int l = 0; l < 5; ++l)
        for (int m = -l; m <= l; ++m)
            EXPECT_EQ(part[sh_index(l, m)], m >= 0 ? full[sh_index(l, m)] : -7.0) << l << ", " << m;
}

}  // namespace
}  // namespace penumbra::sh
