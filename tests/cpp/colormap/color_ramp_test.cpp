// ColorRamp evaluation (colormap/color_ramp.hpp). Blender's own evaluation
// is the reference for ColorRamps; that comparison runs inside both Blenders
// (tests/blender/test_colormap.py). Here: hand-computed values and
// the properties Blender's code has by construction.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "colormap/color_map.hpp"
#include "colormap/color_ramp.hpp"
#include "common/error.hpp"

namespace penumbra::colormap {
namespace {

ColorRamp two_stop_ramp(RampInterpolation ipo) {
    ColorRamp ramp;
    ramp.interpolation = ipo;
    ramp.stops = {{0.25f, {1.0f, 0.0f, 0.0f, 1.0f}}, {0.75f, {0.0f, 0.0f, 1.0f, 0.5f}}};
    return ramp;
}

TEST(ColorRamp, linear_and_ease_and_constant_match_hand_values) {
    auto lin = evaluate_ramp(two_stop_ramp(RampInterpolation::linear), 0.375f);  // a quarter of the way
    EXPECT_FLOAT_EQ(lin[0], 0.75f);
    EXPECT_FLOAT_EQ(lin[2], 0.25f);
    EXPECT_FLOAT_EQ(lin[3], 0.875f);
    // Ease: fac' = 3 t² − 2 t³ of the linear fraction t = 0.25 → 0.15625.
    auto ease = evaluate_ramp(two_stop_ramp(RampInterpolation::ease), 0.375f);
    EXPECT_NEAR(ease[2], 0.15625f, 1e-6);
    auto constant = evaluate_ramp(two_stop_ramp(RampInterpolation::constant), 0.7499f);
    EXPECT_FLOAT_EQ(constant[0], 1.0f);
    constant = evaluate_ramp(two_stop_ramp(RampInterpolation::constant), 0.75f);
    EXPECT_FLOAT_EQ(constant[2], 1.0f);
    // Held outside the stops.
    EXPECT_FLOAT_EQ(evaluate_ramp(two_stop_ramp(RampInterpolation::linear), 0.1f)[0], 1.0f);
    EXPECT_FLOAT_EQ(evaluate_ramp(two_stop_ramp(RampInterpolation::linear), 0.9f)[2], 1.0f);
}

TEST(ColorRamp, cubic_modes_pass_near_stops_and_stay_in_0_1) {
    for (auto ipo : {RampInterpolation::cardinal, RampInterpolation::b_spline}) {
        ColorRamp ramp;
        ramp.interpolation = ipo;
        ramp.stops = {{0.0f, {0, 0, 0, 1}}, {0.3f, {1, 0.2f, 0, 1}}, {0.6f, {0, 1, 0.5f, 1}}, {1.0f, {1, 1, 1, 1}}};
        float previous = evaluate_ramp(ramp, 0.0f)[1];
        for (int i = 1; i <= 1000; ++i) {
            const auto c = evaluate_ramp(ramp, i / 1000.0f);
            for (float v : c) {
                EXPECT_GE(v, 0.0f);
                EXPECT_LE(v, 1.0f);
            }
            EXPECT_LT(std::fabs(c[1] - previous), 0.02f) << "continuous at " << i;  // no jumps
            previous = c[1];
        }
    }
    // Cardinal interpolates: at a stop, the stop's colour.
    ColorRamp ramp;
    ramp.interpolation = RampInterpolation::cardinal;
    ramp.stops = {{0.0f, {0, 0, 0, 1}}, {0.5f, {1, 0.5f, 0.25f, 1}}, {1.0f, {0, 0, 0, 1}}};
    EXPECT_NEAR(evaluate_ramp(ramp, 0.5f)[1], 0.5f, 1e-6);
}

TEST(ColorRamp, hsv_mode_reproduces_the_stops_and_goes_round_the_hue_circle) {
    ColorRamp ramp;
    ramp.color_mode = RampColorMode::hsv;
    ramp.stops = {{0.0f, {1, 0, 0, 1}}, {1.0f, {0, 0, 1, 1}}};  // red to blue
    const auto start = evaluate_ramp(ramp, 0.0f), end = evaluate_ramp(ramp, 1.0f);
    EXPECT_NEAR(start[0], 1.0f, 1e-6);
    EXPECT_NEAR(end[2], 1.0f, 1e-6);
    // NEAR goes red → magenta → blue (hue 0 → 2/3 the short way, through 5/6).
    const auto mid = evaluate_ramp(ramp, 0.5f);
    EXPECT_NEAR(mid[0], 1.0f, 1e-5);
    EXPECT_NEAR(mid[1], 0.0f, 1e-5);
    EXPECT_NEAR(mid[2], 1.0f, 1e-5);
    ramp.hue_interpolation = RampHueInterpolation::far;  // the long way: through green
    const auto far = evaluate_ramp(ramp, 0.5f);
    EXPECT_NEAR(far[1], 1.0f, 1e-5);
}

TEST(ColorRamp, bad_ramps_are_rejected_with_a_reason) {
    ColorRamp empty;
    EXPECT_THROW(evaluate_ramp(empty, 0.5f), ArgumentError);
    ColorRamp nan_colour = two_stop_ramp(RampInterpolation::linear);
    nan_colour.stops[1].color[1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(ramp_to_color_map(nan_colour, RampSampling::exact), ArgumentError);
    ColorRamp single;
    single.stops = {{0.4f, {0.1f, 0.2f, 0.3f, 1.0f}}};
    EXPECT_FLOAT_EQ(evaluate_ramp(single, 0.9f)[2], 0.3f);
}

TEST(ColorRamp, exact_sampling_is_exact_for_linear_and_constant_rgb) {
    for (auto ipo : {RampInterpolation::linear, RampInterpolation::constant}) {
        ColorRamp ramp = two_stop_ramp(ipo);
        ramp.stops.push_back({0.5f, {0.2f, 0.9f, 0.1f, 1.0f}});
        ramp.stops.push_back({0.5f, {0.7f, 0.1f, 0.4f, 1.0f}});  // identical position
        const ColorMap map = ramp_to_color_map(ramp, RampSampling::exact);
        EXPECT_LT(ramp_sampling_error(ramp, map), 1e-6) << static_cast<int>(ipo);
    }
}

TEST(ColorRamp, dense_sampling_error_is_small_for_smooth_modes) {
    ColorRamp ramp = two_stop_ramp(RampInterpolation::b_spline);
    ramp.stops.push_back({0.5f, {0.2f, 0.9f, 0.1f, 1.0f}});
    const ColorMap map = ramp_to_color_map(ramp, RampSampling::exact, 4, 4096);
    EXPECT_LT(ramp_sampling_error(ramp, map), 1e-5);
}

TEST(ColorRamp, cycles_table_is_256_entries_at_i_over_255) {
    const ColorRamp ramp = two_stop_ramp(RampInterpolation::ease);
    const ColorMap map = ramp_to_color_map(ramp, RampSampling::cycles_table, 3);
    ASSERT_EQ(map.knot_count(), 256);
    EXPECT_DOUBLE_EQ(map.positions[255], 1.0);
    EXPECT_FLOAT_EQ(static_cast<float>(map.color(100)[0]), evaluate_ramp(ramp, 100.0f / 255.0f)[0]);
    EXPECT_EQ(ramp_to_color_map(two_stop_ramp(RampInterpolation::constant), RampSampling::cycles_table).interpolation,
              MapInterpolation::constant);
}

// Blender's colour-band table (EEVEE; Cycles 4.5+): 257 entries at i/256, so
// a constant ramp's step at 0.47 falls at 121/256, not at 120/255.
TEST(ColorRamp, colorband_table_is_257_entries_at_i_over_256) {
    ColorRamp ramp = two_stop_ramp(RampInterpolation::constant);
    ramp.stops[1].position = 0.47f;
    const ColorMap map = ramp_to_color_map(ramp, RampSampling::cycles_table, 3, 1024, colorband_ramp_table_size);
    ASSERT_EQ(map.knot_count(), 257);
    EXPECT_DOUBLE_EQ(map.positions[128], 0.5);
    double at_step[3], before_step[3];
    map.evaluate(121.0 / 256.0, at_step);
    map.evaluate(120.5 / 256.0, before_step);
    EXPECT_FLOAT_EQ(static_cast<float>(at_step[0]), ramp.stops[1].color[0]);
    EXPECT_FLOAT_EQ(static_cast<float>(before_step[0]), ramp.stops[0].color[0]);
    EXPECT_THROW(ramp_to_color_map(ramp, RampSampling::cycles_table, 3, 1024, 1), ArgumentError);
}

}  // namespace
}  // namespace penumbra::colormap
