// Microsurface statistics against independent references: order statistics
// of normals (the effective height distribution for integer Λ is the
// distribution of the largest of Λ + 1 standard normals), brute-force
// quadrature, and the direct formula for Λ.
#include <gtest/gtest.h>

#include <cmath>

#include "colormap/microsurface.hpp"
#include "common/error.hpp"

namespace penumbra::colormap {
namespace {

constexpr double pi = 3.14159265358979323846;

TEST(Microsurface, smith_lambda_matches_the_paper_formula_and_is_robust_at_extremes) {
    for (double a : {0.05, 0.3, 1.0, 2.5, 5.0, 12.0}) {
        const double direct = std::exp(-0.5 * a * a) / (std::sqrt(2 * pi) * a) - 0.5 * std::erfc(a / std::sqrt(2.0));
        EXPECT_NEAR(smith_lambda_of_a(a), direct, 1e-14 + 1e-12 * direct);
    }
    // Across the switch to the asymptotic series Λ is continuous.
    EXPECT_NEAR(smith_lambda_of_a(20.0 - 1e-12) / smith_lambda_of_a(20.0 + 1e-12), 1.0, 1e-9);
    EXPECT_EQ(smith_lambda(0.0, 0.3), 0.0);
    EXPECT_TRUE(std::isinf(smith_lambda(pi / 2, 0.3)));
    EXPECT_EQ(smith_lambda(1.2, 0.0), 0.0);  // a flat surface masks nothing
    EXPECT_GT(smith_lambda(pi / 2 - 1e-9, 0.3), 1e6);
    EXPECT_GE(smith_lambda(1e-9, 0.3), 0.0);
    double previous = 0.0;
    for (int i = 1; i < 90; ++i) {
        const double l = smith_lambda(i * pi / 180, 0.4);
        EXPECT_GE(l, previous);
        previous = l;
    }
}

TEST(Microsurface, average_visibility_follows_eq_13_and_its_limits) {
    EXPECT_DOUBLE_EQ(average_visibility(0.0, 0.0), 1.0);
    EXPECT_DOUBLE_EQ(average_visibility(1.0, 2.0), 0.5);
    EXPECT_DOUBLE_EQ(average_visibility(0.3, INFINITY), 0.0);
    EXPECT_DOUBLE_EQ(average_visibility(INFINITY, 0.3), 1.0);
    EXPECT_DOUBLE_EQ(average_visibility(INFINITY, INFINITY), 0.5);
}

TEST(Microsurface, exact_height_statistics_are_order_statistics_for_integer_lambda) {
    // E and Var of max of n standard normals (n = 2..5), known values.
    const double mean[] = {0.5641895835, 0.8462843753, 1.0293753730, 1.1629644736};
    const double var[] = {0.6816901138, 0.5594672037, 0.4917152368, 0.4475340691};
    for (int n = 2; n <= 5; ++n) {
        const HeightStatistics h = effective_height_exact(n - 1.0);
        EXPECT_NEAR(h.mean, mean[n - 2], 1e-8) << n;
        EXPECT_NEAR(h.stddev, std::sqrt(var[n - 2]), 1e-8) << n;
    }
    const HeightStatistics zero = effective_height_exact(0.0);
    EXPECT_DOUBLE_EQ(zero.mean, 0.0);
    EXPECT_DOUBLE_EQ(zero.stddev, 1.0);
}

TEST(Microsurface, exact_height_statistics_survive_huge_lambda) {
    double previous_mean = 0.0, previous_sd = 1.0;
    for (double L : {1e-6, 0.01, 0.5, 10.0, 1e3, 1e6, 1e9, 1e12}) {
        const HeightStatistics h = effective_height_exact(L);
        ASSERT_TRUE(std::isfinite(h.mean) && std::isfinite(h.stddev)) << L;
        EXPECT_GT(h.mean, previous_mean);
        EXPECT_LT(h.stddev, previous_sd);
        previous_mean = h.mean;
        previous_sd = h.stddev;
    }
    // Extreme-value theory: the max of n normals concentrates near sqrt(2 ln n).
    const double n = 1e12 + 1;
    EXPECT_NEAR(effective_height_exact(1e12).mean,
                std::sqrt(2 * std::log(n)) - (std::log(std::log(n)) + std::log(4 * pi)) / (2 * std::sqrt(2 * std::log(n))),
                0.1);  // the expansion converges like 1/log n
    EXPECT_THROW(effective_height_exact(-1.0), ArgumentError);
}

TEST(Microsurface, paper_fit_is_off_by_tens_of_percent_at_small_lambda) {
    // Documented in docs/colormap.md: the fit's μ_d is far from exact for
    // small Λ and close for Λ of a few.
    const double exact = effective_height_exact(0.05).mean, fit = effective_height_fit(0.05).mean;
    EXPECT_GT(std::fabs(fit - exact) / exact, 0.2);
    EXPECT_LT(std::fabs(effective_height_fit(3.0).mean - effective_height_exact(3.0).mean), 0.1);
}

TEST(Microsurface, slope_gaussian_moments_match_brute_force_integration) {
    // (The brute force integrates a function with a kink where facets turn
    // away from the view: its trapezoid error is ~1e-5 on an 801² grid.)
    const std::array<double, 3> iso{0.09, 0.0, 0.09};
    const std::array<double, 3> aniso{0.16, 0.05, 0.04};
    for (const auto& cov : {iso, aniso}) {
        for (double theta_deg : {0.0, 30.0, 60.0, 80.0, 89.0, 90.0}) {
            for (double phi : {0.0, 1.1}) {
                const std::array<double, 2> mean{0.05, -0.1};
                const auto g = slope_filtering_gaussian(theta_deg * pi / 180, phi, mean, cov);
                const auto n = slope_filtering_numerical(theta_deg * pi / 180, phi, mean, cov, 801);
                for (int i = 0; i < 2; ++i)
                    EXPECT_NEAR(g.mean[i], n.mean[i], 3e-5) << theta_deg;
                for (int i = 0; i < 3; ++i)
                    EXPECT_NEAR(g.covariance[i], n.covariance[i], 3e-5) << theta_deg;
            }
        }
    }
}

TEST(Microsurface, slope_filtering_is_the_slope_distribution_seen_head_on_or_on_a_flat_surface) {
    const auto head_on = slope_filtering_gaussian(0.0, 0.0, {0.0, 0.0}, {0.04, 0.0, 0.04});
    // Head on, facets tilted away from the view are still foreshortened:
    // weight ∝ (1 − s·d·0) = 1: unchanged.
    EXPECT_NEAR(head_on.mean[0], 0.0, 1e-12);
    EXPECT_NEAR(head_on.covariance[0], 0.04, 1e-12);
    const auto shift = slope_shift_of_c(INFINITY);
    EXPECT_EQ(shift.mean, 0.0);
    EXPECT_EQ(shift.stddev, 1.0);
    const auto tiny = slope_filtering_gaussian(1.0, 0.0, {0.0, 0.0}, {1e-12, 0.0, 1e-12});
    EXPECT_TRUE(std::isfinite(tiny.mean[0]) && std::isfinite(tiny.covariance[0]));
    EXPECT_THROW(slope_filtering_gaussian(1.0, 0.0, {0.0, 0.0}, {0.0, 0.0, 0.1}), ArgumentError);
}

}  // namespace
}  // namespace penumbra::colormap
