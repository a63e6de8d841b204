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

}  // namespace

bool streams(const MapOptions& options, int width, int height) {
    return is_latlong(options.projection) && options.max_width > 0 && width > options.max_width && height > 0;
}

EnvironmentMap read_environment(const std::string& path, const ColorConfig* config, const std::string& colorspace,
                                const MapOptions& options, const Progress& progress, std::size_t band_bytes,
                                ReadReport* report) {
    if (options.max_width < 0 || (options.max_width > 0 && options.max_width < 4))
        throw ArgumentError("max_width must be 0 (no limit) or at least 4, got " + std::to_string(options.max_width));
    const ImageInfo info = read_image_info(path);  // clear errors for missing, empty or unreadable files
    if (!streams(options, info.width, info.height)) {
        EnvironmentMap map = read_whole(path, config, colorspace, options, progress);
        if (report) *report = ReadReport{false, 1, std::size_t(info.width) * info.height * 3 * sizeof(float)};
        return map;
    }
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw IoError("cannot read '" + path + "' as an image: " + OIIO::geterror());
    const OIIO::ImageSpec spec = in->spec();
    const int W = spec.width, H = spec.height;
    const auto pick = rgb_channels(spec);
    const int ch_begin = *std::min_element(pick.begin(), pick.end());
    const int ch_end = *std::max_element(pick.begin(), pick.end()) + 1;
    const int nch = ch_end - ch_begin;

    EnvironmentMap map;
    map.full_sphere = options.projection == Projection::equirectangular;
    map.width = options.max_width;
    map.height = std::max(1, int(std::lround(double(H) * map.width / W)));
    map.rgb.assign(std::size_t(map.width) * map.height * 3, 0.0f);
    const LatLongSpans spans(W, H, map.width, map.height, map.theta_max());

    // Output rows per band: as many as fit `band_bytes` of input rows (at
    // least one, at most 64, the whole-image path's band).
    std::size_t rows_per_output = 1;
    for (const auto& r : spans.rows) rows_per_output = std::max(rows_per_output, r.weight.size());
    const std::size_t row_bytes = std::size_t(W) * 3 * sizeof(float);
    const int per_band = int(std::clamp<std::size_t>(band_bytes / (rows_per_output * row_bytes), 1, 64));

    std::vector<float> band, raw, tiles;  // held input rows (scene-linear RGB); the file's rows being read
    int band_first = 0, band_end = 0;
    Image fresh;
    double integral = 0.0;
    ReadReport rep;
    rep.streamed = true;
    for (int R0 = 0; R0 < map.height; R0 += per_band) {
        progress.report(double(R0) / map.height);
        const int R1 = std::min(map.height, R0 + per_band);
        const int need_first = spans.rows[R0].first;
        const int need_end = spans.rows[R1 - 1].first + int(spans.rows[R1 - 1].weight.size());
        // Keep the rows the previous band shares with this one.
        const int keep_from = std::max(need_first, band_first);
        const int kept = std::max(0, band_end - keep_from);
        if (kept > 0 && keep_from > band_first)
            std::memmove(band.data(), band.data() + std::size_t(keep_from - band_first) * W * 3,
                         std::size_t(kept) * row_bytes);
        band_first = need_first;
        const int read_first = need_first + kept, n = need_end - read_first;
        band.resize(std::size_t(need_end - need_first) * W * 3);
        if (n > 0) {
            raw.resize(std::size_t(n) * W * nch);
            if (!read_rows(*in, spec, read_first, need_end, ch_begin, ch_end, raw.data(), tiles))
                throw IoError("cannot read rows " + std::to_string(read_first) + ".." + std::to_string(need_end - 1) +
                              " of '" + path + "': " + in->geterror() +
                              "; the file may be truncated or corrupt, re-export it");
            fresh = Image(W, n, 3);
            const std::size_t pixels = std::size_t(W) * n;
            for (std::size_t p = 0; p < pixels; ++p)
                for (int c = 0; c < 3; ++c) fresh.pixels[p * 3 + c] = raw[p * nch + pick[c] - ch_begin];
            if (config) config->to_scene_linear(fresh, colorspace);
            const PixelDefects d = sanitize(fresh, true);
            map.defects.nan += d.nan;
            map.defects.inf += d.inf;
            map.defects.negative += d.negative;
            for (int r = 0; r < n; ++r)
                integral += latlong_row_luminance(options.projection, W, H, read_first + r, fresh.row(r));
            std::memcpy(band.data() + std::size_t(kept) * W * 3, fresh.pixels.data(), fresh.pixels.size() * sizeof(float));
        }
        band_end = need_end;
        rep.buffer_bytes = std::max(rep.buffer_bytes, (band.capacity() + raw.capacity() + fresh.pixels.capacity() +
                                                        tiles.capacity()) *
                                                          sizeof(float));
        ++rep.bands;
        reduce_latlong_rows(spans, band.data(), band_first, W, R0, R1, map, options.threads);
    }
    map.source_integral_luminance = integral;
    if (report) *report = rep;
    return map;
}

LightSource::LightSource(const std::string& path, FrameSourceKind kind) : frames_(open_frames(path, kind)) {
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
    return read_environment(file, config, colorspace, options, progress, std::size_t(16) << 20, report);
}

}  // namespace penumbra::lights
