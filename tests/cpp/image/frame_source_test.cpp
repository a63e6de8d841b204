#include "image/frame_source.hpp"

#include <cstdlib>

#include "common/error.hpp"
#include "image/image_io.hpp"
#include "test_files.hpp"

namespace penumbra {
namespace {

using testing::ScratchDir;

Image flat(int w, int h, float value) {
    Image image(w, h, 3);
    std::fill(image.pixels.begin(), image.pixels.end(), value);
    return image;
}

void write_sequence(const ScratchDir& dir, const std::vector<int>& numbers, int w = 8, int h = 4) {
    for (int n : numbers) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.exr", n);
        write_exr(dir.file(name), flat(w, h, 0.1f * n), ExrPrecision::full, "");
    }
}

TEST(FrameSource, numbered_sequence_is_found_in_order_from_its_first_frame) {
    ScratchDir dir;
    write_sequence(dir, {3, 4, 5, 6});
    testing::write_bytes(dir.file("other_0001.exr"), "unrelated");
    const SequenceFiles files = find_sequence(dir.file("frame_0003.exr"));
    ASSERT_EQ(files.numbers, (std::vector<int>{3, 4, 5, 6}));
    auto source = open_frames(dir.file("frame_0003.exr"));
    ASSERT_EQ(source->frame_count(), 4);
    EXPECT_NEAR(source->read(2).pixels[0], 0.5f, 1e-6);
}

TEST(FrameSource, starting_mid_sequence_skips_earlier_frames) {
    ScratchDir dir;
    write_sequence(dir, {1, 2, 3});
    EXPECT_EQ(find_sequence(dir.file("frame_0002.exr")).numbers, (std::vector<int>{2, 3}));
}

TEST(FrameSource, missing_frame_in_a_sequence_is_an_error_naming_it) {
    ScratchDir dir;
    write_sequence(dir, {1, 2, 4, 5});
    try {
        find_sequence(dir.file("frame_0001.exr"));
        FAIL() << "a gap in the sequence went unnoticed";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("frame_0003.exr"), std::string::npos) << e.what();
    }
}

TEST(FrameSource, sequence_whose_frames_change_size_is_an_error_at_that_frame) {
    ScratchDir dir;
    write_sequence(dir, {1, 2});
    write_exr(dir.file("frame_0003.exr"), flat(16, 4, 1.0f), ExrPrecision::full, "");
    auto source = open_frames(dir.file("frame_0001.exr"), FrameSourceKind::sequence);
    EXPECT_NO_THROW(source->read(1));
    try {
        source->read(2);
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("16x4"), std::string::npos) << e.what();
    }
}

TEST(FrameSource, single_numbered_file_without_neighbours_is_a_single_image) {
    ScratchDir dir;
    write_sequence(dir, {7});
    EXPECT_EQ(open_frames(dir.file("frame_0007.exr"))->frame_count(), 1);
}

// Videos are made with the ffmpeg command line from frames of known colour,
// losslessly (PNG in QuickTime, RGB), so decoded pixels can be checked.
class Video : public ::testing::Test {
protected:
    ScratchDir dir;
    std::string make_video(int frames) {
        for (int i = 0; i < frames; ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "src_%04d.png", i);
            write_png16(dir.file(name), flat(32, 16, 0.2f * i), "");
        }
        const std::string video = dir.file("clip.mov");
        const std::string cmd = "ffmpeg -loglevel error -y -framerate 12 -i '" + dir.file("src_%04d.png") +
                                "' -c:v png -pix_fmt rgb24 '" + video + "'";
        EXPECT_EQ(std::system(cmd.c_str()), 0) << "ffmpeg is needed to make test videos: " << cmd;
        return video;
    }
};

TEST_F(Video, video_frames_are_subimages_with_frame_rate) {
    const std::string video = make_video(5);
    auto source = open_frames(video);
    ASSERT_EQ(source->frame_count(), 5);
    EXPECT_NEAR(source->frames_per_second(), 12.0, 1e-6);
    EXPECT_EQ(source->width(), 32);
    EXPECT_EQ(source->height(), 16);
    for (int i = 0; i < 5; ++i)
        // 16-bit PNG to 8-bit video: one extra level of rounding.
        EXPECT_NEAR(source->read(i).pixels[100], 0.2f * i, 1.5 / 255.0) << "frame " << i;
    EXPECT_THROW(source->read(5), ArgumentError);
}

TEST_F(Video, truncated_video_is_an_error_not_a_crash) {
    const std::string video = make_video(5);
    const std::string bytes = testing::read_bytes(video);
    const std::string cut = dir.file("cut.mov");
    testing::write_bytes(cut, bytes.substr(0, 200));
    bool failed_cleanly = false;
    try {
        auto source = open_frames(cut, FrameSourceKind::video);
        for (int i = 0; i < source->frame_count(); ++i)
            source->read(i);
    } catch (const Error&) {
        failed_cleanly = true;
    }
    EXPECT_TRUE(failed_cleanly) << "200 bytes of a video decoded without any error";
}

}  // namespace
}  // namespace penumbra
