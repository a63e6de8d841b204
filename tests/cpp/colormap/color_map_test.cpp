// ColorMap evaluation (colormap/color_map.hpp): hand-computed values of the
// piecewise-linear map, its clamping and jumps, and what it rejects.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "colormap/color_map.hpp"
#include "common/error.hpp"

namespace penumbra::colormap {
namespace {

TEST(ColorMap, samples_are_joined_linearly_and_clamped_outside) {
    const float colors[] = {0.0f, 1.0f, 0.5f, 0.0f, 1.0f, 1.0f};  // 3 samples, 2 channels
    const ColorMap map = color_map_from_samples(colors, 3, 2);
    double out[2];
    map.evaluate(0.25, out);
    EXPECT_DOUBLE_EQ(out[0], 0.25);
    EXPECT_DOUBLE_EQ(out[1], 0.5);
    map.evaluate(-3.0, out);
    EXPECT_DOUBLE_EQ(out[0], 0.0);
    EXPECT_DOUBLE_EQ(out[1], 1.0);
    map.evaluate(7.0, out);
    EXPECT_DOUBLE_EQ(out[0], 1.0);
    EXPECT_DOUBLE_EQ(out[1], 1.0);
}

TEST(ColorMap, single_sample_is_a_constant_map) {
    const float colors[] = {0.3f, 0.6f, 0.9f};
    const ColorMap map = color_map_from_samples(colors, 1, 3);
    double out[3];
    for (double x : {-1.0, 0.0, 0.4, 1.0, 2.0}) {
        map.evaluate(x, out);
        EXPECT_FLOAT_EQ(out[2], 0.9f);
    }
}

TEST(ColorMap, rejects_nan_colours_and_bad_shapes) {
    const float bad[] = {0.0f, std::numeric_limits<float>::quiet_NaN()};
    EXPECT_THROW(color_map_from_samples(bad, 2, 1), ArgumentError);
    EXPECT_THROW(color_map_from_samples(bad, 0, 1), ArgumentError);
    EXPECT_THROW(color_map_from_samples(bad, 1, 5), ArgumentError);
    EXPECT_THROW(color_map_from_knots({0.5, 0.2}, {0, 1}, 1, MapInterpolation::linear), ArgumentError);
}

TEST(ColorMap, equal_knot_positions_make_a_jump) {
    const ColorMap map = color_map_from_knots({0.0, 0.5, 0.5, 1.0}, {0.0, 0.5, 2.0, 3.0}, 1, MapInterpolation::linear);
    double out;
    map.evaluate(0.4999999, &out);
    EXPECT_NEAR(out, 0.5, 1e-6);
    map.evaluate(0.5, &out);
    EXPECT_DOUBLE_EQ(out, 2.0);
    map.evaluate(0.75, &out);
    EXPECT_DOUBLE_EQ(out, 2.5);
}

}  // namespace
}  // namespace penumbra::colormap
