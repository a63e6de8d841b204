// Video files, decoded by FFmpeg's command-line program in a child process.
//
// Why a child process: the package cannot carry FFmpeg's libraries together
// with headers that match them, but it can carry the static `ffmpeg` of the
// imageio-ffmpeg wheel (docs/packaging.md); and a decoder that crashes on a
// damaged file then cannot take Blender, and the user's unsaved work, with it.
//
// Which `ffmpeg`: set_ffmpeg_executable() (the add-on passes the one it
// ships), else $PENUMBRA_FFMPEG, else `ffmpeg` on PATH.
//
// Frames come out like read_image()'s: float RGB as stored in the file, row 0
// at the top. For ordinary video that is display-referred RGB in [0, 1]
// (YUV converted with the matrix the file declares); colour/ converts it to
// scene-linear. Planar YUV (what HEVC, H.264, ProRes, DNxHR and most other
// codecs decode to) comes through the pipe as the decoder made it and is
// converted here, as FFmpeg's scaler would (image/yuv.hpp); anything else
// (RGB, grey, float) FFmpeg converts to planar float RGB itself.
#pragma once

#include <memory>
#include <string>

#include "image/image.hpp"

namespace penumbra {

// True for the container extensions read as video (.mov, .mp4, .mkv, ...).
bool is_video_file(const std::string& path);

void set_ffmpeg_executable(const std::string& path);  // "" restores the default
std::string ffmpeg_executable();

struct VideoInfo {
    int width = 0;
    int height = 0;
    int frame_count = 0;
    double frames_per_second = 0.0;
    std::string codec;  // FFmpeg's name: "hevc", "prores", ...
    // As FFmpeg describes the stream ("" when it does not say): the
    // decoder's pixel format ("yuv420p10le"), range ("tv", "pc") and colour
    // space ("bt709", "bt2020nc", ...).
    std::string pixel_format, color_range, color_space;
};

// Reads the container without decoding. Throws IoError naming the file and
// FFmpeg's own message for a missing, empty, truncated or unknown file.
VideoInfo probe_video(const std::string& path);

// Decodes frames in order; asking for an earlier frame restarts the decoder.
class VideoReader {
public:
    // Probes; throws IoError. `threads`: FFmpeg's decoding threads and this
    // side's conversion threads (0: as many as there are cores).
    explicit VideoReader(std::string path, int threads = 0);
    ~VideoReader();
    const VideoInfo& info() const { return info_; }
    // Frame `index` in [0, frame_count). Throws ArgumentError out of range,
    // IoError when the file ends or fails to decode before that frame.
    Image read(int index);

private:
    struct Decoder;
    std::string path_;
    VideoInfo info_;
    std::unique_ptr<Decoder> decoder_;
    int next_ = 0;  // the frame the running decoder delivers next
    int threads_ = 0;
};

}  // namespace penumbra
