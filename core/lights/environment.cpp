#include "lights/environment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "common/parallel.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

// RGB copy of a 1–4 channel image: grey copied to R, G, B; alpha dropped.
Image to_rgb(const Image& in) {
    if (in.channels == 3) return in;
    Image out(in.width, in.height, 3);
    for (std::size_t p = 0; p < in.pixel_count(); ++p) {
        const float* src = in.pixels.data() + p * in.channels;
        float* dst = out.pixels.data() + p * 3;
        if (in.channels <= 2) {
            dst[0] = dst[1] = dst[2] = src[0];
        } else {
            dst[0] = src[0]; dst[1] = src[1]; dst[2] = src[2];
        }
    }
    return out;
}

// The input row a look-up at continuous row position y reads first (pixel
// centres at +0.5, clamped to the image): the band that holds it takes it.
int lookup_top_row(double y, int height) { return int(std::clamp(y - 0.5, 0.0, double(height - 1))); }

// Bilinear look-up at continuous position (x, y), pixel centres at +0.5,
// clamped to the image, from RGB rows held from input row `first` on.
void bilinear(const float* rows, int first, int width, int height, double x, double y, double out[3]) {
    const double fx = std::clamp(x - 0.5, 0.0, double(width - 1));
    const double fy = std::clamp(y - 0.5, 0.0, double(height - 1));
    const int x0 = int(fx), y0 = int(fy);
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const double ax = fx - x0, ay = fy - y0;
    const float* top = rows + std::size_t(y0 - first) * width * 3;
    const float* bottom = rows + std::size_t(y1 - first) * width * 3;
    for (int c = 0; c < 3; ++c)
        out[c] = (1 - ay) * ((1 - ax) * top[x0 * 3 + c] + ax * top[x1 * 3 + c]) +
                 ay * ((1 - ax) * bottom[x0 * 3 + c] + ax * bottom[x1 * 3 + c]);
}

}  // namespace

LatLongSpans::LatLongSpans(int in_width, int in_height, int out_width, int out_height, double theta_max) {
    const int W = in_width, H = in_height, w = out_width, h = out_height;
    // Column overlaps: output column C covers input x ∈ [C·W/w, (C+1)·W/w).
    columns.resize(w);
    rows.resize(h);
    for (int C = 0; C < w; ++C) {
        const double a = double(C) * W / w, b = double(C + 1) * W / w;
        columns[C].first = int(std::floor(a));
        for (int c = columns[C].first; c < W && c < b; ++c)
            columns[C].weight.push_back(std::min<double>(b, c + 1) - std::max<double>(a, c));
    }
    for (int R = 0; R < h; ++R) {
        const double a = double(R) * H / h, b = double(R + 1) * H / h;
        rows[R].first = int(std::floor(a));
        for (int r = rows[R].first; r < H && r < b; ++r) {
            const double t0 = latlong::theta_of_y(std::max<double>(a, r), H, theta_max);
            const double t1 = latlong::theta_of_y(std::min<double>(b, r + 1), H, theta_max);
            rows[R].weight.push_back(std::cos(t0) - std::cos(t1));
        }
    }
}

void reduce_latlong_rows(const LatLongSpans& spans, const float* band, int band_first_row, int in_width,
                         int row_begin, int row_end, EnvironmentMap& out, int threads) {
    const int W = in_width, w = out.width;
    parallel_for(std::size_t(row_end - row_begin), {threads, 2, "lights.map_rows"},
                 [&](std::size_t b, std::size_t e) {
        std::vector<double> row_sum(std::size_t(W) * 3);
        for (int R = row_begin + int(b); R < row_begin + int(e); ++R) {
            const auto& row = spans.rows[R];
            std::fill(row_sum.begin(), row_sum.end(), 0.0);
            double wsum = 0.0;
            for (std::size_t k = 0; k < row.weight.size(); ++k) {
                const float* src = band + std::size_t(row.first + int(k) - band_first_row) * W * 3;
                const double wr = row.weight[k];
                wsum += wr;
                for (std::size_t i = 0; i < std::size_t(W) * 3; ++i) row_sum[i] += wr * src[i];
            }
            for (int C = 0; C < w; ++C) {
                const auto& col = spans.columns[C];
                double acc[3] = {0, 0, 0}, cw = 0.0;
                for (std::size_t k = 0; k < col.weight.size(); ++k) {
                    const double wc = col.weight[k];
                    cw += wc;
                    for (int ch = 0; ch < 3; ++ch) acc[ch] += wc * row_sum[(col.first + k) * 3 + ch];
                }
                float* dst = out.rgb.data() + (std::size_t(R) * w + C) * 3;
                for (int ch = 0; ch < 3; ++ch) dst[ch] = float(acc[ch] / (cw * wsum));
            }
        }
    });
}

double input_row_luminance(const MapOptions& options, int in_width, int in_height, int row, const float* rgb) {
    const auto& Y = rec709_luminance;
    double row_sum = 0.0;
    if (is_latlong(options.projection)) {
        // One solid angle for the whole row.
        const double omega = pixel_solid_angle(options.projection, {}, in_width, in_height, 0, row);
        if (omega == 0.0) return 0.0;
        for (int c = 0; c < in_width; ++c)
            row_sum += omega * (Y[0] * rgb[3 * c] + Y[1] * rgb[3 * c + 1] + Y[2] * rgb[3 * c + 2]);
        return row_sum;
    }
    for (int c = 0; c < in_width; ++c) {
        const double omega = pixel_solid_angle(options.projection, options.lens, in_width, in_height, c, row);
        if (omega == 0.0) continue;
        row_sum += omega * (Y[0] * rgb[3 * c] + Y[1] * rgb[3 * c + 1] + Y[2] * rgb[3 * c + 2]);
    }
    return row_sum;
}

void check_map_options(const MapOptions& options) {
    if (options.max_width < 0 || (options.max_width > 0 && options.max_width < 4))
        throw ArgumentError("max_width must be 0 (no limit) or at least 4, got " + std::to_string(options.max_width));
    if (options.supersampling < 1 || options.supersampling > 16)
        throw ArgumentError("supersampling must be between 1 and 16, got " + std::to_string(options.supersampling));
    if (options.projection == Projection::fisheye) options.lens.check();
}

double EnvironmentMap::theta_max() const { return full_sphere ? latlong::full_sphere : latlong::upper_hemisphere; }
double EnvironmentMap::theta_edge(int row) const { return latlong::theta_of_y(row, height, theta_max()); }
double EnvironmentMap::solid_angle(int row) const {
    return latlong::pixel_solid_angle(row, height, width, theta_max());
}
Eigen::Vector3d EnvironmentMap::direction(int row, int column) const {
    return latlong::pixel_direction(row, column, height, width, theta_max());
}

namespace {

void check_map_input(const Image& radiance, const MapOptions& options) {
    if (radiance.empty() || radiance.pixels.size() != radiance.pixel_count() * std::size_t(radiance.channels))
        throw ArgumentError("the environment image is empty (" + std::to_string(radiance.width) + "x" +
                            std::to_string(radiance.height) + "); give an image with pixels");
    if (radiance.channels < 1 || radiance.channels > 4)
        throw ArgumentError("the environment image needs 1 to 4 channels, got " + std::to_string(radiance.channels));
    check_map_options(options);
}

// Σ Y·Ω over the input's pixels, each with its own projection's solid angle.
double input_integral_luminance(const Image& in, const MapOptions& options) {
    double sum = 0.0;
    for (int r = 0; r < in.height; ++r) sum += input_row_luminance(options, in.width, in.height, r, in.row(r));
    return sum;
}

// Equirectangular and polar input: the grid itself, or averaged down to
// max_width columns (energy-exact), 64 output rows per progress report.
void reduce_latlong(Image& in, const MapOptions& options, const Progress& progress, EnvironmentMap& map) {
    const int limit = options.max_width;
    map.full_sphere = options.projection == Projection::equirectangular;
    if (limit == 0 || in.width <= limit) {
        map.width = in.width;
        map.height = in.height;
        map.rgb = std::move(in.pixels);
        return;
    }
    map.width = limit;
    map.height = std::max(1, int(std::lround(double(in.height) * limit / in.width)));
    map.rgb.assign(std::size_t(map.width) * map.height * 3, 0.0f);
    const LatLongSpans spans(in.width, in.height, map.width, map.height, map.theta_max());
    for (int R0 = 0; R0 < map.height; R0 += 64) {
        progress.report(double(R0) / map.height);
        reduce_latlong_rows(spans, in.pixels.data(), 0, in.width, R0, std::min(map.height, R0 + 64), map,
                            options.threads);
    }
}

// The grid a fisheye (hemisphere, 4H × H, H ≈ the image-circle radius) or
// mirror ball (sphere, 2H × H, H ≈ πR/2) is resampled to, and the look-ups
// per cell side; a grid wider than max_width is narrowed and supersampled
// more instead.
struct ResampleGrid {
    int width, height, supersampling;
};

ResampleGrid resample_grid(int in_width, int in_height, const MapOptions& options, bool full_sphere) {
    const double radius = 0.5 * std::min(in_width, in_height);
    const int aspect = full_sphere ? 2 : 4;
    int h = full_sphere ? int(std::ceil(0.5 * pi * radius)) : int(std::ceil(radius));
    h = std::max(h, 4);
    int w = aspect * h;
    int ss = options.supersampling;
    const int limit = options.max_width;
    if (limit > 0 && w > limit) {
        ss = std::min(16, int(std::ceil(double(ss) * w / limit)));
        h = std::max(1, limit / aspect);
        w = aspect * h;
    }
    return {w, h, ss};
}

}  // namespace

// Calls look_up(x, y) for each of the ss² look-ups of output cell (r, c)
// that land inside the image circle (the others count as black), in the
// same order every time: the index pass and the band passes must agree on
// every position.
template <class LookUp>
void BandResampler::for_each_look_up(int r, int c, LookUp&& look_up) const {
    const int ss = supersampling_;
    for (int j = 0; j < ss; ++j) {
        const double sin_theta = sub_row_sin_[std::size_t(r) * ss + j], cos_theta = sub_row_cos_[std::size_t(r) * ss + j];
        for (int i = 0; i < ss; ++i) {
            const Eigen::Vector3d d(sin_theta * sub_column_cos_[std::size_t(c) * ss + i],
                                    sin_theta * sub_column_sin_[std::size_t(c) * ss + i], cos_theta);
            double x, y;
            if (direction_to_image(options_.projection, options_.lens, in_width_, in_height_, d, x, y)) look_up(x, y);
        }
    }
}

BandResampler::BandResampler(const MapOptions& options, int in_width, int in_height, int band_rows)
    : options_(options), in_width_(in_width), in_height_(in_height) {
    if (is_latlong(options.projection)) throw ArgumentError("BandResampler is for fisheye and mirror-ball input");
    if (in_width < 1 || in_height < 1) throw ArgumentError("the environment image is empty");
    check_map_options(options);
    band_rows_ = std::clamp(band_rows, 1, in_height);
    band_count_ = (in_height + band_rows_ - 1) / band_rows_;
    map_.full_sphere = options.projection == Projection::mirror_ball;
    const ResampleGrid grid = resample_grid(in_width, in_height, options, map_.full_sphere);
    map_.width = grid.width;
    map_.height = grid.height;
    supersampling_ = grid.supersampling;
    map_.rgb.assign(std::size_t(map_.width) * map_.height * 3, 0.0f);
    // sin and cos of every look-up's θ (per output row) and φ (per output
    // column): the same values direction_of_angles computes, once each.
    const int ss = supersampling_;
    sub_row_sin_.resize(std::size_t(map_.height) * ss);
    sub_row_cos_.resize(sub_row_sin_.size());
    for (int r = 0; r < map_.height; ++r) {
        const double t0 = latlong::theta_of_y(r, map_.height, map_.theta_max());
        const double t1 = latlong::theta_of_y(r + 1, map_.height, map_.theta_max());
        for (int j = 0; j < ss; ++j) {
            // Sub-rows equally spaced in cos θ, so each look-up stands for
            // the same solid angle.
            const double z = std::cos(t0) + (std::cos(t1) - std::cos(t0)) * (j + 0.5) / ss;
            const double theta = std::acos(std::clamp(z, -1.0, 1.0));
            sub_row_sin_[std::size_t(r) * ss + j] = std::sin(theta);
            sub_row_cos_[std::size_t(r) * ss + j] = std::cos(theta);
        }
    }
    sub_column_sin_.resize(std::size_t(map_.width) * ss);
    sub_column_cos_.resize(sub_column_sin_.size());
    for (int c = 0; c < map_.width; ++c)
        for (int i = 0; i < ss; ++i) {
            const double phi = latlong::phi_of_x(c + (i + 0.5) / ss, map_.width);
            sub_column_sin_[std::size_t(c) * ss + i] = std::sin(phi);
            sub_column_cos_[std::size_t(c) * ss + i] = std::cos(phi);
        }
    if (band_count_ == 1) return;

    // Index: per cell the first and last band its look-ups start in, then
    // per band the cells (a cell near a mirror ball's rim can span many).
    const std::size_t cells = std::size_t(map_.width) * map_.height;
    if (cells > std::numeric_limits<std::uint32_t>::max())
        throw ArgumentError("the working grid is too large to stream; set max_width");
    std::vector<int> lo(cells), hi(cells);
    parallel_for(std::size_t(map_.height), {options_.threads, 1, "lights.map_resample_index"},
                 [&](std::size_t b, std::size_t e) {
        for (int r = int(b); r < int(e); ++r)
            for (int c = 0; c < map_.width; ++c) {
                const std::size_t cell = std::size_t(r) * map_.width + c;
                int first = band_count_, last = -1;
                for_each_look_up(r, c, [&](double, double y) {
                    const int band = lookup_top_row(y, in_height_) / band_rows_;
                    first = std::min(first, band);
                    last = std::max(last, band);
                });
                lo[cell] = first;
                hi[cell] = last;
            }
    });
    band_offsets_.assign(std::size_t(band_count_) + 1, 0);
    for (std::size_t cell = 0; cell < cells; ++cell)
        for (int band = lo[cell]; band <= hi[cell]; ++band) ++band_offsets_[band + 1];
    for (int band = 0; band < band_count_; ++band) band_offsets_[band + 1] += band_offsets_[band];
    band_cells_.resize(band_offsets_.back());
    std::vector<std::size_t> next(band_offsets_.begin(), band_offsets_.end() - 1);
    for (std::size_t cell = 0; cell < cells; ++cell)
        for (int band = lo[cell]; band <= hi[cell]; ++band) band_cells_[next[band]++] = std::uint32_t(cell);
    sum_.assign(cells * 3, 0.0);
}

int BandResampler::end_row(int band) const { return std::min(in_height_, (band + 1) * band_rows_ + 1); }

void BandResampler::add_cells(const std::uint32_t* cells, std::size_t count, const float* rows, int first,
                              int end) {
    // Look-ups starting in rows [first, end) (this band's own rows).
    parallel_for(count, {options_.threads, 256, "lights.map_resample"}, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
            const std::uint32_t cell = cells[k];
            const int r = int(cell / std::uint32_t(map_.width)), c = int(cell % std::uint32_t(map_.width));
            double acc[3] = {0, 0, 0};
            for_each_look_up(r, c, [&](double x, double y) {
                const int top = lookup_top_row(y, in_height_);
                if (top < first || top >= end) return;
                double v[3];
                bilinear(rows, first, in_width_, in_height_, x, y, v);
                for (int ch = 0; ch < 3; ++ch) acc[ch] += v[ch];
            });
            for (int ch = 0; ch < 3; ++ch) sum_[std::size_t(cell) * 3 + ch] += acc[ch];
        }
    });
}

void BandResampler::add_band(int band, const float* rows, const Progress& progress) {
    if (band < 0 || band >= band_count_) throw ArgumentError("band " + std::to_string(band) + " is out of range");
    const int w = map_.width, h = map_.height;
    const double n = double(supersampling_) * supersampling_;
    if (band_count_ > 1) {
        const std::size_t begin = band_offsets_[band], end = band_offsets_[band + 1];
        add_cells(band_cells_.data() + begin, end - begin, rows, first_row(band), first_row(band) + band_rows_);
        return;
    }
    // The whole image: each cell's mean straight into the map, in bands of
    // 64 output rows (one progress report each).
    for (int R0 = 0; R0 < h; R0 += 64) {
        progress.report(double(R0) / h);
        parallel_for(std::size_t(std::min(64, h - R0)), {options_.threads, 1, "lights.map_resample"},
                     [&](std::size_t b, std::size_t e) {
            for (int r = R0 + int(b); r < R0 + int(e); ++r)
                for (int c = 0; c < w; ++c) {
                    double acc[3] = {0, 0, 0};
                    for_each_look_up(r, c, [&](double x, double y) {
                        double v[3];
                        bilinear(rows, 0, in_width_, in_height_, x, y, v);
                        for (int ch = 0; ch < 3; ++ch) acc[ch] += v[ch];
                    });
                    float* dst = map_.rgb.data() + (std::size_t(r) * w + c) * 3;
                    for (int ch = 0; ch < 3; ++ch) dst[ch] = float(acc[ch] / n);
                }
        });
    }
}

EnvironmentMap BandResampler::finish() {
    const double n = double(supersampling_) * supersampling_;
    if (band_count_ > 1)
        for (std::size_t i = 0; i < sum_.size(); ++i) map_.rgb[i] = float(sum_[i] / n);
    sum_ = {};
    sub_row_sin_ = sub_row_cos_ = sub_column_sin_ = sub_column_cos_ = {};
    band_cells_ = {};
    band_offsets_ = {};
    return std::move(map_);
}

std::size_t BandResampler::buffer_bytes() const {
    return band_offsets_.capacity() * sizeof(std::size_t) + band_cells_.capacity() * sizeof(std::uint32_t) +
           (sum_.capacity() + sub_row_sin_.capacity() + sub_row_cos_.capacity() + sub_column_sin_.capacity() +
            sub_column_cos_.capacity()) * sizeof(double);
}

EnvironmentMap make_environment(const Image& radiance, const MapOptions& options, const Progress& progress) {
    check_map_input(radiance, options);
    Image in = to_rgb(radiance);
    EnvironmentMap map;
    map.defects = sanitize(in, true);
    map.source_integral_luminance = input_integral_luminance(in, options);
    if (is_latlong(options.projection)) {
        reduce_latlong(in, options, progress, map);
        return map;
    }
    BandResampler resampler(options, in.width, in.height, in.height);
    resampler.add_band(0, in.pixels.data(), progress);
    EnvironmentMap resampled = resampler.finish();
    resampled.defects = map.defects;
    resampled.source_integral_luminance = map.source_integral_luminance;
    return resampled;
}

Eigen::Vector3d integral_rgb(const EnvironmentMap& map) {
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (int r = 0; r < map.height; ++r) {
        Eigen::Vector3d row = Eigen::Vector3d::Zero();
        for (int c = 0; c < map.width; ++c) {
            const float* p = map.pixel(r, c);
            row += Eigen::Vector3d(p[0], p[1], p[2]);
        }
        total += map.solid_angle(r) * row;
    }
    return total;
}

double integral_luminance(const EnvironmentMap& map, const std::array<double, 3>& y) {
    const Eigen::Vector3d rgb = integral_rgb(map);
    return y[0] * rgb[0] + y[1] * rgb[1] + y[2] * rgb[2];
}

Image rotate_equirectangular_z(const Image& image, double angle) {
    if (image.empty()) throw ArgumentError("cannot rotate an empty image");
    // Content at φ moves to φ + angle; column x ↔ φ = π − 2π x/W
    // (latlong::phi_of_x), so the new column x takes the old column x + angle·W/2π.
    Image out(image.width, image.height, image.channels);
    const double shift = angle * image.width / (2.0 * pi);
    for (int x = 0; x < image.width; ++x) {
        double src = x + shift;
        src -= std::floor(src / image.width) * image.width;
        const int x0 = int(std::floor(src)) % image.width;
        const int x1 = (x0 + 1) % image.width;
        const double a = src - std::floor(src);
        for (int y = 0; y < image.height; ++y)
            for (int c = 0; c < image.channels; ++c)
                out.at(x, y, c) = float((1 - a) * image.at(x0, y, c) + a * image.at(x1, y, c));
    }
    return out;
}

}  // namespace penumbra::lights
