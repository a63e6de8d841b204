#include "image/yuv.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <regex>
#include <vector>

#include "common/parallel.hpp"

namespace penumbra {

namespace {

// Keys' cubic convolution kernel with swscale's default parameter a = −0.6
// (SWS_BICUBIC: B = 0, C = 0.6).
constexpr double keys(double x) {
    constexpr double a = -0.6;
    x = x < 0 ? -x : x;
    if (x < 1.0) return ((a + 2.0) * x - (a + 3.0)) * x * x + 1.0;
    if (x < 2.0) return ((a * x - 5.0 * a) * x + 8.0 * a) * x - 4.0 * a;
    return 0.0;
}

// Halved chroma, positions centred: luma sample 2k sits at chroma k − 1/4,
// 2k + 1 at k + 1/4; the four taps around each.
constexpr std::array<float, 4> even_taps{float(keys(1.75)), float(keys(0.75)), float(keys(0.25)), float(keys(1.25))};  // k−2..k+1
constexpr std::array<float, 4> odd_taps{float(keys(1.25)), float(keys(0.25)), float(keys(0.75)), float(keys(1.75))};   // k−1..k+2

struct Matrix {
    float y_offset, y_scale, c_offset, c_scale;  // normalized value = (sample − offset) · scale
    float r_cr, g_cb, g_cr, b_cb;                // R′ = Y′ + r_cr Cr, G′ = Y′ + g_cb Cb + g_cr Cr, B′ = Y′ + b_cb Cb
};

Matrix matrix_of(const YuvFormat& f) {
    const double s = double(1 << (f.bits - 8)), top = double((1 << f.bits) - 1);
    Matrix m{};
    if (f.full_range) {
        m.y_offset = 0.0f;
        m.y_scale = float(1.0 / top);
        m.c_offset = float(1 << (f.bits - 1));
        m.c_scale = float(1.0 / top);
    } else {
        m.y_offset = float(16.0 * s);
        m.y_scale = float(1.0 / (219.0 * s));
        m.c_offset = float(128.0 * s);
        m.c_scale = float(1.0 / (224.0 * s));
    }
    const double kg = 1.0 - f.kr - f.kb;
    m.r_cr = float(2.0 * (1.0 - f.kr));
    m.b_cb = float(2.0 * (1.0 - f.kb));
    m.g_cb = float(-2.0 * f.kb * (1.0 - f.kb) / kg);
    m.g_cr = float(-2.0 * f.kr * (1.0 - f.kr) / kg);
    return m;
}

// Row `row` of a plane of `width` samples as floats.
[[gnu::always_inline]] inline void load_row(const unsigned char* plane, int bytes, int width, int row, float* out) {
    const unsigned char* p = plane + std::size_t(row) * width * bytes;
    if (bytes == 1) {
        for (int i = 0; i < width; ++i) out[i] = float(p[i]);
    } else {
        for (int i = 0; i < width; ++i) {
            std::uint16_t v;
            std::memcpy(&v, p + 2 * i, 2);
            out[i] = float(v);
        }
    }
}

// Everything one thread needs for its rows.
struct RowScratch {
    std::vector<float> y, taps[4], cb, cr, wide_cb, wide_cr;
};

// Chroma row `row` of output row r: the plane's own row, or the vertical
// bicubic of the four around it (halved vertically), into `out`.
[[gnu::always_inline]] inline void chroma_row(const YuvFormat& f, const unsigned char* plane, int bytes, int r, RowScratch& s, std::vector<float>& out) {
    const int cw = f.chroma_width(), ch = f.chroma_height();
    out.resize(std::size_t(cw) + 4);  // two repeated samples on each side for the horizontal taps
    float* dst = out.data() + 2;
    if (f.chroma_shift_y == 0) {
        load_row(plane, bytes, cw, r, dst);
    } else {
        const int k = r >> 1;
        const auto& w = (r & 1) ? odd_taps : even_taps;
        const int first = (r & 1) ? k - 1 : k - 2;
        for (int t = 0; t < 4; ++t) {
            s.taps[t].resize(std::size_t(cw));
            load_row(plane, bytes, cw, std::clamp(first + t, 0, ch - 1), s.taps[t].data());
        }
        for (int i = 0; i < cw; ++i)
            dst[i] = w[0] * s.taps[0][i] + w[1] * s.taps[1][i] + w[2] * s.taps[2][i] + w[3] * s.taps[3][i];
    }
    out[0] = out[1] = dst[0];
    out[std::size_t(cw) + 2] = out[std::size_t(cw) + 3] = dst[cw - 1];
}

// Full-width chroma from a padded chroma row (halved horizontally or not).
[[gnu::always_inline]] inline void widen(const YuvFormat& f, const std::vector<float>& padded, std::vector<float>& wide) {
    wide.resize(std::size_t(f.width) + 1);
    const float* c = padded.data() + 2;
    if (f.chroma_shift_x == 0) {
        std::copy_n(c, f.width, wide.data());
        return;
    }
    const int cw = f.chroma_width();
    for (int k = 0; k < cw; ++k) {
        wide[2 * std::size_t(k)] = even_taps[0] * c[k - 2] + even_taps[1] * c[k - 1] + even_taps[2] * c[k] + even_taps[3] * c[k + 1];
        wide[2 * std::size_t(k) + 1] = odd_taps[0] * c[k - 1] + odd_taps[1] * c[k] + odd_taps[2] * c[k + 1] + odd_taps[3] * c[k + 2];
    }
}

// Compiled for x86-64-v3 (AVX2) too, chosen at load time where the CPU has it.
__attribute__((target_clones("arch=x86-64-v3", "default")))
void convert_row(const YuvFormat& f, const Matrix& m, const unsigned char* frame, int r, RowScratch& s, float* rgb) {
    const int bytes = f.bits > 8 ? 2 : 1;
    const std::size_t luma = std::size_t(f.width) * f.height * bytes;
    const std::size_t chroma = std::size_t(f.chroma_width()) * f.chroma_height() * bytes;
    s.y.resize(std::size_t(f.width));
    load_row(frame, bytes, f.width, r, s.y.data());
    chroma_row(f, frame + luma, bytes, r, s, s.cb);
    chroma_row(f, frame + luma + chroma, bytes, r, s, s.cr);
    widen(f, s.cb, s.wide_cb);
    widen(f, s.cr, s.wide_cr);
    for (int x = 0; x < f.width; ++x) {
        const float y = (s.y[std::size_t(x)] - m.y_offset) * m.y_scale;
        const float cb = (s.wide_cb[std::size_t(x)] - m.c_offset) * m.c_scale;
        const float cr = (s.wide_cr[std::size_t(x)] - m.c_offset) * m.c_scale;
        rgb[3 * x + 0] = std::clamp(y + m.r_cr * cr, 0.0f, 1.0f);
        rgb[3 * x + 1] = std::clamp(y + m.g_cb * cb + m.g_cr * cr, 0.0f, 1.0f);
        rgb[3 * x + 2] = std::clamp(y + m.b_cb * cb, 0.0f, 1.0f);
    }
}

}  // namespace

std::size_t YuvFormat::frame_bytes() const {
    const std::size_t bytes = bits > 8 ? 2 : 1;
    const std::size_t luma = std::size_t(width) * height, chroma = std::size_t(chroma_width()) * chroma_height();
    return bytes * (luma + 2 * chroma + (alpha ? luma : 0));
}

std::optional<YuvFormat> yuv_format(const std::string& pixel_format, const std::string& color_range,
                                    const std::string& color_space, int width, int height) {
    static const std::regex name(R"(^yuv(j?)(a?)(420|422|444|440)p(?:(9|1[0-6])le)?$)");
    std::smatch m;
    if (width <= 0 || height <= 0 || !std::regex_match(pixel_format, m, name)) return std::nullopt;
    YuvFormat f;
    f.pixel_format = pixel_format;
    f.width = width;
    f.height = height;
    const std::string sampling = m[3];
    f.chroma_shift_x = sampling == "420" || sampling == "422" ? 1 : 0;
    f.chroma_shift_y = sampling == "420" || sampling == "440" ? 1 : 0;
    f.bits = m[4].matched ? std::stoi(m[4]) : 8;
    f.alpha = m[2] == "a";
    const bool jpeg = m[1] == "j";
    if (jpeg && f.bits != 8) return std::nullopt;
    if (color_range == "pc") f.full_range = true;
    else if (color_range == "tv") f.full_range = false;
    else if (color_range.empty()) f.full_range = jpeg;
    else return std::nullopt;
    if (color_space.empty() || color_space == "unknown" || color_space == "reserved" || color_space == "bt470bg" ||
        color_space == "smpte170m") {
        f.kr = 0.299;
        f.kb = 0.114;
    } else if (color_space == "bt709") {
        f.kr = 0.2126;
        f.kb = 0.0722;
    } else if (color_space == "bt2020nc") {
        f.kr = 0.2627;
        f.kb = 0.0593;
    } else if (color_space == "smpte240m") {
        f.kr = 0.212;
        f.kb = 0.087;
    } else if (color_space == "fcc") {
        f.kr = 0.30;
        f.kb = 0.11;
    } else {
        return std::nullopt;
    }
    return f;
}

void yuv_to_rgb(const YuvFormat& format, const unsigned char* frame, Image& out, int threads) {
    if (out.width != format.width || out.height != format.height || out.channels != 3 ||
        out.pixels.size() != std::size_t(format.width) * format.height * 3)
        out = Image(format.width, format.height, 3);
    const Matrix m = matrix_of(format);
    parallel_for(std::size_t(format.height), {threads, 16, "image.yuv_to_rgb"}, [&](std::size_t b, std::size_t e) {
        RowScratch scratch;
        for (std::size_t r = b; r < e; ++r) convert_row(format, m, frame, int(r), scratch, out.row(int(r)));
    });
}

}  // namespace penumbra
