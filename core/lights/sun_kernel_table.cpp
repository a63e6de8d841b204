#include "lights/sun_kernel_table.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "lights/sun_irradiance.hpp"

namespace penumbra::lights {

namespace {

constexpr double pi = std::numbers::pi;
constexpr int t_cells = 128, h_cells = 512;
constexpr double s_step = 2.0 / t_cells, h_step = 0.5 * pi / h_cells;

// The band's coordinate t runs through s ∈ [−1, 1] as t = sin(πs/2): near
// t = ±1 the kernel goes as (1 ∓ t)^{5/2} (the sun's cap leaving the
// horizon), which is (1 ∓ s)^5 in s, smooth enough for cubics.
double t_of_s(double s) { return std::sin(0.5 * pi * s); }
// Narrower suns are points (sun_irradiance.cpp's threshold); the table's
// h = 0 column is the small-sun limit, taken at h = 1e-3, where the closed
// forms still have their digits and B differs from its limit by O(h²).
constexpr double point_half_angle = 1e-4, first_column = 1e-3;

// Both cone models face the sun alike: EEVEE's shadow cuts only the band.
bool is_cone(SunModel model) { return model != SunModel::blender3_disc; }

double facing(double h, SunModel model) {
    const double c = std::cos(h);
    return is_cone(model) ? 0.5 * (1.0 + c) : 2.0 * c / (1.0 + c);
}

double facing_slope(double h, SunModel model) {
    const double c = std::cos(h), s = std::sin(h);
    return is_cone(model) ? -0.5 * s : -2.0 * s / ((1.0 + c) * (1.0 + c));
}

// Catmull–Rom weights and their derivatives at u ∈ [0, 1] for the points
// −1, 0, 1, 2.
void cubic_weights(double u, std::array<double, 4>& w, std::array<double, 4>& dw) {
    const double u2 = u * u, u3 = u2 * u;
    w = {0.5 * (-u3 + 2 * u2 - u), 0.5 * (3 * u3 - 5 * u2 + 2), 0.5 * (-3 * u3 + 4 * u2 + u), 0.5 * (u3 - u2)};
    dw = {0.5 * (-3 * u2 + 4 * u - 1), 0.5 * (9 * u2 - 10 * u), 0.5 * (-9 * u2 + 8 * u + 1), 0.5 * (3 * u2 - 2 * u)};
}

// B(t(s_i), h_j) for i = −1 … t_cells + 1 (padded), j = 0 … h_cells,
// row-major by j.
struct ShapeTable {
    std::vector<double> b;
    explicit ShapeTable(SunModel model) : b(std::size_t(t_cells + 3) * (h_cells + 1)) {
        for (int j = 0; j <= h_cells; ++j) {
            const double h = std::max(first_column, j * h_step);
            const double scale = facing(std::min(h, 0.5 * pi - 1e-6), model) * std::sin(h);
            for (int i = -1; i <= t_cells + 1; ++i) {
                const double s = -1.0 + i * s_step, t = t_of_s(s);
                // Padding: 0 below the band, t above (the linear form, mirrored in s).
                const double v = s <= -1.0 ? 0.0 : s >= 1.0 ? t : sun_kernel(t * std::sin(h), h, model) / scale;
                b[std::size_t(j) * (t_cells + 3) + std::size_t(i + 1)] = v;
            }
        }
    }
    double at(int i, int j) const {  // j mirrored below 0, extrapolated above h_cells
        if (j < 0) j = -j;
        if (j > h_cells) return 2.0 * at(i, h_cells) - at(i, 2 * h_cells - j);
        return b[std::size_t(j) * (t_cells + 3) + std::size_t(i + 1)];
    }
};

const ShapeTable& table(SunModel model) {
    if (model == SunModel::eevee_next_shadowed) {
        static const ShapeTable shadowed(SunModel::eevee_next_shadowed);  // built only when asked for
        return shadowed;
    }
    static const ShapeTable disc(SunModel::blender3_disc), cone(SunModel::blender4_cone);
    return model == SunModel::blender3_disc ? disc : cone;  // EEVEE Legacy's kernel is the cone's
}

}  // namespace

TabulatedSun::TabulatedSun(double h, SunModel model) : model_(model) {
    half_ = std::clamp(h, 0.0, 0.5 * pi);
    point_ = model == SunModel::point || half_ < point_half_angle;
    if (model == SunModel::point) {
        facing_ = 1.0;
        return;
    }
    // sun_kernel holds the disc's h below π/2, where its radius tan h is finite.
    const double held = model == SunModel::blender3_disc ? std::min(half_, 0.5 * pi - 1e-6) : half_;
    facing_ = facing(held, model);
    facing_slope_ = facing_slope(held, model);
    if (point_) return;
    sin_h_ = std::sin(half_);
    cot_h_ = std::cos(half_) / sin_h_;
    // This h's column of B and ∂B/∂h: the h-cubic applied once per t entry.
    const ShapeTable& tab = table(model);
    const double x = half_ / h_step;
    const int j = std::min(int(x), h_cells - 1);
    std::array<double, 4> w, dw;
    cubic_weights(x - j, w, dw);
    shape_.assign(t_cells + 3, 0.0);
    shape_dh_.assign(t_cells + 3, 0.0);
    for (int i = -1; i <= t_cells + 1; ++i)
        for (int a = 0; a < 4; ++a) {
            const double v = tab.at(i, j - 1 + a);
            shape_[std::size_t(i + 1)] += w[a] * v;
            shape_dh_[std::size_t(i + 1)] += dw[a] * v / h_step;
        }
}

SunKernelValue TabulatedSun::operator()(double c) const {
    c = std::clamp(c, -1.0, 1.0);
    SunKernelValue out;
    if (point_ || c >= sin_h_ || c <= -sin_h_) {
        if (c <= 0.0) return out;  // a point behind the surface, or the whole sun below its horizon
        out.value = facing_ * c;
        out.slope = facing_;
        out.angle_slope = facing_slope_ * c;
        return out;
    }
    // In the band: K = α sin h · B(t, h), t = c / sin h = sin(πs/2).
    const double t = std::clamp(c / sin_h_, -1.0, 1.0);
    const double s = std::asin(t) / (0.5 * pi), x = (s + 1.0) / s_step;
    const int i = std::clamp(int(x), 0, t_cells - 1);
    std::array<double, 4> w, dw;
    cubic_weights(x - i, w, dw);
    double b = 0.0, b_s = 0.0, b_h = 0.0;
    for (int a = 0; a < 4; ++a) {
        const std::size_t e = std::size_t(i + a);  // entry of point i − 1 + a (padded by one)
        b += w[a] * shape_[e];
        b_s += dw[a] * shape_[e] / s_step;
        b_h += w[a] * shape_dh_[e];
    }
    // dB/dt = (dB/ds) / (dt/ds), dt/ds = (π/2) cos(πs/2) = (π/2)√(1 − t²);
    // at the band's very edges the limits, 0 and 1.
    const double dt_ds = 0.5 * pi * std::sqrt(std::max(0.0, 1.0 - t * t));
    const double b_t = dt_ds > 1e-6 ? b_s / dt_ds : (t > 0.0 ? 1.0 : 0.0);
    const double scale = facing_ * sin_h_;
    out.value = scale * b;
    out.slope = facing_ * b_t;
    // d(α sin h)/dh · B + α sin h · (B_t · ∂t/∂h + B_h), ∂t/∂h = −t cot h.
    out.angle_slope = (facing_slope_ * sin_h_ + facing_ * std::cos(half_)) * b +
                      scale * (-t * cot_h_ * b_t + b_h);
    return out;
}

}  // namespace penumbra::lights
