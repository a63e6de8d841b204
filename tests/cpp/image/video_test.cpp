// Video files (image/video.hpp) as frame sources: frames, rate and size of a
// lossless test clip, and a truncated file failing cleanly.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "common/error.hpp"
#include "image/frame_source.hpp"
#include "image/image_io.hpp"
#include "image_test_util.hpp"
#include "test_files.hpp"

namespace penumbra {
namespace {

using testing::flat;
using testing::ScratchDir;

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
