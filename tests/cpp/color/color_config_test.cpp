#include "color/color_config.hpp"

#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>

#include "common/error.hpp"

namespace penumbra {
namespace {

// Blender's own config, from Debian's blender-data (found by CMake).
const std::string blender_config = PENUMBRA_BLENDER_OCIO;

double srgb_to_linear(double v) {  // IEC 61966-2-1, independent of OCIO
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST(ColorConfig, blender_config_loads_with_a_scene_linear_role) {
    const ColorConfig config = ColorConfig::load(blender_config);
    EXPECT_EQ(config.scene_linear(), "Linear");
    EXPECT_TRUE(config.has_colorspace("sRGB"));
    EXPECT_TRUE(config.has_colorspace("Non-Color"));
    EXPECT_FALSE(config.has_colorspace("Not A Space"));
}

TEST(ColorConfig, srgb_to_scene_linear_matches_the_srgb_formula) {
    const ColorConfig config = ColorConfig::load(blender_config);
    Image image(5, 1, 3);
    const float values[] = {0.0f, 0.02f, 0.2f, 0.5f, 1.0f};
    for (int x = 0; x < 5; ++x)
        for (int c = 0; c < 3; ++c)
            image.at(x, 0, c) = values[x];
    config.to_scene_linear(image, "sRGB");
    for (int x = 0; x < 5; ++x)
        EXPECT_NEAR(image.at(x, 0, 1), srgb_to_linear(values[x]), 2e-3) << values[x];
}

TEST(ColorConfig, round_trip_through_a_display_space_is_identity) {
    const ColorConfig config = ColorConfig::load(blender_config);
    Image image(4, 3, 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = 0.05f * (i % 17);
    const Image original = image;
    config.from_scene_linear(image, "sRGB");
    EXPECT_GT(std::abs(image.pixels[5] - original.pixels[5]), 1e-3);
    config.to_scene_linear(image, "sRGB");
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        EXPECT_NEAR(image.pixels[i], original.pixels[i], 1e-3);
}

TEST(ColorConfig, unknown_colorspace_error_lists_the_valid_names_and_keeps_the_image) {
    const ColorConfig config = ColorConfig::load(blender_config);
    Image image(2, 2, 3);
    std::fill(image.pixels.begin(), image.pixels.end(), 0.5f);
    try {
        config.to_scene_linear(image, "sRGB-ish");
        FAIL();
    } catch (const ArgumentError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("'sRGB-ish'"), std::string::npos) << message;
        EXPECT_NE(message.find("'Filmic Log'"), std::string::npos) << message;
        EXPECT_NE(message.find("'Non-Color'"), std::string::npos) << message;
    }
    for (float v : image.pixels)
        EXPECT_EQ(v, 0.5f);
}

TEST(ColorConfig, cancelled_conversion_leaves_the_image_unchanged) {
    const ColorConfig config = ColorConfig::load(blender_config);
    Image image(8, 300, 3);
    std::fill(image.pixels.begin(), image.pixels.end(), 0.5f);
    int calls = 0;
    Progress stop_at_second([&](double) { return ++calls < 2; });
    EXPECT_THROW(config.to_scene_linear(image, "sRGB", stop_at_second), Cancelled);
    EXPECT_EQ(calls, 2);
    for (float v : image.pixels)
        ASSERT_EQ(v, 0.5f);
}

TEST(ColorConfig, progress_is_reported_at_bounded_intervals_up_to_one) {
    const ColorConfig config = ColorConfig::load(blender_config);
    Image image(4, 1000, 3);
    std::vector<double> seen;
    config.to_scene_linear(image, "sRGB", Progress([&](double f) { seen.push_back(f); return true; }));
    ASSERT_GE(seen.size(), 1000u / 64);
    EXPECT_EQ(seen.back(), 1.0);
    for (std::size_t i = 1; i < seen.size(); ++i)
        EXPECT_GE(seen[i], seen[i - 1]);
}

TEST(ColorConfig, ocio_environment_variable_is_used_when_no_path_is_given) {
    ::setenv("OCIO", blender_config.c_str(), 1);
    EXPECT_EQ(ColorConfig::load().path(), blender_config);
    ::unsetenv("OCIO");
    EXPECT_THROW(ColorConfig::load(), Error);
}

TEST(ColorConfig, missing_config_file_is_a_clear_error) {
    try {
        ColorConfig::load("/no/such/config.ocio");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/no/such/config.ocio"), std::string::npos);
    }
}

}  // namespace
}  // namespace penumbra
