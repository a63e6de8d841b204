#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "lights/environment.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;
using testing::as_map;
using testing::constant_image;

TEST(LightsEnvironment, bad_pixels_are_counted_and_zeroed) {
    Image im = constant_image(8, 4, 1, 1, 1);
    im.at(0, 0, 0) = std::numeric_limits<float>::quiet_NaN();
    im.at(1, 0, 1) = std::numeric_limits<float>::infinity();
    im.at(2, 0, 2) = -std::numeric_limits<float>::infinity();
    im.at(3, 0, 0) = -0.5f;
    const EnvironmentMap map = as_map(im);
    EXPECT_EQ(map.defects.nan, 1u);
    EXPECT_EQ(map.defects.inf, 2u);
    EXPECT_EQ(map.defects.negative, 1u);
    for (float v : map.rgb) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f);
}

TEST(LightsEnvironment, one_two_and_four_channel_images_are_read_as_rgb) {
    for (int channels : {1, 2, 4}) {
        Image im(4, 2, channels);
        for (std::size_t p = 0; p < im.pixel_count(); ++p)
            for (int c = 0; c < channels; ++c) im.pixels[p * channels + c] = c == 0 ? 2.0f : (c == 3 || channels == 2 ? 0.25f : 1.0f);
        const EnvironmentMap map = as_map(im);
        const float* p = map.pixel(1, 1);
        if (channels <= 2) {
            EXPECT_EQ(p[0], 2.0f); EXPECT_EQ(p[1], 2.0f); EXPECT_EQ(p[2], 2.0f);
        } else {
            EXPECT_EQ(p[0], 2.0f); EXPECT_EQ(p[1], 1.0f); EXPECT_EQ(p[2], 1.0f);
        }
    }
    EXPECT_THROW(make_environment(Image()), ArgumentError);
    EXPECT_THROW(make_environment(Image(0, 5, 3)), ArgumentError);
}

TEST(LightsEnvironment, reducing_a_map_keeps_its_integral_exactly) {
    std::mt19937 rng(1);
    std::lognormal_distribution<float> lum(0.0f, 3.0f);
    Image im(1000, 500, 3);
    for (float& v : im.pixels) v = lum(rng);
    const EnvironmentMap full = as_map(im);
    MapOptions o;
    o.max_width = 256;
    const EnvironmentMap small = make_environment(im, o);
    EXPECT_EQ(small.width, 256);
    EXPECT_EQ(small.height, 128);
    const Eigen::Vector3d a = integral_rgb(full), b = integral_rgb(small);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-5 * a[c]);
}

TEST(LightsEnvironment, eight_orders_of_magnitude_survive_in_double) {
    // One 1e4 pixel over a 1e-4 background: the background's share must stay.
    Image im = constant_image(512, 256, 1e-4f, 1e-4f, 1e-4f);
    im.at(100, 100, 0) = im.at(100, 100, 1) = im.at(100, 100, 2) = 1e4f;
    const EnvironmentMap map = as_map(im);
    long double expected = 0.0L;
    for (int r = 0; r < 256; ++r)
        for (int c = 0; c < 512; ++c)
            expected += (long double)map.solid_angle(r) * (long double)im.at(c, r, 0);
    EXPECT_NEAR(integral_luminance(map), double(expected), 1e-12 * double(expected));
    // The background alone is ~4π·1e-4; it is not lost beside the spike.
    const double spike = map.solid_angle(100) * 1e4;
    EXPECT_NEAR(integral_luminance(map) - spike, 4 * pi * 1e-4, 4 * pi * 1e-4 * 1e-3);
}

TEST(LightsEnvironment, uniform_fisheye_and_mirror_ball_resample_exactly) {
    MapOptions o;
    o.projection = Projection::fisheye;
    const EnvironmentMap fish = make_environment(constant_image(200, 200, 2, 2, 2), o);
    EXPECT_FALSE(fish.full_sphere);
    EXPECT_NEAR(integral_luminance(fish), 2 * pi * 2, 1e-5);
    EXPECT_NEAR(fish.source_integral_luminance, 2 * pi * 2, 2 * pi * 2 * 0.01);
    o.projection = Projection::mirror_ball;
    const EnvironmentMap ball = make_environment(constant_image(200, 200, 1, 1, 1), o);
    EXPECT_TRUE(ball.full_sphere);
    EXPECT_NEAR(integral_luminance(ball), 4 * pi, 1e-5);
}

TEST(LightsEnvironment, a_single_bright_fisheye_pixel_keeps_its_energy) {
    MapOptions o;
    o.projection = Projection::fisheye;
    for (auto [x, y] : {std::pair{100, 100}, std::pair{130, 70}, std::pair{60, 150}}) {
        Image im = constant_image(200, 200, 0, 0, 0);
        im.at(x, y, 0) = im.at(x, y, 1) = im.at(x, y, 2) = 1000.0f;
        const EnvironmentMap map = make_environment(im, o);
        EXPECT_GT(map.source_integral_luminance, 0.0);
        EXPECT_NEAR(integral_luminance(map), map.source_integral_luminance, 0.1 * map.source_integral_luminance)
            << x << "," << y;
    }
}

TEST(LightsEnvironment, rotation_about_z_moves_content_by_the_angle) {
    Image im = testing::sky_and_sun(360, 180, 0.0, Eigen::Vector3d(1, 0, 0.2), 0.1, 10.0);
    const Image rotated = rotate_equirectangular_z(im, pi / 2);  // exact: 90 columns
    const Image expected = testing::sky_and_sun(360, 180, 0.0, Eigen::Vector3d(0, 1, 0.2), 0.1, 10.0);
    double diff = 0.0;
    for (std::size_t i = 0; i < im.pixels.size(); ++i) diff += std::abs(rotated.pixels[i] - expected.pixels[i]);
    EXPECT_LT(diff, 1e-3);
}

}  // namespace
}  // namespace penumbra::lights
