#include "image/image_io.hpp"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "test_files.hpp"

namespace penumbra {
namespace {

using testing::ScratchDir;

// A small image whose every value is distinct, so channel mix-ups show.
Image ramp(int w, int h, int c) {
    Image image(w, h, c);
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = 0.001f * static_cast<float>(i) + 0.25f;
    return image;
}

// Writes a file with OpenImageIO directly, independent of the code under test.
void oiio_write(const std::string& path, const Image& image, OIIO::TypeDesc type) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()));
    ASSERT_TRUE(out->close());
}

TEST(ImageIo, float_exr_round_trip_is_exact_and_records_colorspace) {
    ScratchDir dir;
    const Image original = ramp(7, 5, 3);
    write_exr(dir.file("a.exr"), original, ExrPrecision::full, "Linear Rec.709");
    const Image back = read_image(dir.file("a.exr"));
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    ASSERT_EQ(back.channels, 3);
    EXPECT_EQ(back.pixels, original.pixels);
    EXPECT_EQ(read_image_info(dir.file("a.exr")).colorspace, "Linear Rec.709");
}

TEST(ImageIo, half_exr_round_trip_keeps_half_precision) {
    ScratchDir dir;
    const Image original = ramp(4, 3, 3);
    write_exr(dir.file("h.exr"), original, ExrPrecision::half, "");
    const Image back = read_image(dir.file("h.exr"));
    for (std::size_t i = 0; i < original.pixels.size(); ++i)
        EXPECT_NEAR(back.pixels[i], original.pixels[i], original.pixels[i] * 1e-3);
}

TEST(ImageIo, png16_quantizes_to_16_bits_clamps_and_records_colorspace) {
    ScratchDir dir;
    Image image(3, 1, 3);
    image.pixels = {0.5f, -1.0f, 2.0f, 0.25f, 0.75f, 1.0f, 0.0f, 0.1f, 0.9f};
    write_png16(dir.file("p.png"), image, "sRGB");
    const Image back = read_image(dir.file("p.png"));
    const float expected[] = {0.5f, 0.0f, 1.0f, 0.25f, 0.75f, 1.0f, 0.0f, 0.1f, 0.9f};
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(back.pixels[i], expected[i], 1.0 / 65535.0);
    auto in = OIIO::ImageInput::open(dir.file("p.png"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT16);
    EXPECT_EQ(read_image_info(dir.file("p.png")).colorspace, "sRGB");
}

TEST(ImageIo, radiance_hdr_and_tiff_are_read) {
    ScratchDir dir;
    const Image original = ramp(6, 4, 3);
    oiio_write(dir.file("a.hdr"), original, OIIO::TypeDesc::FLOAT);
    oiio_write(dir.file("a.tif"), original, OIIO::TypeDesc::FLOAT);
    const Image hdr = read_image(dir.file("a.hdr"));
    const Image tif = read_image(dir.file("a.tif"));
    for (std::size_t i = 0; i < original.pixels.size(); ++i) {
        EXPECT_NEAR(hdr.pixels[i], original.pixels[i], original.pixels[i] * 0.01);  // RGBE: 8-bit mantissa
        EXPECT_EQ(tif.pixels[i], original.pixels[i]);
    }
}

TEST(ImageIo, one_channel_image_is_copied_to_rgb) {
    ScratchDir dir;
    const Image grey = ramp(3, 2, 1);
    oiio_write(dir.file("g.exr"), grey, OIIO::TypeDesc::FLOAT);
    const Image rgb = read_image(dir.file("g.exr"));
    ASSERT_EQ(rgb.channels, 3);
    for (std::size_t p = 0; p < grey.pixels.size(); ++p)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(rgb.pixels[p * 3 + c], grey.pixels[p]);
    EXPECT_EQ(read_image_info(dir.file("g.exr")).file_channels, 1);
}

TEST(ImageIo, two_channel_image_keeps_grey_and_drops_alpha) {
    ScratchDir dir;
    const Image ga = ramp(3, 2, 2);
    oiio_write(dir.file("ga.tif"), ga, OIIO::TypeDesc::FLOAT);
    const Image rgb = read_image(dir.file("ga.tif"));
    for (std::size_t p = 0; p < ga.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(rgb.pixels[p * 3 + c], ga.pixels[p * 2]);
}

TEST(ImageIo, four_channel_image_drops_alpha) {
    ScratchDir dir;
    const Image rgba = ramp(3, 2, 4);
    write_exr(dir.file("rgba.exr"), rgba, ExrPrecision::full, "");
    const Image rgb = read_image(dir.file("rgba.exr"));
    for (std::size_t p = 0; p < rgba.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(rgb.pixels[p * 3 + c], rgba.pixels[p * 4 + c]);
}

TEST(ImageIo, nan_and_inf_pixels_are_kept_as_stored_and_counted_by_sanitize) {
    ScratchDir dir;
    Image image(2, 2, 3);
    image.pixels = {1.0f, std::numeric_limits<float>::quiet_NaN(), 2.0f,
                    std::numeric_limits<float>::infinity(), -3.0f, 0.5f,
                    0.0f, 0.0f, -std::numeric_limits<float>::infinity(),
                    4.0f, 5.0f, 6.0f};
    write_exr(dir.file("bad.exr"), image, ExrPrecision::full, "");
    Image back = read_image(dir.file("bad.exr"));
    EXPECT_TRUE(std::isnan(back.pixels[1]));
    EXPECT_TRUE(std::isinf(back.pixels[3]));
    const PixelDefects found = sanitize(back, true);
    EXPECT_EQ(found.nan, 1u);
    EXPECT_EQ(found.inf, 2u);
    EXPECT_EQ(found.negative, 1u);
    EXPECT_EQ(back.pixels[1], 0.0f);
    EXPECT_EQ(back.pixels[3], 0.0f);
    EXPECT_EQ(back.pixels[4], 0.0f);
    EXPECT_EQ(back.pixels[0], 1.0f);
    EXPECT_EQ(count_defects(back).total(), 0u);
}

TEST(ImageIo, truncated_exr_is_a_clear_error) {
    ScratchDir dir;
    write_exr(dir.file("full.exr"), ramp(64, 64, 3), ExrPrecision::full, "");
    const std::string bytes = testing::read_bytes(dir.file("full.exr"));
    testing::write_bytes(dir.file("cut.exr"), bytes.substr(0, bytes.size() / 2));
    try {
        read_image(dir.file("cut.exr"));
        FAIL() << "a truncated EXR was read without error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("cut.exr"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
}

// Documented behaviour: a file is read by its content, not its extension, so
// a PNG named .exr is read as the PNG it is and reported as such.
TEST(ImageIo, png_renamed_exr_is_read_by_content_and_reports_png) {
    ScratchDir dir;
    Image image(2, 2, 3);
    image.pixels = {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f, 0.1f, 0.3f, 0.5f, 0.7f, 0.9f, 0.0f};
    write_png16(dir.file("real.png"), image, "");
    std::filesystem::copy_file(dir.file("real.png"), dir.file("fake.exr"));
    EXPECT_EQ(read_image_info(dir.file("fake.exr")).format, "png");
    const Image back = read_image(dir.file("fake.exr"));
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        EXPECT_NEAR(back.pixels[i], image.pixels[i], 1.0 / 65535.0);
}

TEST(ImageIo, garbage_with_exr_extension_is_a_clear_error) {
    ScratchDir dir;
    testing::write_bytes(dir.file("junk.exr"), "this is not an image at all, just text\n");
    EXPECT_THROW(read_image(dir.file("junk.exr")), IoError);
}

TEST(ImageIo, empty_file_and_missing_file_are_clear_errors) {
    ScratchDir dir;
    testing::write_bytes(dir.file("empty.exr"), "");
    try {
        read_image(dir.file("empty.exr"));
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
    }
    try {
        read_image(dir.file("nope.exr"));
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, zero_sized_image_cannot_be_written_and_leaves_no_file) {
    ScratchDir dir;
    Image empty(0, 0, 3);
    EXPECT_THROW(write_exr(dir.file("z.exr"), empty, ExrPrecision::half, ""), ArgumentError);
    EXPECT_THROW(write_png16(dir.file("z.png"), Image(0, 4, 3), ""), ArgumentError);
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(ImageIo, failed_write_keeps_the_previous_file_and_leaves_no_temporary) {
    ScratchDir dir;
    const Image first = ramp(4, 4, 3);
    write_exr(dir.file("keep.exr"), first, ExrPrecision::full, "");
    const std::string before = testing::read_bytes(dir.file("keep.exr"));
    // Unsupported extension for the same name: the write fails before rename.
    EXPECT_THROW(write_exr(dir.file("keep.notaformat"), first, ExrPrecision::full, ""), IoError);
    EXPECT_EQ(testing::read_bytes(dir.file("keep.exr")), before);
    int files = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path()))
        ++files;
    EXPECT_EQ(files, 1);
}

TEST(ImageIo, write_into_missing_folder_is_a_clear_error) {
    ScratchDir dir;
    EXPECT_THROW(write_exr(dir.file("no/such/folder/a.exr"), ramp(2, 2, 3), ExrPrecision::half, ""), IoError);
}

TEST(ImageIo, missing_video_frame_index_is_a_clear_error) {
    ScratchDir dir;
    write_exr(dir.file("one.exr"), ramp(2, 2, 3), ExrPrecision::half, "");
    EXPECT_THROW(read_image(dir.file("one.exr"), 3), IoError);
}

}  // namespace
}  // namespace penumbra
