#include "lights/sun_irradiance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/parallel.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::lights {

namespace {

constexpr double pi = std::numbers::pi;

// Below this half-angle a sun is a point whose facing irradiance carries the
// model's factor: the horizon band |c| < sin h is then too thin to matter and
// the closed forms lose digits to 1 − cos h.
constexpr double point_half_angle = 1e-4;

// Gauss–Legendre rule on [0, 1], computed once.
struct UnitRule {
    std::vector<double> x, w;
    explicit UnitRule(int n) {
        sh::gauss_legendre(n, x, w);
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] = 0.5 * (1.0 + x[i]);
            w[i] *= 0.5;
        }
    }
};

// Uniform cone of half-angle h, unit flux: the sphere-light form factor
// (Snyder 1996, "Area light sources for real-time graphics"; the horizon-
// clipped branch as in Lagarde & de Rousiers 2014, Frostbite, eq. 19) for unit
// radiance, divided by the cone's solid angle 2π(1 − cos h).
double cone_kernel(double c, double h) {
    const double s = std::sin(h), cos_h = std::cos(h);
    const double solid_angle = 4.0 * pi * std::pow(std::sin(0.5 * h), 2);
    if (c >= s) return pi * s * s * c / solid_angle;
    if (c <= -s) return 0.0;
    const double sin_b = std::sqrt(std::max(0.0, 1.0 - c * c));
    const double x = cos_h / s;  // cot h ≥ 0 for h ≤ π/2
    const double y = std::clamp(-x * c / sin_b, -1.0, 1.0);
    const double q = sin_b * std::sqrt(std::max(0.0, 1.0 - y * y));
    const double unit = (c * std::acos(y) - x * q) * s * s + std::atan2(q, x);
    return std::max(0.0, unit) / solid_angle;
}

// Blender 3.x disc: radius R = tan h at unit distance, uniform by area. With
// u = √(1 + r²) the area element r dr/√(1 + r²) is du, so
//   K = ∫_1^U ∫_0^2π max(0, c + sin β·r·cos φ) dφ du / (π R²),  U = sec h,
// whose inner integral is closed-form: 2πc while sin β·r ≤ |c| (u ≤ 1/sin β),
// else 2(c φ₀ + a sin φ₀) with a = sin β·r, φ₀ = acos(−c/a).
double disc_kernel(double c, double h) {
    h = std::min(h, 0.5 * pi - 1e-6);  // sec h stays finite; angle π is 3.x's limit
    const double s = std::sin(h), U = 1.0 / std::cos(h);
    if (c >= s) return 2.0 * c / (U + 1.0);
    if (c <= -s) return 0.0;
    const double sin_b = std::sqrt(std::max(0.0, 1.0 - c * c));
    const double u_kink = std::min(U, 1.0 / std::max(sin_b, 1e-300));
    double sum = c > 0.0 ? 2.0 * pi * c * (u_kink - 1.0) : 0.0;
    // u = u_kink + t² takes the square-root onset at the kink out of the integrand.
    static const UnitRule rule(32);
    const double t_max = std::sqrt(std::max(0.0, U - u_kink));
    for (std::size_t i = 0; i < rule.x.size(); ++i) {
        const double t = t_max * rule.x[i], u = u_kink + t * t;
        const double a = sin_b * std::sqrt(std::max(0.0, u * u - 1.0));
        if (a <= std::abs(c)) {
            sum += (c > 0.0 ? 2.0 * pi * c : 0.0) * 2.0 * t * t_max * rule.w[i];
            continue;
        }
        const double phi0 = std::acos(std::clamp(-c / a, -1.0, 1.0));
        const double inner = 2.0 * (c * phi0 + a * std::sin(phi0));
        sum += inner * 2.0 * t * t_max * rule.w[i];
    }
    return std::max(0.0, sum) / (pi * (U * U - 1.0));
}

}  // namespace

SunModel sun_model_for_blender(int major, int /*minor*/) {
    // docs/lights.md: the cone came with Cycles' 2023 light rework (4.0).
    return major >= 4 ? SunModel::blender4_cone : SunModel::blender3_disc;
}

double sun_angle(double spread) {
    if (!(spread > 0.0)) return 0.0;
    const double angle = std::min(2.0 * std::numbers::sqrt2 * spread, pi);
    return angle < min_sun_angle ? 0.0 : angle;
}

double sun_half_angle(double spread) { return 0.5 * sun_angle(spread); }

double sun_strength_per_flux(double angle, SunModel model) {
    if (model != SunModel::blender4_cone) return 1.0;
    return 0.5 * (1.0 + std::cos(0.5 * angle));
}

double sun_kernel(double c, double h, SunModel model) {
    c = std::clamp(c, -1.0, 1.0);
    if (model == SunModel::point) return std::max(0.0, c);
    if (h < point_half_angle) {
        const double facing = model == SunModel::blender4_cone ? 0.5 * (1.0 + std::cos(h))
                                                                : 2.0 * std::cos(h) / (1.0 + std::cos(h));
        return facing * std::max(0.0, c);
    }
    return model == SunModel::blender4_cone ? cone_kernel(c, h) : disc_kernel(c, h);
}

double sun_kernel_slope(double c, double h, SunModel model) {
    c = std::clamp(c, -1.0, 1.0);
    if (model == SunModel::point || h < point_half_angle) {
        if (c <= 0.0) return 0.0;
        return sun_kernel(1.0, h, model);
    }
    // Outside the horizon band the kernel is linear (or zero).
    const double s = std::sin(std::min(h, 0.5 * pi - 1e-6));
    if (c >= s) return sun_kernel(1.0, h, model);
    if (c <= -s) return 0.0;
    const double step = 1e-6;
    const double lo = std::max(-1.0, c - step), hi = std::min(1.0, c + step);
    return (sun_kernel(hi, h, model) - sun_kernel(lo, h, model)) / (hi - lo);
}

Eigen::MatrixXd sun_irradiance(const std::vector<Light>& lights, const std::vector<Eigen::Vector3d>& normals,
                               SunModel model, int threads) {
    std::vector<double> half(lights.size());
    for (std::size_t k = 0; k < lights.size(); ++k) half[k] = sun_half_angle(lights[k].spread);
    Eigen::MatrixXd e = Eigen::MatrixXd::Zero(Eigen::Index(normals.size()), 3);
    parallel_for(normals.size(), {threads, 64, "lights.sun_irradiance"}, [&](std::size_t b, std::size_t end) {
        for (std::size_t i = b; i < end; ++i) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            for (std::size_t k = 0; k < lights.size(); ++k) {
                const double kernel = sun_kernel(normals[i].dot(lights[k].direction), half[k], model);
                if (kernel > 0.0) sum += kernel * lights[k].rgb;
            }
            e.row(Eigen::Index(i)) = sum.transpose();
        }
    });
    return e;
}

}  // namespace penumbra::lights
