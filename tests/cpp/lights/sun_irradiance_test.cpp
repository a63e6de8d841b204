#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lights/sun_irradiance.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

// Brute force: midpoint rule over (θ, φ) inside the sun, flux density per
// solid angle ∝ 1 (cone) or 1/cos³θ (3.x disc), normalized to unit flux.
double brute_force(double c, double h, SunModel model) {
    const int nt = 400, np = 400;
    const Eigen::Vector3d n(std::sqrt(1.0 - c * c), 0.0, c);
    double sum = 0.0, flux = 0.0;
    for (int i = 0; i < nt; ++i) {
        const double t = h * (i + 0.5) / nt;
        const double density = model == SunModel::blender4_cone ? 1.0 : std::pow(std::cos(t), -3.0);
        const double w = density * std::sin(t);
        for (int j = 0; j < np; ++j) {
            const double p = 2.0 * pi * (j + 0.5) / np;
            const Eigen::Vector3d d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
            sum += w * std::max(0.0, n.dot(d));
            flux += w;
        }
    }
    return sum / flux;
}

TEST(LightsSunIrradiance, kernels_match_brute_force_in_and_across_the_horizon_band) {
    for (SunModel model : {SunModel::blender4_cone, SunModel::blender3_disc})
        for (double h : {0.05, 0.5, 1.2, 1.5})
            for (double c : {-0.9, -0.3, 0.0, 0.2, 0.6, 0.99})
                EXPECT_NEAR(sun_kernel(c, h, model), brute_force(c, h, model), 2e-3)
                    << "model " << int(model) << " h " << h << " c " << c;
}

TEST(LightsSunIrradiance, facing_irradiance_follows_blenders_conventions) {
    // docs/lights.md: 4.x gives (1 + cos h)/2 of the flux to a facing surface, 3.x 2cos h/(1 + cos h).
    for (double h : {1e-7, 0.3, 0.8, 1.4}) {
        EXPECT_NEAR(sun_kernel(1.0, h, SunModel::blender4_cone), 0.5 * (1.0 + std::cos(h)), 1e-9);
        EXPECT_NEAR(sun_kernel(1.0, h, SunModel::blender3_disc), 2.0 * std::cos(h) / (1.0 + std::cos(h)), 1e-9);
    }
}

// The add-on writes these values (tests/blender/lights/test_lights.py checks
// the suns it writes against the core); here, the rule itself.
TEST(LightsSunIrradiance, sun_angle_is_two_root_two_spread_clipped_to_pi_and_zero_when_tiny) {
    EXPECT_DOUBLE_EQ(sun_angle(0.1), 2.0 * std::sqrt(2.0) * 0.1);  // a disc of radius ρ has RMS radius ρ/√2
    EXPECT_DOUBLE_EQ(sun_half_angle(0.1), std::sqrt(2.0) * 0.1);
    EXPECT_DOUBLE_EQ(sun_angle(10.0), pi);          // clipped to π
    EXPECT_DOUBLE_EQ(sun_angle(1.6e-16), 0.0);      // below 1e-6 rad: written as 0
    EXPECT_DOUBLE_EQ(sun_angle(-1.0), 0.0);
}

TEST(LightsSunIrradiance, strength_per_flux_is_the_cones_facing_irradiance_and_1_for_the_disc) {
    // 4.x: the strength is the sun's facing irradiance, flux·K(1, h); 3.x: the disc's flux.
    for (double angle : {0.0, 0.2, 1.6, pi}) {
        EXPECT_NEAR(sun_strength_per_flux(angle, SunModel::blender4_cone),
                    sun_kernel(1.0, 0.5 * angle, SunModel::blender4_cone), 1e-9);
        EXPECT_DOUBLE_EQ(sun_strength_per_flux(angle, SunModel::blender3_disc), 1.0);
        EXPECT_DOUBLE_EQ(sun_strength_per_flux(angle, SunModel::point), 1.0);
    }
}

TEST(LightsSunIrradiance, slope_matches_a_wide_difference_quotient) {
    for (SunModel model : {SunModel::blender4_cone, SunModel::blender3_disc})
        for (double c : {-0.4, -0.1, 0.1, 0.5}) {
            const double h = 0.9, step = 1e-3;
            const double quotient = (sun_kernel(c + step, h, model) - sun_kernel(c - step, h, model)) / (2 * step);
            EXPECT_NEAR(sun_kernel_slope(c, h, model), quotient, 1e-3);
        }
}

}  // namespace
}  // namespace penumbra::lights
