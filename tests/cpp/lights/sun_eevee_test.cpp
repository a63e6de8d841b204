// EEVEE's suns (sun_irradiance.hpp: eevee_next_shadowed, eevee_legacy)
// against brute-force integrals of what docs/lights.md "Suns in EEVEE" says
// each EEVEE computes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lights/sun_irradiance.hpp"
#include "lights/sun_kernel_table.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

// Midpoint rule over the cone (θ ≤ h, φ), uniform in solid angle, normal
// at cos β = c: (the fraction of directions above the horizon, the mean of
// max(0, n·ω)).
std::pair<double, double> cone_brute_force(double c, double h) {
    const int nt = 600, np = 600;
    const Eigen::Vector3d n(std::sqrt(1.0 - c * c), 0.0, c);
    double above = 0.0, cosine = 0.0, weight = 0.0;
    for (int i = 0; i < nt; ++i) {
        const double t = h * (i + 0.5) / nt, w = std::sin(t);
        for (int j = 0; j < np; ++j) {
            const double p = 2.0 * pi * (j + 0.5) / np;
            const Eigen::Vector3d d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
            above += w * (n.dot(d) > 0.0);
            cosine += w * std::max(0.0, n.dot(d));
            weight += w;
        }
    }
    return {above / weight, cosine / weight};
}

TEST(LightsSunEevee, fraction_above_the_horizon_matches_brute_force) {
    for (double h : {0.1, 0.5, 0.785, 1.05, 1.5, 2.5})
        for (double c : {-0.9, -0.3, 0.0, 0.2, 0.5, 0.9}) {
            const double expected = cone_brute_force(c, h).first;
            EXPECT_NEAR(cone_fraction_above_horizon(c, h), expected, 2e-3) << "h " << h << " c " << c;
        }
    // Wholly above or below the horizon.
    EXPECT_EQ(cone_fraction_above_horizon(0.5, 0.2), 1.0);
    EXPECT_EQ(cone_fraction_above_horizon(-0.5, 0.2), 0.0);
}

TEST(LightsSunEevee, shadowed_eevee_next_sun_is_the_cone_times_what_its_shadow_keeps) {
    // The plane: a sun 30° up (c = 0.5), angles 90° and 120°.
    for (double h : {pi / 4, pi / 3}) {
        const auto [fraction, cosine] = cone_brute_force(0.5, h);
        EXPECT_NEAR(sun_kernel(0.5, h, SunModel::eevee_next_shadowed), fraction * cosine, 2e-3);
        EXPECT_LT(sun_kernel(0.5, h, SunModel::eevee_next_shadowed), 0.9 * sun_kernel(0.5, h, SunModel::blender4_cone));
    }
    // Outside the band nothing is cut, and the strength is the cone's.
    EXPECT_NEAR(sun_kernel(0.9, 0.3, SunModel::eevee_next_shadowed), sun_kernel(0.9, 0.3, SunModel::blender4_cone),
                1e-12);
    EXPECT_EQ(sun_strength_per_flux(1.0, SunModel::eevee_next_shadowed),
              sun_strength_per_flux(1.0, SunModel::blender4_cone));
}

TEST(LightsSunEevee, legacy_strength_carries_the_flux_at_eevee_legacys_radiance) {
    // Radiance per strength (1 + r²/2)/(π r²), r = tan h, over the cone's
    // solid angle 2π(1 − cos h): the strength per flux is its inverse.
    for (double angle : {0.1, 0.5, 1.5, 2.0, 3.0}) {
        const double h = 0.5 * angle, r = std::tan(h);
        const double flux_per_strength = (1.0 + 0.5 * r * r) / (pi * r * r) * 2.0 * pi * (1.0 - std::cos(h));
        EXPECT_NEAR(sun_strength_per_flux(angle, SunModel::eevee_legacy), 1.0 / flux_per_strength, 1e-9);
        EXPECT_NEAR(sun_kernel(0.3, h, SunModel::eevee_legacy), sun_kernel(0.3, h, SunModel::blender4_cone), 1e-12);
    }
    EXPECT_EQ(sun_strength_per_flux(0.0, SunModel::eevee_legacy), 1.0);
}

TEST(LightsSunEevee, renderer_picks_the_model) {
    EXPECT_EQ(sun_model_for_renderer(4, 5, false, true), SunModel::blender4_cone);
    EXPECT_EQ(sun_model_for_renderer(3, 4, false, true), SunModel::blender3_disc);
    EXPECT_EQ(sun_model_for_renderer(3, 4, true, true), SunModel::eevee_legacy);
    EXPECT_EQ(sun_model_for_renderer(4, 1, true, true), SunModel::eevee_legacy);
    EXPECT_EQ(sun_model_for_renderer(4, 2, true, true), SunModel::eevee_next_shadowed);
    EXPECT_EQ(sun_model_for_renderer(5, 2, true, false), SunModel::blender4_cone);
}

TEST(LightsSunEevee, table_follows_the_shadowed_kernel) {
    for (double h : {0.2, 0.785, 1.3})
        for (double c : {-0.1, 0.1, 0.5, 0.95}) {
            const TabulatedSun sun(h, SunModel::eevee_next_shadowed);
            EXPECT_NEAR(sun(c).value, sun_kernel(c, h, SunModel::eevee_next_shadowed), 1e-4) << h << " " << c;
        }
}

}  // namespace
}  // namespace penumbra::lights
