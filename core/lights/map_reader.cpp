#include "lights/map_reader.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "common/error.hpp"
#include "image/image_io.hpp"
#include "image/video.hpp"

namespace penumbra::lights {

namespace {

// The channels that become R, G, B, chosen as core/image's read_image does:
// grey (1–2 channels) → channel 0 three times; else the channels named R,
// G, B when all three exist, otherwise the first three.
std::array<int, 3> rgb_channels(const OIIO::ImageSpec& spec) {
    if (spec.nchannels <= 2) return {0, 0, 0};
    std::array<int, 3> picked{0, 1, 2};
    const char* names[3] = {"R", "G", "B"};
    for (int k = 0; k < 3; ++k) {
        auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), names[k]);
        if (it == spec.channelnames.end()) return {0, 1, 2};
        picked[k] = int(it - spec.channelnames.begin());
    }
    return picked;
}

// Rows [y0, y1) of the data window, channels [ch_begin, ch_end), as float.
// Tiled files are read by whole tile rows (OpenImageIO 2.4's read_scanlines
// divides by zero on tiled files) into `tiles`, then the rows are copied.
bool read_rows(OIIO::ImageInput& in, const OIIO::ImageSpec& spec, int y0, int y1, int ch_begin, int ch_end,
               float* out, std::vector<float>& tiles) {
    const int nch = ch_end - ch_begin;
    if (spec.tile_width <= 0)
        return in.read_scanlines(0, 0, spec.y + y0, spec.y + y1, spec.z, ch_begin, ch_end, OIIO::TypeDesc::FLOAT, out);
    const int th = spec.tile_height;
    const int t0 = y0 / th * th, t1 = std::min(spec.height, (y1 + th - 1) / th * th);
    const std::size_t row = std::size_t(spec.width) * nch;
    tiles.resize(std::size_t(t1 - t0) * row);
    if (!in.read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + t0, spec.y + t1, spec.z,
                       spec.z + std::max(1, spec.tile_depth), ch_begin, ch_end, OIIO::TypeDesc::FLOAT, tiles.data()))
        return false;
    std::memcpy(out, tiles.data() + std::size_t(y0 - t0) * row, std::size_t(y1 - y0) * row * sizeof(float));
    return true;
}

EnvironmentMap read_whole(const std::string& path, const ColorConfig* config, const std::string& colorspace,
                          const MapOptions& options, const Progress& progress) {
    Image image = read_image(path);
    if (config) config->to_scene_linear(image, colorspace);
    return make_environment(image, options, progress);
}

// An image file's rows, read top to bottom as scene-linear RGB: each row is
// picked to R, G, B, converted, sanitized (counted in `defects`) and added to
// `integral` (Σ Y·Ω with the projection's own Jacobian) once, when it is
// read, exactly as make_environment treats the whole image.
class RowStream {
public:
    RowStream(const std::string& path, const ColorConfig* config, const std::string& colorspace,
              const MapOptions& options)
        : path_(path), config_(config), colorspace_(colorspace), options_(options) {
        in_ = OIIO::ImageInput::open(path);
        if (!in_) throw IoError("cannot read '" + path + "' as an image: " + OIIO::geterror());
        spec_ = in_->spec();
        pick_ = rgb_channels(spec_);
        ch_begin_ = *std::min_element(pick_.begin(), pick_.end());
        ch_end_ = *std::max_element(pick_.begin(), pick_.end()) + 1;
    }
    int width() const { return spec_.width; }
    int height() const { return spec_.height; }

    // Holds input rows [first, end) at rows(): keeps those already held,
    // reads the rest. Neither bound may move back, and `first` may not pass
    // the rows read so far (each row is read, counted and integrated once).
    void hold(int first, int end) {
        const int W = width();
        if (first < first_ || end < end_ || first > end_ || first > end)
            throw Error("internal: rows [" + std::to_string(first) + ", " + std::to_string(end) + ") after [" +
                        std::to_string(first_) + ", " + std::to_string(end_) + ") of '" + path_ + "'");
        const std::size_t row_floats = std::size_t(W) * 3;
        const int kept = end_ - first;
        if (kept > 0 && first > first_)
            std::memmove(band_.data(), band_.data() + std::size_t(first - first_) * row_floats,
                         std::size_t(kept) * row_floats * sizeof(float));
        band_.resize(std::size_t(end - first) * row_floats);
        if (end > end_) read(end_, end, band_.data() + std::size_t(kept) * row_floats);
        first_ = first;
        end_ = end;
    }
    const float* rows() const { return band_.data(); }
    PixelDefects defects;
    double integral = 0.0;
    // The pixel buffers held now: the rows, the file's rows and one converted copy.
    std::size_t buffer_bytes() const {
        return (band_.capacity() + raw_.capacity() + fresh_.pixels.capacity() + tiles_.capacity()) * sizeof(float);
    }

private:
    // Rows [y0, y1) of the file into `out` (RGB), converted and sanitized.
    void read(int y0, int y1, float* out) {
        const int W = width(), n = y1 - y0, nch = ch_end_ - ch_begin_;
        raw_.resize(std::size_t(n) * W * nch);
        if (!read_rows(*in_, spec_, y0, y1, ch_begin_, ch_end_, raw_.data(), tiles_))
            throw IoError("cannot read rows " + std::to_string(y0) + ".." + std::to_string(y1 - 1) + " of '" + path_ +
                          "': " + in_->geterror() + "; the file may be truncated or corrupt, re-export it");
        fresh_ = Image(W, n, 3);
        const std::size_t pixels = std::size_t(W) * n;
        for (std::size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) fresh_.pixels[p * 3 + c] = raw_[p * nch + pick_[c] - ch_begin_];
        if (config_) config_->to_scene_linear(fresh_, colorspace_);
        const PixelDefects d = sanitize(fresh_, true);
        defects.nan += d.nan;
        defects.inf += d.inf;
        defects.negative += d.negative;
        for (int r = 0; r < n; ++r) integral += input_row_luminance(options_, W, height(), y0 + r, fresh_.row(r));
        std::memcpy(out, fresh_.pixels.data(), fresh_.pixels.size() * sizeof(float));
    }

    std::string path_;
    const ColorConfig* config_;
    std::string colorspace_;
    MapOptions options_;
    std::unique_ptr<OIIO::ImageInput> in_;
    OIIO::ImageSpec spec_;
    std::array<int, 3> pick_{};
    int ch_begin_ = 0, ch_end_ = 0;
    std::vector<float> band_, raw_, tiles_;  // held rows (scene-linear RGB); the file's rows being read
    Image fresh_;
    int first_ = 0, end_ = 0;  // rows held: [first_, end_)
};

// Lat-long input: reduced output band by output band (as many output rows
// as fit `band_bytes` of input rows, at least one, at most 64, the
// whole-image path's band), keeping the input rows neighbouring bands share.
EnvironmentMap stream_latlong(RowStream& stream, const MapOptions& options, const Progress& progress,
                              std::size_t band_bytes, ReadReport& report) {
    const int W = stream.width(), H = stream.height();
    EnvironmentMap map;
    map.full_sphere = options.projection == Projection::equirectangular;
    map.width = options.max_width;
    map.height = std::max(1, int(std::lround(double(H) * map.width / W)));
    map.rgb.assign(std::size_t(map.width) * map.height * 3, 0.0f);
    const LatLongSpans spans(W, H, map.width, map.height, map.theta_max());
    std::size_t rows_per_output = 1;
    for (const auto& r : spans.rows) rows_per_output = std::max(rows_per_output, r.weight.size());
    const std::size_t row_bytes = std::size_t(W) * 3 * sizeof(float);
    const int per_band = int(std::clamp<std::size_t>(band_bytes / (rows_per_output * row_bytes), 1, 64));
    for (int R0 = 0; R0 < map.height; R0 += per_band) {
        progress.report(double(R0) / map.height);
        const int R1 = std::min(map.height, R0 + per_band);
        const int need_first = spans.rows[R0].first;
        const int need_end = spans.rows[R1 - 1].first + int(spans.rows[R1 - 1].weight.size());
        stream.hold(need_first, need_end);
        report.buffer_bytes = std::max(report.buffer_bytes, stream.buffer_bytes());
        ++report.bands;
        reduce_latlong_rows(spans, stream.rows(), need_first, W, R0, R1, map, options.threads);
    }
    return map;
}

// Fisheye and mirror ball: bands of as many input rows as fit `band_bytes`,
// each handing its look-ups to the resampler (environment.hpp).
EnvironmentMap stream_resampled(RowStream& stream, const MapOptions& options, const Progress& progress,
                                std::size_t band_bytes, ReadReport& report) {
    const int W = stream.width(), H = stream.height();
    const std::size_t row_bytes = std::size_t(W) * 3 * sizeof(float);
    const int band_rows = int(std::clamp<std::size_t>(band_bytes / row_bytes, 1, std::size_t(H)));
    BandResampler resampler(options, W, H, band_rows);
    for (int band = 0; band < resampler.band_count(); ++band) {
        progress.report(double(band) / resampler.band_count());
        stream.hold(resampler.first_row(band), resampler.end_row(band));
        report.buffer_bytes = std::max(report.buffer_bytes, stream.buffer_bytes() + resampler.buffer_bytes());
        ++report.bands;
        resampler.add_band(band, stream.rows());
    }
    return resampler.finish();
}

}  // namespace

bool streams(const MapOptions& options, int width, int height) {
    return options.max_width > 0 && width > options.max_width && height > 0;
}

EnvironmentMap read_environment(const std::string& path, const ColorConfig* config, const std::string& colorspace,
                                const MapOptions& options, const Progress& progress, std::size_t band_bytes,
                                ReadReport* report) {
    check_map_options(options);
    const ImageInfo info = read_image_info(path);  // clear errors for missing, empty or unreadable files
    if (!streams(options, info.width, info.height)) {
        EnvironmentMap map = read_whole(path, config, colorspace, options, progress);
        if (report) *report = ReadReport{false, 1, std::size_t(info.width) * info.height * 3 * sizeof(float)};
        return map;
    }
    RowStream stream(path, config, colorspace, options);
    ReadReport rep;
    rep.streamed = true;
    EnvironmentMap map = is_latlong(options.projection) ? stream_latlong(stream, options, progress, band_bytes, rep)
                                                        : stream_resampled(stream, options, progress, band_bytes, rep);
    map.defects = stream.defects;
    map.source_integral_luminance = stream.integral;
    if (report) *report = rep;
    return map;
}

LightSource::LightSource(const std::string& path, FrameSourceKind kind, std::size_t band_bytes)
    : frames_(open_frames(path, kind)), band_bytes_(band_bytes) {
    if (kind == FrameSourceKind::video || (kind == FrameSourceKind::automatic && is_video_file(path))) return;
    if (frames_->frame_count() == 1) {
        files_ = {path};
    } else {
        SequenceFiles seq = find_sequence(path);
        if (int(seq.paths.size()) == frames_->frame_count()) files_ = std::move(seq.paths);
    }
}

EnvironmentMap LightSource::read_map(int index, const ColorConfig* config, const std::string& colorspace,
                                     const MapOptions& options, const Progress& progress, ReadReport* report) const {
    if (index < 0 || index >= frames_->frame_count())
        throw ArgumentError("frame index " + std::to_string(index) + " is outside the source's " +
                            std::to_string(frames_->frame_count()) + " frames");
    if (files_.empty() || !streams(options, frames_->width(), frames_->height())) {
        Image image = frames_->read(index);  // checks the frame's size
        if (config) config->to_scene_linear(image, colorspace);
        if (report) *report = ReadReport{false, 1, image.pixels.size() * sizeof(float)};
        return make_environment(image, options, progress);
    }
    const std::string& file = files_[index];
    const ImageInfo info = read_image_info(file);
    if (info.width != frames_->width() || info.height != frames_->height())
        throw IoError("frame '" + file + "' is " + std::to_string(info.width) + "x" + std::to_string(info.height) +
                      " but the first frame is " + std::to_string(frames_->width()) + "x" +
                      std::to_string(frames_->height()) + "; every frame of a sequence or video must have the same size");
    return read_environment(file, config, colorspace, options, progress, band_bytes_, report);
}

}  // namespace penumbra::lights
