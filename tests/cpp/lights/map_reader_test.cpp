// Streaming reduce-on-read (lights/map_reader.hpp) against reading the whole
// file with core/image and reducing it in memory (make_environment).
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <limits>
#include <random>

#include "color/color_config.hpp"
#include "common/error.hpp"
#include "image/image_io.hpp"
#include "lights/map_reader.hpp"
#include "lights/rig.hpp"
#include "test_files.hpp"

namespace penumbra::lights {
namespace {

using penumbra::testing::ScratchDir;

// Random HDR content with a bright spot and a few bad values, written with
// OpenImageIO (float, `channels` channels, scanline or tiled).
void write_test_exr(const std::string& path, int w, int h, int channels, bool tiled, unsigned seed) {
    std::mt19937 rng(seed);
    std::lognormal_distribution<float> lum(0.0f, 2.0f);
    std::vector<float> px(std::size_t(w) * h * channels);
    for (float& v : px) v = lum(rng);
    px[5] = std::numeric_limits<float>::quiet_NaN();
    px[std::size_t(w) * channels * (h / 2) + 7] = -3.0f;
    px[px.size() - 2] = std::numeric_limits<float>::infinity();
    for (int y = h / 3; y < h / 3 + 3; ++y)
        for (int x = w / 5; x < w / 5 + 3; ++x) px[(std::size_t(y) * w + x) * channels] = 5e4f;
    OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::FLOAT);
    if (channels == 4) spec.channelnames = {"R", "G", "B", "A"};
    if (tiled) {
        spec.tile_width = 32;
        spec.tile_height = 32;
    }
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    out->close();
}

void expect_same_map(const EnvironmentMap& a, const EnvironmentMap& b) {
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    EXPECT_EQ(a.full_sphere, b.full_sphere);
    EXPECT_EQ(a.defects.nan, b.defects.nan);
    EXPECT_EQ(a.defects.inf, b.defects.inf);
    EXPECT_EQ(a.defects.negative, b.defects.negative);
    EXPECT_DOUBLE_EQ(a.source_integral_luminance, b.source_integral_luminance);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
        if (a.rgb[i] != b.rgb[i]) ++differ;
    EXPECT_EQ(differ, 0u) << "of " << a.rgb.size() << " values";
}

TEST(LightsMapReader, streaming_equals_reading_whole_then_reducing) {
    ScratchDir dir;
    struct Case { int w, h, channels; bool tiled; int max_width; Projection p; std::size_t band; };
    // Non-integer ratios (rows shared by neighbouring bands), one-row bands,
    // RGBA, grey, tiled, hemisphere polar.
    for (const Case c : {Case{1000, 500, 3, false, 256, Projection::equirectangular, 1},
                         Case{1000, 500, 4, false, 300, Projection::equirectangular, 200000},
                         Case{999, 333, 1, false, 128, Projection::hemisphere_polar, 1},
                         Case{640, 320, 3, true, 96, Projection::equirectangular, 50000},
                         Case{640, 320, 3, false, 96, Projection::equirectangular, std::size_t(1) << 30}}) {
        SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h) + "x" + std::to_string(c.channels) +
                     (c.tiled ? " tiled" : "") + " -> " + std::to_string(c.max_width));
        const std::string path = dir.file("map.exr");
        write_test_exr(path, c.w, c.h, c.channels, c.tiled, unsigned(c.w + c.channels));
        MapOptions o;
        o.projection = c.p;
        o.max_width = c.max_width;
        ReadReport report;
        const EnvironmentMap streamed = read_environment(path, nullptr, "", o, {}, c.band, &report);
        EXPECT_TRUE(report.streamed);
        EXPECT_GT(report.bands, c.band < (std::size_t(1) << 30) ? 1 : 0);
        const EnvironmentMap whole = make_environment(read_image(path), o);
        expect_same_map(streamed, whole);
        EXPECT_GT(streamed.defects.total(), 0u);
    }
}

TEST(LightsMapReader, colour_conversion_per_band_equals_converting_the_whole_image) {
    ScratchDir dir;
    const ColorConfig config = ColorConfig::load(PENUMBRA_BLENDER_OCIO);
    const std::string path = dir.file("map.exr");
    write_test_exr(path, 800, 400, 3, false, 7);
    MapOptions o;
    o.max_width = 200;
    const EnvironmentMap streamed = read_environment(path, &config, "sRGB", o, {}, 1);
    Image image = read_image(path);
    config.to_scene_linear(image, "sRGB");
    expect_same_map(streamed, make_environment(image, o));
}

TEST(LightsMapReader, memory_stays_within_a_few_bands) {
    ScratchDir dir;
    const std::string path = dir.file("wide.exr");
    write_test_exr(path, 4096, 2048, 3, false, 3);
    MapOptions o;
    o.max_width = 256;
    ReadReport report;
    read_environment(path, nullptr, "", o, {}, std::size_t(1) << 20, &report);
    const std::size_t whole = std::size_t(4096) * 2048 * 3 * sizeof(float);  // 100 MB
    EXPECT_TRUE(report.streamed);
    // band ≤ 1 MiB of rows (or one output row's 16 rows), plus the file rows and one converted copy
    EXPECT_LE(report.buffer_bytes, 3 * std::max<std::size_t>(1 << 20, 16 * 4096 * 12) + 3 * 4096 * 12);
    EXPECT_LT(report.buffer_bytes * 20, whole);
}

TEST(LightsMapReader, small_images_and_fisheye_are_read_whole) {
    ScratchDir dir;
    const std::string path = dir.file("small.exr");
    write_test_exr(path, 200, 100, 3, false, 1);
    MapOptions o;
    o.max_width = 256;
    ReadReport report;
    const EnvironmentMap a = read_environment(path, nullptr, "", o, {}, 1, &report);
    EXPECT_FALSE(report.streamed);
    expect_same_map(a, make_environment(read_image(path), o));
    o.projection = Projection::fisheye;
    o.max_width = 64;
    read_environment(path, nullptr, "", o, {}, 1, &report);
    EXPECT_FALSE(report.streamed);
}

TEST(LightsMapReader, bad_files_raise_io_errors) {
    ScratchDir dir;
    MapOptions o;
    o.max_width = 16;
    EXPECT_THROW(read_environment(dir.file("missing.exr"), nullptr, "", o), IoError);
    // A truncated file: the header reads, the rows do not.
    const std::string path = dir.file("cut.exr");
    write_test_exr(path, 512, 256, 3, false, 2);
    std::string bytes = penumbra::testing::read_bytes(path);
    penumbra::testing::write_bytes(path, bytes.substr(0, bytes.size() / 2));
    EXPECT_THROW(read_environment(path, nullptr, "", o), IoError);
    o.max_width = 2;
    EXPECT_THROW(read_environment(path, nullptr, "", o), ArgumentError);
}

TEST(LightsMapReader, a_light_source_streams_sequence_frames_and_checks_their_size) {
    ScratchDir dir;
    write_test_exr(dir.file("f_0001.exr"), 600, 300, 3, false, 11);
    write_test_exr(dir.file("f_0002.exr"), 600, 300, 3, false, 12);
    write_test_exr(dir.file("f_0003.exr"), 400, 200, 3, false, 13);
    const LightSource source(dir.file("f_0001.exr"));
    ASSERT_EQ(source.frames().frame_count(), 3);
    ASSERT_EQ(source.files().size(), 3u);
    MapOptions o;
    o.max_width = 64;
    ReadReport report;
    const EnvironmentMap m = source.read_map(1, nullptr, "", o, {}, &report);
    EXPECT_TRUE(report.streamed);
    expect_same_map(m, make_environment(read_image(dir.file("f_0002.exr")), o));
    EXPECT_THROW(source.read_map(2, nullptr, "", o), IoError);
    // The rig built from the source equals the one built from whole frames.
    RigOptions ro;
    ro.map = o;
    ro.lights.count = 8;
    const LightSource two(dir.file("f_0001.exr"));
    RigBuilder whole(ro);
    whole.add_frame(read_image(dir.file("f_0001.exr")));
    whole.add_frame(read_image(dir.file("f_0002.exr")));
    const LightRig a = whole.finish(), b = build_light_rig(two, nullptr, "", ro, 0, 2);
    ASSERT_EQ(a.frames.size(), b.frames.size());
    for (std::size_t t = 0; t < a.frames.size(); ++t)
        for (int k = 0; k < a.slots; ++k) {
            EXPECT_EQ(a.frames[t].lights[k].direction, b.frames[t].lights[k].direction);
            EXPECT_EQ(a.frames[t].lights[k].rgb, b.frames[t].lights[k].rgb);
        }
}

}  // namespace
}  // namespace penumbra::lights
