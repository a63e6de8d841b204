// Streaming reduce-on-read (lights/map_reader.hpp) against reading the whole
// file with core/image and reducing it in memory (make_environment).
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <limits>
#include <numbers>
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

TEST(LightsMapReader, images_no_wider_than_max_width_are_read_whole) {
    ScratchDir dir;
    const std::string path = dir.file("small.exr");
    write_test_exr(path, 200, 100, 3, false, 1);
    MapOptions o;
    o.max_width = 256;
    ReadReport report;
    const EnvironmentMap a = read_environment(path, nullptr, "", o, {}, 1, &report);
    EXPECT_FALSE(report.streamed);
    expect_same_map(a, make_environment(read_image(path), o));
    for (const Projection p : {Projection::fisheye, Projection::mirror_ball}) {
        o.projection = p;
        read_environment(path, nullptr, "", o, {}, 1, &report);
        EXPECT_FALSE(report.streamed);
    }
}

// Values equal, or one float step apart (a cell whose look-ups span bands is
// summed per band, so its double sum can round to the neighbouring float).
void expect_map_within_one_ulp(const EnvironmentMap& streamed, const EnvironmentMap& whole) {
    ASSERT_EQ(streamed.width, whole.width);
    ASSERT_EQ(streamed.height, whole.height);
    EXPECT_EQ(streamed.full_sphere, whole.full_sphere);
    EXPECT_EQ(streamed.defects.nan, whole.defects.nan);
    EXPECT_EQ(streamed.defects.inf, whole.defects.inf);
    EXPECT_EQ(streamed.defects.negative, whole.defects.negative);
    // Rows are integrated in the same order either way.
    EXPECT_DOUBLE_EQ(streamed.source_integral_luminance, whole.source_integral_luminance);
    ASSERT_EQ(streamed.rgb.size(), whole.rgb.size());
    std::size_t apart = 0, equal = 0;
    for (std::size_t i = 0; i < whole.rgb.size(); ++i) {
        const float a = streamed.rgb[i], b = whole.rgb[i];
        if (a == b) {
            ++equal;
        } else if (std::nextafter(b, 0.0f) == a || std::nextafter(b, 1e30f) == a) {
            ++apart;
        } else {
            ADD_FAILURE() << "value " << i << ": streamed " << a << ", whole " << b;
            return;
        }
    }
    EXPECT_GT(equal, 99 * (equal + apart) / 100);  // nearly every cell lies in one band
}

TEST(LightsMapReader, fisheye_and_mirror_ball_stream_to_the_whole_image_s_map) {
    ScratchDir dir;
    FisheyeLens kannala_brandt;
    kannala_brandt.k = {-0.05, 0.01, 0.0, 0.0};
    struct Case { int w, h, channels; bool tiled; int max_width; Projection p; std::size_t band; FisheyeLens lens; };
    // One-row bands (every cell spans bands), non-square, RGBA, grey, tiled,
    // a lens with distortion, a band as large as the image (one band).
    for (const Case c : {Case{300, 300, 3, false, 128, Projection::fisheye, 1, {}},
                         Case{400, 300, 4, false, 96, Projection::fisheye, 40000, kannala_brandt},
                         Case{320, 320, 1, true, 64, Projection::fisheye, 30000, {}},
                         Case{300, 300, 3, false, 128, Projection::mirror_ball, 1, {}},
                         Case{300, 320, 4, true, 96, Projection::mirror_ball, 60000, {}},
                         Case{300, 300, 3, false, 64, Projection::mirror_ball, std::size_t(1) << 30, {}}}) {
        SCOPED_TRACE(std::string(projection_name(c.p)) + " " + std::to_string(c.w) + "x" + std::to_string(c.h) +
                     "x" + std::to_string(c.channels) + (c.tiled ? " tiled" : "") + " -> " +
                     std::to_string(c.max_width) + ", band " + std::to_string(c.band));
        const std::string path = dir.file("round.exr");
        write_test_exr(path, c.w, c.h, c.channels, c.tiled, unsigned(c.w + c.channels));
        MapOptions o;
        o.projection = c.p;
        o.lens = c.lens;
        o.max_width = c.max_width;
        ReadReport report;
        const EnvironmentMap streamed = read_environment(path, nullptr, "", o, {}, c.band, &report);
        EXPECT_TRUE(report.streamed);
        EXPECT_EQ(report.bands > 1, c.band < (std::size_t(1) << 30));
        expect_map_within_one_ulp(streamed, make_environment(read_image(path), o));
        EXPECT_GT(streamed.defects.total(), 0u);
    }
}

TEST(LightsMapReader, fisheye_colour_conversion_per_band_equals_converting_the_whole_image) {
    ScratchDir dir;
    const ColorConfig config = ColorConfig::load(PENUMBRA_BLENDER_OCIO);
    const std::string path = dir.file("fisheye.exr");
    write_test_exr(path, 300, 300, 3, false, 9);
    MapOptions o;
    o.projection = Projection::fisheye;
    o.max_width = 96;
    const EnvironmentMap streamed = read_environment(path, &config, "sRGB", o, {}, 20000);
    Image image = read_image(path);
    config.to_scene_linear(image, "sRGB");
    expect_map_within_one_ulp(streamed, make_environment(image, o));
}

TEST(LightsMapReader, fisheye_and_mirror_ball_memory_stays_within_a_few_bands) {
    ScratchDir dir;
    const std::string path = dir.file("round.exr");
    const int side = 1536;
    write_test_exr(path, side, side, 3, false, 5);
    const std::size_t whole = std::size_t(side) * side * 3 * sizeof(float);  // 28 MB
    const std::size_t band = std::size_t(512) << 10, row = side * 3 * sizeof(float);
    for (const Projection p : {Projection::fisheye, Projection::mirror_ball}) {
        SCOPED_TRACE(projection_name(p));
        MapOptions o;
        o.projection = p;
        o.max_width = 128;
        ReadReport report;
        const EnvironmentMap map = read_environment(path, nullptr, "", o, {}, band, &report);
        EXPECT_TRUE(report.streamed);
        // The band and the row after it, the file's rows and one converted
        // copy, plus per cell its partial sums, a few index entries and the
        // look-ups' sin/cos tables.
        const std::size_t cells = std::size_t(map.width) * map.height;
        EXPECT_LE(report.buffer_bytes, 3 * band + 3 * row + cells * (3 * sizeof(double) + 4 * sizeof(std::uint32_t)) +
                                           std::size_t(map.width + map.height) * 16 * 2 * sizeof(double));
        EXPECT_LT(report.buffer_bytes * 10, whole);
    }
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

// A sky (brighter towards the zenith, dim ground) and a sun disc of radius
// 8° at 35° elevation that turns 20° about +z per frame.
Eigen::Vector3d sky_radiance(const Eigen::Vector3d& d, int frame) {
    const double az = 0.4 + 0.35 * frame, el = 0.61;
    const Eigen::Vector3d sun(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    if (d.dot(sun) >= std::cos(0.14)) return {60.0, 55.0, 45.0};
    if (d.z() < 0.0) return {0.1, 0.09, 0.08};
    return {0.2 + 0.4 * d.z(), 0.3 + 0.5 * d.z(), 0.5 + 0.8 * d.z()};
}

// The sky as a w×h image in `p`, each pixel the mean of 3×3 look-ups
// (pixels outside a fisheye's or mirror ball's circle stay black).
Image render_sky(Projection p, int w, int h, int frame) {
    Image im(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            for (int j = 0; j < 3; ++j)
                for (int i = 0; i < 3; ++i) {
                    Eigen::Vector3d d;
                    if (image_to_direction(p, {}, w, h, x + (i + 0.5) / 3, y + (j + 0.5) / 3, d))
                        sum += sky_radiance(d, frame);
                }
            for (int c = 0; c < 3; ++c) im.at(x, y, c) = float(sum[c] / 9);
        }
    return im;
}

// Irradiance of a frame's lights on `normal` (luminance).
double rig_irradiance(const RigFrame& frame, const Eigen::Vector3d& normal) {
    double e = 0.0;
    for (const Light& l : frame.lights) e += l.power * std::max(0.0, normal.dot(l.direction));
    return e;
}

TEST(LightsMapReader, fisheye_and_mirror_ball_sequences_give_the_lat_long_sequence_s_lights) {
    ScratchDir dir;
    // Three frames of the same sky in each projection, 384 px wide, streamed
    // in bands of 64 KiB (14 rows) to 192-wide working maps of the same grid:
    // fisheye and hemisphere polar 192×48 (upper hemisphere), mirror ball and
    // equirectangular 192×96. Measured: total power within 0.1%, each light
    // within 1.2° and 0.6% of the total, irradiance on 200 normals within
    // 0.13% of the total.
    const int frames = 3, side = 384;
    const std::size_t band = std::size_t(64) << 10;
    struct Pair { Projection round, latlong; int latlong_height; };
    for (const Pair pair : {Pair{Projection::fisheye, Projection::hemisphere_polar, side / 4},
                            Pair{Projection::mirror_ball, Projection::equirectangular, side / 2}}) {
        SCOPED_TRACE(projection_name(pair.round));
        for (int t = 0; t < frames; ++t) {
            const std::string number = "_000" + std::to_string(t + 1) + ".exr";
            write_exr(dir.file("round" + number), render_sky(pair.round, side, side, t), ExrPrecision::full, "");
            write_exr(dir.file("latlong" + number), render_sky(pair.latlong, side, pair.latlong_height, t),
                      ExrPrecision::full, "");
        }
        RigOptions o;
        o.map.max_width = side / 2;
        o.lights.count = 16;
        // Region lights: the fit would take two nearly equal maps to two of
        // its many nearly equal optima, light by light (it is tested apart).
        o.lights.fit_irradiance = false;
        o.map.projection = pair.round;
        const LightSource round_source(dir.file("round_0001.exr"), FrameSourceKind::automatic, band);
        ReadReport report;
        round_source.read_map(frames - 1, nullptr, "", o.map, {}, &report);
        EXPECT_TRUE(report.streamed);
        EXPECT_GT(report.bands, 20);
        const LightRig round = build_light_rig(round_source, nullptr, "", o);
        o.map.projection = pair.latlong;
        const LightSource latlong_source(dir.file("latlong_0001.exr"), FrameSourceKind::automatic, band);
        const LightRig latlong = build_light_rig(latlong_source, nullptr, "", o);
        ASSERT_EQ(round.frames.size(), std::size_t(frames));
        ASSERT_EQ(latlong.frames.size(), std::size_t(frames));
        ASSERT_EQ(round.slots, latlong.slots);
        std::mt19937 rng(4);
        std::normal_distribution<double> g;
        for (int t = 0; t < frames; ++t) {
            SCOPED_TRACE("frame " + std::to_string(t));
            const RigFrame &a = round.frames[t], &b = latlong.frames[t];
            const double total = b.total_power;
            EXPECT_NEAR(a.total_power, total, 0.002 * total);
            for (int k = 0; k < round.slots; ++k) {
                const double cosine = a.lights[k].direction.dot(b.lights[k].direction);
                EXPECT_GT(cosine, std::cos(2.0 * std::numbers::pi / 180)) << "light " << k;
                EXPECT_NEAR(a.lights[k].power, b.lights[k].power, 0.015 * total) << "light " << k;
            }
            for (int n = 0; n < 200; ++n) {
                const Eigen::Vector3d normal = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
                EXPECT_NEAR(rig_irradiance(a, normal), rig_irradiance(b, normal), 0.005 * total);
            }
        }
    }
}

}  // namespace
}  // namespace penumbra::lights
