// The exact Gaussian-filtered lookup against brute-force quadrature of the
// same integral (a fine midpoint rule over the Gaussian, evaluating the map
// pointwise), the two limits, and the bilinear table accuracy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "colormap/color_map.hpp"
#include "colormap/lookup.hpp"
#include "common/error.hpp"

namespace penumbra::colormap {
namespace {

// ∫ C(v) N(v; mean, σ²) dv by composite 5-point Gauss–Legendre quadrature
// on each smooth piece between knots over mean ± 12σ (nodes are interior, so
// jumps are never sampled on their edge), evaluating the map pointwise.
std::vector<double> brute_force(const ColorMap& map, double mean, double sigma, int panels_per_piece = 200) {
    static const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                 0.2369268850561891};
    std::vector<double> breaks{mean - 12 * sigma, mean + 12 * sigma};
    for (double x : map.positions)
        if (x > breaks[0] && x < breaks[1])
            breaks.push_back(x);
    std::sort(breaks.begin(), breaks.end());
    std::vector<double> sum(map.channels, 0.0), value(map.channels);
    for (std::size_t b = 0; b + 1 < breaks.size(); ++b) {
        const double width = (breaks[b + 1] - breaks[b]) / panels_per_piece;
        if (width <= 0)
            continue;
        for (int p = 0; p < panels_per_piece; ++p) {
            const double centre = breaks[b] + (p + 0.5) * width;
            for (int g = 0; g < 5; ++g) {
                const double v = centre + 0.5 * width * gx[g];
                const double z = (v - mean) / sigma;
                const double w = 0.5 * width * gw[g] * std::exp(-0.5 * z * z) / (sigma * std::sqrt(2 * M_PI));
                map.evaluate(v, value.data());
                for (int c = 0; c < map.channels; ++c)
                    sum[c] += w * value[c];
            }
        }
    }
    return sum;
}

ColorMap wiggly_map() {
    // Uneven knots, a jump and a hole in the middle, two channels.
    return color_map_from_knots({0.0, 0.1, 0.35, 0.35, 0.6, 0.62, 1.0},
                                {0.2, 1.0, 0.9, 0.1, 0.0, 0.5, 1.0, 0.0, 0.3, 0.3, 0.8, 0.9, 0.1, 0.7}, 2,
                                MapInterpolation::linear);
}

TEST(Lookup, exact_convolution_matches_brute_force_quadrature) {
    for (auto ipo : {MapInterpolation::linear, MapInterpolation::constant}) {
        ColorMap map = wiggly_map();
        map.interpolation = ipo;
        for (double mean : {-0.4, 0.0, 0.12, 0.35, 0.5, 0.97, 1.3}) {
            for (double sigma : {0.003, 0.02, 0.1, 0.5, 2.0}) {
                double exact[2];
                filtered_color(map, mean, sigma, exact);
                const auto reference = brute_force(map, mean, sigma);
                for (int c = 0; c < 2; ++c)
                    EXPECT_NEAR(exact[c], reference[c], 1e-12) << "mean " << mean << " sigma " << sigma;
            }
        }
    }
}

TEST(Lookup, sigma_zero_is_the_map_and_huge_sigma_the_clamped_mean) {
    const ColorMap map = wiggly_map();
    double out[2], expect[2];
    for (double mean : {-1.0, 0.2, 0.35, 0.8, 3.0}) {
        filtered_color(map, mean, 0.0, out);
        map.evaluate(mean, expect);
        EXPECT_DOUBLE_EQ(out[0], expect[0]);
        filtered_color(map, mean, 1e-300, out);  // tiny but not zero: no NaN, the map again
        if (mean != 0.35) {  // (on the jump itself any σ > 0 averages the two sides)
            EXPECT_NEAR(out[0], expect[0], 1e-12) << mean;
        }
    }
    for (double sigma : {1e6, 1e30, 1e300}) {
        filtered_color(map, 0.5, sigma, out);
        EXPECT_NEAR(out[0], 0.5 * (0.2 + 0.1), 1e-6) << sigma;  // (C(0) + C(1)) / 2
        EXPECT_NEAR(out[1], 0.5 * (1.0 + 0.7), 1e-6) << sigma;
    }
}

TEST(Lookup, linear_map_far_from_its_ends_is_unchanged_by_blurring) {
    // A line blurred stays the line where the Gaussian does not reach the clamps.
    const ColorMap map = color_map_from_knots({0.0, 1.0}, {0.0, 1.0}, 1, MapInterpolation::linear);
    double out;
    filtered_color(map, 0.5, 0.05, &out);
    EXPECT_NEAR(out, 0.5, 1e-15);
    filtered_color(map, 0.3, 0.02, &out);
    EXPECT_NEAR(out, 0.3, 1e-15);
}

TEST(Lookup, table_has_the_contract_layout) {
    const float colors[] = {0.0f, 1.0f, 0.25f};
    const ColorMap map = color_map_from_samples(colors, 3, 1);
    LookupSpec spec{17, 9, 0.4, -0.5, 1.5, SigmaSpacing::linear};
    const Image table = build_lookup(map, spec);
    ASSERT_EQ(table.width, 17);
    ASSERT_EQ(table.height, 9);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 17; ++x) {
            double exact;
            filtered_color(map, -0.5 + 2.0 * x / 16, 0.4 * y / 8, &exact);
            EXPECT_FLOAT_EQ(table.at(x, y, 0), static_cast<float>(exact));
        }
    spec.sigma_spacing = SigmaSpacing::quadratic;
    EXPECT_DOUBLE_EQ(spec.sigma_of_row(4), 0.1);
    EXPECT_DOUBLE_EQ(spec.row_of_sigma(0.1), 4.0);
}

TEST(Lookup, bad_specs_are_rejected) {
    const float colors[] = {0.0f, 1.0f};
    const ColorMap map = color_map_from_samples(colors, 2, 1);
    EXPECT_THROW(build_lookup(map, {256, 256, 0.0, 0.0, 1.0}), ArgumentError);
    EXPECT_THROW(build_lookup(map, {256, 256, std::nan(""), 0.0, 1.0}), ArgumentError);
    EXPECT_THROW(build_lookup(map, {1, 256, 0.2, 0.0, 1.0}), ArgumentError);
    EXPECT_THROW(build_lookup(map, {256, 256, 0.2, 1.0, 1.0}), ArgumentError);
    double out;
    EXPECT_THROW(filtered_color(map, 0.5, -1.0, &out), ArgumentError);
}

TEST(Lookup, huge_sigma_max_gives_a_finite_table) {
    const float colors[] = {0.0f, 1.0f, 0.0f};
    const ColorMap map = color_map_from_samples(colors, 3, 1);
    const Image table = build_lookup(map, {32, 8, 1e200, -1.0, 2.0});
    for (float v : table.pixels)
        EXPECT_TRUE(std::isfinite(v));
    EXPECT_NEAR(table.at(10, 7, 0), 0.0f, 1e-6);
}

TEST(Lookup, steep_piece_under_huge_mean_and_sigma_stays_within_the_maps_range) {
    // Found by fuzzing: a piece 1e-300 wide rising by 1 has slope 1e300; at
    // a mean and σ of 1e250 its mass underflows to 0 and Inf·0 gave NaN.
    const ColorMap map = color_map_from_knots({0.0, 1e-300, 1.0}, {0.0, 1.0, 0.5}, 1, MapInterpolation::linear);
    for (double mean : {-1e250, 0.0, 1e250})
        for (double sigma : {1e-200, 1.0, 1e248, 1e250}) {
            double out = -1.0;
            filtered_color(map, mean, sigma, &out);
            EXPECT_TRUE(out >= 0.0 && out <= 1.0) << "mean " << mean << " sigma " << sigma << ": " << out;
        }
}

TEST(Lookup, a_nan_probe_or_an_overflowing_mean_range_is_an_argument_error) {
    const float colors[] = {0.0f, 1.0f};
    const ColorMap map = color_map_from_samples(colors, 2, 1);
    const LookupSpec spec{8, 8, 0.25, 0.0, 1.0};
    const Image table = build_lookup(map, spec);
    double out;
    EXPECT_THROW(bilinear_lookup(table, spec, std::nan(""), 0.1, &out), ArgumentError);
    EXPECT_THROW(bilinear_lookup(table, spec, 0.5, std::nan(""), &out), ArgumentError);
    // Both ends finite, the width not: the table would be all NaN.
    EXPECT_THROW(build_lookup(map, {8, 8, 0.25, -1e308, 1e308}), ArgumentError);
}

TEST(Lookup, colours_beyond_float32_are_an_argument_error_not_inf_texels) {
    const ColorMap map = color_map_from_knots({0.0, 1.0}, {0.0, 1e103}, 1, MapInterpolation::linear);
    EXPECT_THROW(build_lookup(map, {8, 8, 0.25, 0.0, 1.0}), ArgumentError);
}

TEST(Lookup, progress_can_cancel_and_reports_completion) {
    const float colors[] = {0.0f, 1.0f};
    const ColorMap map = color_map_from_samples(colors, 2, 1);
    double last = 0.0;
    build_lookup(map, {64, 64, 0.2, 0.0, 1.0}, Progress([&](double f) { last = f; return true; }));
    EXPECT_DOUBLE_EQ(last, 1.0);
    EXPECT_THROW(build_lookup(map, {64, 64, 0.2, 0.0, 1.0}, Progress([](double) { return false; })), Cancelled);
}

TEST(Lookup, bilinear_error_shrinks_with_table_size) {
    // A step map, the hardest case for a bilinear table.
    const ColorMap map = color_map_from_knots({0.0, 0.5, 1.0}, {0.0, 1.0, 1.0}, 1, MapInterpolation::constant);
    auto error = [&](int size, SigmaSpacing spacing) {
        const LookupSpec spec{size, size, 0.2, 0.0, 1.0, spacing};
        return measure_lookup_accuracy(map, spec, build_lookup(map, spec), 120).rms_error;
    };
    const double small = error(32, SigmaSpacing::linear), large = error(128, SigmaSpacing::linear);
    EXPECT_LT(large, 0.5 * small);
    EXPECT_LT(error(128, SigmaSpacing::quadratic), 0.5 * small);
}

}  // namespace
}  // namespace penumbra::colormap
