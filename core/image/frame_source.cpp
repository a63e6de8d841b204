#include "image/frame_source.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <regex>

#include "common/error.hpp"
#include "image/image_io.hpp"
#include "image/video.hpp"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct NamePattern {
    std::string prefix, suffix;
    int digits = 0;
    int number = 0;
};

bool split_frame_number(const std::string& filename, NamePattern& out) {
    static const std::regex re(R"(^(.*?)(\d+)(\.[^.]+)$)");
    std::smatch m;
    if (!std::regex_match(filename, m, re))
        return false;
    // A run of digits too large for an int (a date, an ID) is no frame number.
    const std::string digits = m[2];
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), out.number);
    if (error != std::errc() || end != digits.data() + digits.size())
        return false;
    out.prefix = m[1];
    out.digits = static_cast<int>(digits.size());
    out.suffix = m[3];
    return true;
}

std::string frame_name(const NamePattern& p, int number) {
    std::string digits = std::to_string(number);
    if (static_cast<int>(digits.size()) < p.digits)
        digits.insert(0, p.digits - digits.size(), '0');
    return p.prefix + digits + p.suffix;
}

void check_size(const Image& image, int width, int height, const std::string& what) {
    if (image.width != width || image.height != height)
        throw IoError(what + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                      " but the first frame is " + std::to_string(width) + "x" + std::to_string(height) +
                      "; every frame of a sequence or video must have the same size");
}

class SingleImage final : public FrameSource {
public:
    explicit SingleImage(std::string path) : path_(std::move(path)), info_(read_image_info(path_)) {}
    int frame_count() const override { return 1; }
    int width() const override { return info_.width; }
    int height() const override { return info_.height; }
    double frames_per_second() const override { return 0.0; }
    Image read(int index) const override {
        if (index != 0)
            throw ArgumentError("a single image has only frame 0, not " + std::to_string(index));
        return read_image(path_);
    }
    std::string describe() const override { return "image '" + path_ + "'"; }

private:
    std::string path_;
    ImageInfo info_;
};

class ImageSequence final : public FrameSource {
public:
    explicit ImageSequence(SequenceFiles files) : files_(std::move(files)) {
        const ImageInfo first = read_image_info(files_.paths.front());
        width_ = first.width;
        height_ = first.height;
    }
    int frame_count() const override { return static_cast<int>(files_.paths.size()); }
    int width() const override { return width_; }
    int height() const override { return height_; }
    double frames_per_second() const override { return 0.0; }
    Image read(int index) const override {
        if (index < 0 || index >= frame_count())
            throw ArgumentError("frame index " + std::to_string(index) + " is outside the sequence's " +
                                std::to_string(frame_count()) + " frames");
        Image image = read_image(files_.paths[index]);
        check_size(image, width_, height_, "frame '" + files_.paths[index] + "'");
        return image;
    }
    std::string describe() const override {
        return "sequence of " + std::to_string(frame_count()) + " frames from '" + files_.paths.front() + "'";
    }

private:
    SequenceFiles files_;
    int width_ = 0, height_ = 0;
};

class VideoFile final : public FrameSource {
public:
    explicit VideoFile(std::string path) : path_(std::move(path)), reader_(path_) {}
    int frame_count() const override { return reader_.info().frame_count; }
    int width() const override { return reader_.info().width; }
    int height() const override { return reader_.info().height; }
    double frames_per_second() const override { return reader_.info().frames_per_second; }
    Image read(int index) const override { return reader_.read(index); }
    std::string describe() const override {
        return "video '" + path_ + "' (" + std::to_string(frame_count()) + " frames)";
    }

private:
    std::string path_;
    mutable VideoReader reader_;  // decodes in order: reading advances it
};

}  // namespace

SequenceFiles find_sequence(const std::string& first_frame) {
    const fs::path path(first_frame);
    NamePattern pattern;
    if (!split_frame_number(path.filename().string(), pattern))
        throw IoError("'" + first_frame + "' has no frame number in its name; name frames like frame_0001.exr");
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw IoError("folder '" + folder.string() + "' of the sequence does not exist");

    std::vector<int> numbers;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        NamePattern p;
        if (split_frame_number(entry.path().filename().string(), p) && p.prefix == pattern.prefix &&
            p.suffix == pattern.suffix && p.digits == pattern.digits && p.number >= pattern.number)
            numbers.push_back(p.number);
    }
    if (numbers.empty() || std::find(numbers.begin(), numbers.end(), pattern.number) == numbers.end())
        throw IoError("first frame '" + first_frame + "' not found");
    std::sort(numbers.begin(), numbers.end());

    std::vector<std::string> missing;
    for (std::size_t i = 1; i < numbers.size(); ++i)
        for (int n = numbers[i - 1] + 1; n < numbers[i] && missing.size() < 10; ++n)
            missing.push_back(frame_name(pattern, n));
    if (!missing.empty()) {
        std::string list;
        for (const auto& m : missing)
            list += (list.empty() ? "" : ", ") + m;
        throw IoError("the sequence starting at '" + first_frame + "' has missing frames: " + list +
                      "; re-render them or choose a frame range without gaps");
    }

    SequenceFiles files;
    for (int n : numbers) {
        files.paths.push_back((folder / frame_name(pattern, n)).string());
        files.numbers.push_back(n);
    }
    return files;
}

std::unique_ptr<FrameSource> open_frames(const std::string& path, FrameSourceKind kind) {
    switch (kind) {
    case FrameSourceKind::single_image:
        return std::make_unique<SingleImage>(path);
    case FrameSourceKind::sequence:
        return std::make_unique<ImageSequence>(find_sequence(path));
    case FrameSourceKind::video:
        return std::make_unique<VideoFile>(path);
    case FrameSourceKind::automatic:
        break;
    }
    if (is_video_file(path))
        return std::make_unique<VideoFile>(path);
    NamePattern pattern;
    if (split_frame_number(fs::path(path).filename().string(), pattern)) {
        SequenceFiles files = find_sequence(path);
        if (files.paths.size() > 1)
            return std::make_unique<ImageSequence>(std::move(files));
    }
    return std::make_unique<SingleImage>(path);
}

}  // namespace penumbra
