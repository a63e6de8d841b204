// Video files (image/video.hpp) as frame sources: frames, rate and size of a
// lossless test clip, a truncated file failing cleanly, and planar YUV
// frames converted here as FFmpeg's own scaler converts them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/child_process.hpp"
#include "common/error.hpp"
#include "image/video.hpp"
#include "image/yuv.hpp"
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

// Frames of `path` as FFmpeg converts them itself (planar float GBR, the
// decoder's path for everything but planar YUV), interleaved to RGB.
std::vector<Image> ffmpeg_rgb_frames(const std::string& path, int width, int height, int frames) {
    ChildProcess child({ffmpeg_executable(), "-v", "error", "-nostdin", "-i", path, "-map", "0:v:0", "-f", "rawvideo",
                        "-pix_fmt", "gbrpf32le", "-"});
    const std::size_t plane = std::size_t(width) * height;
    std::vector<Image> out;
    std::vector<float> gbr(plane * 3);
    for (int f = 0; f < frames; ++f) {
        EXPECT_TRUE(child.read_exact(gbr.data(), gbr.size() * sizeof(float))) << path << " frame " << f;
        Image image(width, height, 3);
        for (std::size_t p = 0; p < plane; ++p) {
            image.pixels[3 * p] = gbr[2 * plane + p];
            image.pixels[3 * p + 1] = gbr[p];
            image.pixels[3 * p + 2] = gbr[plane + p];
        }
        out.push_back(image);
    }
    return out;
}

TEST_F(Video, planar_yuv_frames_match_ffmpegs_own_conversion) {
    // FFmpeg's test pattern (colour bars, gradients, sharp edges: chroma
    // upsampling shows) in the formats HDR and ordinary video come in. Odd
    // sizes for 4:2:0 and 4:2:2 (a chroma sample covering one luma column).
    struct Case {
        const char* name;
        const char* size;
        const char* encode;  // ffmpeg arguments after the input
        const char* pixel_format;
        const char* color_space;
    };
    const Case cases[] = {
        {"h264_709.mp4", "63x37", "-c:v libx264 -pix_fmt yuv420p -colorspace bt709 -color_range tv", "yuv420p", "bt709"},
        {"h264_444.mp4", "64x36", "-c:v libx264 -pix_fmt yuv444p", "yuv444p", ""},
        {"mjpeg.mov", "65x35", "-c:v mjpeg -pix_fmt yuvj422p", "yuvj422p", "bt470bg"},
        {"hevc10_2020.mp4", "64x48",
         "-c:v libx265 -pix_fmt yuv420p10le -x265-params log-level=error -colorspace bt2020nc -color_primaries bt2020 "
         "-color_trc smpte2084",
         "yuv420p10le", "bt2020nc"},
        {"prores4444a.mov", "48x32",
         "-c:v prores_ks -profile:v 4444 -pix_fmt yuva444p10le -colorspace bt709 -color_primaries bt709 "
         "-color_trc bt709",
         "yuva444p12le", "bt709"},
    };
    for (const Case& c : cases) {
        const std::string video = dir.file(c.name);
        const std::string cmd = std::string("ffmpeg -loglevel error -y -f lavfi -i testsrc2=size=") + c.size +
                                ":rate=10 -frames:v 3 " + c.encode + " '" + video + "'";
        ASSERT_EQ(std::system(cmd.c_str()), 0) << "ffmpeg is needed to make test videos: " << cmd;
        VideoReader reader(video);
        const VideoInfo& info = reader.info();
        EXPECT_EQ(info.pixel_format, c.pixel_format) << c.name;
        EXPECT_EQ(info.color_space, c.color_space) << c.name;
        // The frames come through the pipe as the decoder made them.
        ASSERT_TRUE(yuv_format(info.pixel_format, info.color_range, info.color_space, info.width, info.height))
            << c.name << ": " << info.pixel_format;
        const std::vector<Image> expected = ffmpeg_rgb_frames(video, info.width, info.height, info.frame_count);
        ASSERT_EQ(info.frame_count, 3) << c.name;
        double worst = 0.0, sum = 0.0;
        std::size_t count = 0;
        for (int f = 0; f < info.frame_count; ++f) {
            const Image got = reader.read(f);
            ASSERT_EQ(got.pixels.size(), expected[std::size_t(f)].pixels.size()) << c.name;
            for (std::size_t i = 0; i < got.pixels.size(); ++i) {
                const double d = std::abs(double(got.pixels[i]) - expected[std::size_t(f)].pixels[i]);
                worst = std::max(worst, d);
                sum += d;
                ++count;
            }
        }
        // swscale works in fixed point (15 to 19 bits): a few 12-bit steps.
        // Where chroma is subsampled its filters also differ a little from
        // the bicubic here at sharp chroma edges (measured up to 0.03).
        const bool subsampled = info.pixel_format.find("444") == std::string::npos;
        EXPECT_LT(worst, subsampled ? 0.05 : 0.01) << c.name;
        EXPECT_LT(sum / double(count), 0.002) << c.name;
        std::printf("%s: max |ours - FFmpeg's| %.4f, mean %.5f\n", c.name, worst, sum / double(count));
    }
}

TEST_F(Video, frames_are_the_same_on_one_thread_and_several) {
    const std::string video = dir.file("clip.mp4");
    const std::string cmd = "ffmpeg -loglevel error -y -f lavfi -i testsrc2=size=96x64:rate=10 -frames:v 4 -c:v libx264 "
                            "-pix_fmt yuv420p '" + video + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    VideoReader one(video, 1), several(video, 3);
    for (int f = 0; f < 4; ++f) EXPECT_EQ(one.read(f).pixels, several.read(f).pixels) << "frame " << f;
}

}  // namespace
}  // namespace penumbra
