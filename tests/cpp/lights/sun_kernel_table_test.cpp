#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "lights/sun_irradiance.hpp"
#include "lights/sun_kernel_table.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

double facing(double h, SunModel model) { return sun_kernel(1.0, h, model); }

TEST(LightsSunKernelTable, matches_the_direct_kernel_inside_and_outside_the_horizon_band) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (SunModel model : {SunModel::blender4_cone, SunModel::blender3_disc}) {
        const double widest = model == SunModel::blender3_disc ? max_disc_half_angle : 0.5 * pi;
        double worst = 0.0;
        for (int trial = 0; trial < 20000; ++trial) {
            // Half-angles from a point to the widest, more of them narrow,
            // and a tenth right at the widest end.
            const double h = trial % 10 == 0 ? widest * (1.0 - 0.02 * u(rng)) : widest * std::pow(u(rng), 3.0);
            // Normals concentrated in the band, where the table works, and at its edges.
            const double r = u(rng);
            const double t = r < 0.6 ? 2.0 * u(rng) - 1.0 : r < 0.8 ? 1.0 - 1e-3 * u(rng) : -1.0 + 1e-3 * u(rng);
            const double c = u(rng) < 0.9 ? std::sin(h) * t : 2.0 * u(rng) - 1.0;
            const double err = std::abs(TabulatedSun(h, model)(c).value - sun_kernel(c, h, model)) / facing(h, model);
            worst = std::max(worst, err);
        }
        EXPECT_LT(worst, 3e-5) << "model " << int(model);
    }
}

TEST(LightsSunKernelTable, slopes_are_the_derivatives_of_its_values) {
    for (SunModel model : {SunModel::blender4_cone, SunModel::blender3_disc})
        for (double h : {2e-4, 0.003, 0.07, 0.6, 1.3, 1.44})
            for (double t : {-0.97, -0.6, -0.2, 0.0, 0.45, 0.93, 1.5}) {
                const double c = t * std::sin(h);
                if (std::abs(c) > 0.999) continue;  // the difference quotient would cross c = ±1
                const TabulatedSun sun(h, model);
                const SunKernelValue v = sun(c);
                const double dc = 1e-7 * std::sin(h), dh = 1e-7 * h;
                const double slope = (sun(c + dc).value - sun(c - dc).value) / (2 * dc);
                const double angle_slope =
                    (TabulatedSun(h + dh, model)(c).value - TabulatedSun(h - dh, model)(c).value) / (2 * dh);
                const double scale = facing(h, model);
                EXPECT_NEAR(v.slope, slope, 1e-5 * scale) << int(model) << " h " << h << " t " << t;
                EXPECT_NEAR(v.angle_slope, angle_slope, 1e-4 * scale) << int(model) << " h " << h << " t " << t;
            }
}

TEST(LightsSunKernelTable, a_point_sun_is_the_clamped_cosine_times_its_facing_factor) {
    for (SunModel model : {SunModel::point, SunModel::blender4_cone, SunModel::blender3_disc})
        for (double c : {-1.0, -0.3, 0.0, 0.4, 1.0}) {
            const SunKernelValue v = TabulatedSun(0.0, model)(c);
            EXPECT_DOUBLE_EQ(v.value, std::max(0.0, c));
            EXPECT_DOUBLE_EQ(v.slope, c > 0.0 ? 1.0 : 0.0);
        }
}

}  // namespace
}  // namespace penumbra::lights
