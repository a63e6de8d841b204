#include "image/video.hpp"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include "common/child_process.hpp"
#include "common/error.hpp"
#include "image/yuv.hpp"

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

// ffmpeg's arguments up to the output: never reading our stdin, `threads`
// decoding threads (0: FFmpeg's choice), only errors on stderr unless
// `level` says otherwise (without progress lines).
std::vector<std::string> ffmpeg_command(const std::string& path, int threads = 0, const char* level = "error") {
    std::vector<std::string> argv{ffmpeg_executable(), "-hide_banner", "-nostdin", "-nostats", "-v", level};
    if (threads > 0)
        for (const std::string& a : {std::string("-threads"), std::to_string(threads), std::string("-filter_threads"),
                                    std::to_string(threads)})
            argv.push_back(a);
    for (const char* a : {"-i", path.c_str(), "-map", "0:v:0"}) argv.emplace_back(a);
    return argv;
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

// The decoder's pixel format, range and colour space from FFmpeg's
// description of the input's first video stream, e.g.
//   Stream #0:0[0x1](und): Video: hevc (Main 10) (hvc1 / 0x31637668), yuv420p10le(tv, bt709, progressive), 1024x512, ...
// (libavcodec's avcodec_string: the pixel format, then in parentheses the
// bits per sample if fewer, the range, the colour space — alone, or as
// space/primaries/transfer — and the field order). Fields it cannot find
// stay empty, which later means "let FFmpeg convert".
void parse_stream_description(const std::string& text, VideoInfo& info) {
    // The first line that is a stream of input 0 and a video one (metadata
    // lines are indented further, so a title cannot pose as a stream).
    std::size_t at = text.find("Input #0");
    std::string line;
    while (at != std::string::npos && line.empty()) {
        at = text.find("\n  Stream #0:", at);
        if (at == std::string::npos) return;
        const std::size_t end = text.find('\n', at + 1);
        const std::string candidate = text.substr(at + 1, end == std::string::npos ? std::string::npos : end - at - 1);
        const std::size_t video = candidate.find(": Video: ");
        if (video != std::string::npos) line = candidate.substr(video + 9);
        at = end;
    }
    if (line.empty()) return;
    // The second top-level ", "-separated field is the pixel format.
    int depth = 0;
    std::size_t field = 0, start = 0;
    for (std::size_t i = 0; i <= line.size() && field < 2; ++i) {
        if (i < line.size() && line[i] == '(') ++depth;
        if (i < line.size() && line[i] == ')') --depth;
        if (i == line.size() || (depth == 0 && line.compare(i, 2, ", ") == 0)) {
            if (field == 1) {
                const std::string f = line.substr(start, i - start);
                const std::size_t open = f.find('(');
                info.pixel_format = f.substr(0, std::min(open, f.find(' ')));
                if (open == std::string::npos || f.back() != ')') return;
                std::istringstream items(f.substr(open + 1, f.size() - open - 2));
                std::string item;
                while (std::getline(items, item, ',')) {
                    item.erase(0, item.find_first_not_of(' '));
                    if (item == "tv" || item == "pc") info.color_range = item;
                    else if (item.find('/') != std::string::npos) info.color_space = item.substr(0, item.find('/'));
                    else if (item.rfind("bt", 0) == 0 || item.rfind("smpte", 0) == 0 || item == "fcc" ||
                             item == "gbr" || item.rfind("ycgco", 0) == 0 || item == "ictcp")
                        info.color_space = item;
                }
                return;
            }
            ++field;
            start = i + 2;
        }
    }
}

// One frame of `bytes` from the decoder into `frame`. The buffer grows to a
// whole frame only once the first 64 MiB of it have arrived, so dimensions
// from a damaged or hostile listing cost memory only when the decoder really
// delivers that many pixels. False when the output ends first.
// (Float storage: FFmpeg's float frames are read as floats, native ones as bytes.)
bool read_frame(ChildProcess& child, std::vector<float>& frame, std::size_t bytes) {
    constexpr std::size_t first_bytes = std::size_t(64) << 20;
    std::size_t done = 0;
    for (const std::size_t until : {std::min(bytes, first_bytes), bytes}) {
        if (until <= done) continue;
        if (frame.size() * sizeof(float) < until) frame.resize((until + sizeof(float) - 1) / sizeof(float));
        if (!child.read_exact(reinterpret_cast<unsigned char*>(frame.data()) + done, until - done)) return false;
        done = until;
    }
    return true;
}

// Planar float GBR (FFmpeg's own conversion) to interleaved RGB.
void gbr_to_rgb(const float* gbr, std::size_t plane, Image& image) {
    const float* g = gbr;
    const float* b = g + plane;
    const float* r = b + plane;
    for (std::size_t p = 0; p < plane; ++p) {
        image.pixels[p * 3 + 0] = r[p];
        image.pixels[p * 3 + 1] = g[p];
        image.pixels[p * 3 + 2] = b[p];
    }
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
    // At level "info" FFmpeg describes the stream on stderr (pixel format,
    // range, colour space: how to convert the frames).
    std::vector<std::string> argv = ffmpeg_command(path, 0, "info");
    for (const char* a : {"-c", "copy", "-f", "framecrc", "-"}) argv.emplace_back(a);
    ChildProcess child(argv);
    const std::string listing = child.read_all();
    if (child.wait() != 0) fail(path, "read", child);
    VideoInfo info;
    parse_framecrc(listing, info);
    parse_stream_description(child.stderr_text(std::size_t(1) << 18), info);
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
    std::optional<YuvFormat> yuv;  // native frames converted here; else FFmpeg's planar float RGB
    std::vector<float> frame;
    Decoder(const std::vector<std::string>& argv, std::optional<YuvFormat> format)
        : child(argv), yuv(std::move(format)) {}
    std::size_t frame_bytes(const VideoInfo& info) const {
        return yuv ? yuv->frame_bytes() : std::size_t(info.width) * info.height * 3 * sizeof(float);
    }
};

VideoReader::VideoReader(std::string path, int threads)
    : path_(std::move(path)), info_(probe_video(path_)), threads_(threads) {}

VideoReader::~VideoReader() = default;

Image VideoReader::read(int index) {
    if (index < 0 || index >= info_.frame_count)
        throw ArgumentError("frame index " + std::to_string(index) + " is outside the video's " +
                            std::to_string(info_.frame_count) + " frames");
    if (!decoder_ || index < next_) {
        std::optional<YuvFormat> yuv =
            yuv_format(info_.pixel_format, info_.color_range, info_.color_space, info_.width, info_.height);
        std::vector<std::string> argv = ffmpeg_command(path_, threads_);
        for (const std::string& a : {std::string("-f"), std::string("rawvideo"), std::string("-pix_fmt"),
                                    yuv ? yuv->pixel_format : std::string("gbrpf32le"), std::string("-")})
            argv.push_back(a);
        decoder_.reset();
        decoder_ = std::make_unique<Decoder>(argv, std::move(yuv));
        next_ = 0;
    }
    const std::size_t bytes = decoder_->frame_bytes(info_);
    for (; next_ <= index; ++next_) {
        if (!read_frame(decoder_->child, decoder_->frame, bytes)) {
            std::unique_ptr<Decoder> ended = std::move(decoder_);
            if (ended->child.wait() != 0) fail(path_, "decode frame " + std::to_string(next_) + " of", ended->child);
            throw IoError("video '" + path_ + "' ended after " + std::to_string(next_) + " of its " +
                          std::to_string(info_.frame_count) + " frames; the file may be truncated");
        }
    }
    Image image;
    if (decoder_->yuv) {
        yuv_to_rgb(*decoder_->yuv, reinterpret_cast<const unsigned char*>(decoder_->frame.data()), image, threads_);
    } else {
        image = Image(info_.width, info_.height, 3);
        gbr_to_rgb(decoder_->frame.data(), std::size_t(info_.width) * info_.height, image);
    }
    return image;
}

}  // namespace penumbra
