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

double cone_fraction_above_horizon(double c, double h) {
    c = std::clamp(c, -1.0, 1.0);
    h = std::clamp(h, 0.0, pi);
    const double s = std::sin(h);
    if (h <= 0.5 * pi && c >= s) return 1.0;
    if (h <= 0.5 * pi && c <= -s) return 0.0;
    if (h < 1e-9) return c > 0.0 ? 1.0 : 0.0;
    // Rings at angle ψ from the axis: ω·n = cos ψ c + sin ψ sin β cos φ, so
    // a ring is wholly on one side while ψ < ψ0 = |π/2 − β| and above the
    // horizon on an arc 2φ₀, φ₀ = acos(−c cos ψ / (sin β sin ψ)), beyond it.
    const double beta = std::acos(c), sin_b = std::sin(beta);
    const double psi0 = std::min(h, std::abs(0.5 * pi - beta));
    double above = c > 0.0 ? 2.0 * pi * (1.0 - std::cos(psi0)) : 0.0;
    // ψ = ψ0 + t² takes the square-root onset at ψ0 out of the integrand.
    static const UnitRule rule(48);
    const double t_max = std::sqrt(std::max(0.0, h - psi0));
    for (std::size_t i = 0; i < rule.x.size(); ++i) {
        const double t = t_max * rule.x[i], psi = psi0 + t * t;
        const double sin_psi = std::sin(psi);
        const double denom = sin_b * sin_psi;
        const double arg = denom > 1e-300 ? -c * std::cos(psi) / denom : (c * std::cos(psi) > 0.0 ? -1.0 : 1.0);
        const double phi0 = std::acos(std::clamp(arg, -1.0, 1.0));
        above += 2.0 * phi0 * sin_psi * 2.0 * t * t_max * rule.w[i];
    }
    return std::clamp(above / (2.0 * pi * (1.0 - std::cos(h))), 0.0, 1.0);
}

SunModel sun_model_for_renderer(int major, int minor, bool eevee, bool shadow) {
    if (!eevee) return sun_model_for_blender(major, minor);
    if (major < 4 || (major == 4 && minor < 2)) return SunModel::eevee_legacy;
    return shadow ? SunModel::eevee_next_shadowed : SunModel::blender4_cone;
}

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
    if (model == SunModel::eevee_legacy) {
        // EEVEE Legacy clamps the radius to at least 0.001 and the angle to 179.9°.
        const double h = 0.5 * std::min(angle, 179.9 / 180.0 * pi);
        const double r2 = std::pow(std::max(0.001, std::tan(h)), 2);
        const double one_minus_cos = 2.0 * std::pow(std::sin(0.5 * h), 2);
        // A point sun (h below the clamp) carries its strength as flux.
        return h < 1e-3 ? 1.0 : r2 / ((2.0 + r2) * one_minus_cos);
    }
    if (model != SunModel::blender4_cone && model != SunModel::eevee_next_shadowed) return 1.0;
    return 0.5 * (1.0 + std::cos(0.5 * angle));
}

double sun_kernel(double c, double h, SunModel model) {
    c = std::clamp(c, -1.0, 1.0);
    if (model == SunModel::point) return std::max(0.0, c);
    const bool cone = model != SunModel::blender3_disc;
    if (h < point_half_angle) {
        const double facing = cone ? 0.5 * (1.0 + std::cos(h)) : 2.0 * std::cos(h) / (1.0 + std::cos(h));
        return facing * std::max(0.0, c);
    }
    if (model == SunModel::eevee_next_shadowed) return cone_kernel(c, h) * cone_fraction_above_horizon(c, h);
    return cone ? cone_kernel(c, h) : disc_kernel(c, h);
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
