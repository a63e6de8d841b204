#include "image/video.hpp"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <vector>

#include "common/child_process.hpp"
#include "common/error.hpp"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

std::mutex executable_mutex;
std::string executable_override;

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

void check_readable(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError("video file not found: '" + path + "'; check the path");
    if (fs::is_directory(path, ec)) throw IoError("'" + path + "' is a folder, not a video file");
    if (fs::file_size(path, ec) == 0) throw IoError("video file '" + path + "' is empty (0 bytes); re-export it");
}

// ffmpeg's arguments before the input: quiet, never reading our stdin.
std::vector<std::string> ffmpeg_command(const std::string& path) {
    return {ffmpeg_executable(), "-hide_banner", "-nostdin", "-v", "error", "-i", path, "-map", "0:v:0"};
}

[[noreturn]] void fail(const std::string& path, const std::string& what, ChildProcess& child) {
    const int status = child.wait();
    std::string message = child.stderr_text();
    if (status == 127 || (message.empty() && status != 0))
        message = "'" + ffmpeg_executable() + "' exited with status " + std::to_string(status) +
                  " (is it installed? the add-on ships one; set PENUMBRA_FFMPEG to use another)";
    throw IoError("cannot " + what + " video '" + path + "': " + (message.empty() ? "no output" : message) +
                  "; the file may be truncated or in a format FFmpeg cannot read");
}

// One line of FFmpeg's framecrc listing: "#key 0: value" headers, then one
// "stream, dts, pts, duration, size, crc" line per packet of the stream.
void parse_framecrc(const std::string& text, VideoInfo& info) {
    std::istringstream lines(text);
    std::string line;
    long long tb_num = 0, tb_den = 0, duration = 0;
    while (std::getline(lines, line)) {
        if (line.rfind("#tb 0: ", 0) == 0) {
            std::sscanf(line.c_str() + 7, "%lld/%lld", &tb_num, &tb_den);
        } else if (line.rfind("#codec_id 0: ", 0) == 0) {
            info.codec = line.substr(13);
        } else if (line.rfind("#dimensions 0: ", 0) == 0) {
            std::sscanf(line.c_str() + 15, "%dx%d", &info.width, &info.height);
        } else if (!line.empty() && line[0] != '#') {
            long long dts = 0, pts = 0, d = 0;
            if (std::sscanf(line.c_str(), "0, %lld, %lld, %lld", &dts, &pts, &d) == 3) {
                ++info.frame_count;
                if (duration == 0) duration = d;
            }
        }
    }
    if (tb_num > 0 && tb_den > 0 && duration > 0)
        info.frames_per_second = double(tb_den) / (double(tb_num) * double(duration));
}

// One frame of `values` floats from the decoder into `frame`. The buffer
// grows to a whole frame only once the first 64 MiB of it have arrived, so
// dimensions from a damaged or hostile listing cost memory only when the
// decoder really delivers that many pixels. False when the output ends first.
bool read_frame(ChildProcess& child, std::vector<float>& frame, std::size_t values) {
    constexpr std::size_t first_values = (std::size_t(64) << 20) / sizeof(float);
    std::size_t done = 0;
    for (const std::size_t until : {std::min(values, first_values), values}) {
        if (until <= done) continue;
        if (frame.size() < until) frame.resize(until);
        if (!child.read_exact(frame.data() + done, (until - done) * sizeof(float))) return false;
        done = until;
    }
    return true;
}

}  // namespace

bool is_video_file(const std::string& path) {
    static const char* const extensions[] = {".mov", ".mp4", ".m4v", ".mkv", ".webm", ".avi",
                                             ".mxf", ".mts", ".m2ts", ".ts", ".mpg", ".mpeg"};
    const std::string ext = lower_extension(path);
    return std::any_of(std::begin(extensions), std::end(extensions), [&](const char* e) { return ext == e; });
}

void set_ffmpeg_executable(const std::string& path) {
    std::lock_guard<std::mutex> lock(executable_mutex);
    executable_override = path;
}

std::string ffmpeg_executable() {
    {
        std::lock_guard<std::mutex> lock(executable_mutex);
        if (!executable_override.empty()) return executable_override;
    }
    const char* env = std::getenv("PENUMBRA_FFMPEG");
    return env && *env ? env : "ffmpeg";
}

VideoInfo probe_video(const std::string& path) {
    check_readable(path);
    // Copying packets into framecrc lists every frame without decoding any.
    std::vector<std::string> argv = ffmpeg_command(path);
    for (const char* a : {"-c", "copy", "-f", "framecrc", "-"}) argv.emplace_back(a);
    ChildProcess child(argv);
    const std::string listing = child.read_all();
    if (child.wait() != 0) fail(path, "read", child);
    VideoInfo info;
    parse_framecrc(listing, info);
    if (info.width <= 0 || info.height <= 0 || info.frame_count <= 0)
        throw IoError("video '" + path + "' has no video frames (" + std::to_string(info.width) + "x" +
                      std::to_string(info.height) + ", " + std::to_string(info.frame_count) + " frames)");
    // FFmpeg decodes no picture beyond (w + 128)(h + 128) < INT_MAX / 8
    // (av_image_check_size); larger dimensions are a damaged listing.
    if ((std::uint64_t(info.width) + 128) * (std::uint64_t(info.height) + 128) >= std::uint64_t(INT_MAX / 8))
        throw IoError("video '" + path + "' declares " + std::to_string(info.width) + "x" +
                      std::to_string(info.height) + " pixels, more than FFmpeg decodes; the file is damaged");
    return info;
}

struct VideoReader::Decoder {
    ChildProcess child;
    explicit Decoder(const std::vector<std::string>& argv) : child(argv) {}
};

VideoReader::VideoReader(std::string path) : path_(std::move(path)), info_(probe_video(path_)) {}

VideoReader::~VideoReader() = default;

Image VideoReader::read(int index) {
    if (index < 0 || index >= info_.frame_count)
        throw ArgumentError("frame index " + std::to_string(index) + " is outside the video's " +
                            std::to_string(info_.frame_count) + " frames");
    if (!decoder_ || index < next_) {
        // Planar float GBR: FFmpeg does the YUV -> RGB conversion at full precision.
        std::vector<std::string> argv = ffmpeg_command(path_);
        for (const char* a : {"-f", "rawvideo", "-pix_fmt", "gbrpf32le", "-"}) argv.emplace_back(a);
        decoder_.reset();
        decoder_ = std::make_unique<Decoder>(argv);
        next_ = 0;
    }
    const std::size_t plane = std::size_t(info_.width) * info_.height;
    std::vector<float> gbr;
    for (; next_ <= index; ++next_) {
        if (!read_frame(decoder_->child, gbr, plane * 3)) {
            std::unique_ptr<Decoder> ended = std::move(decoder_);
            if (ended->child.wait() != 0) fail(path_, "decode frame " + std::to_string(next_) + " of", ended->child);
            throw IoError("video '" + path_ + "' ended after " + std::to_string(next_) + " of its " +
                          std::to_string(info_.frame_count) + " frames; the file may be truncated");
        }
    }
    Image image(info_.width, info_.height, 3);
    const float* g = gbr.data();
    const float* b = g + plane;
    const float* r = b + plane;
    for (std::size_t p = 0; p < plane; ++p) {
        image.pixels[p * 3 + 0] = r[p];
        image.pixels[p * 3 + 1] = g[p];
        image.pixels[p * 3 + 2] = b[p];
    }
    return image;
}

}  // namespace penumbra
