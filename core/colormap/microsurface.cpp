#include "colormap/microsurface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/error.hpp"

namespace penumbra::colormap {

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double inv_sqrt_2 = 0.70710678118654752440;
constexpr double inv_sqrt_2pi = 0.39894228040143267794;
constexpr double log_sqrt_2pi = 0.91893853320467274178;

double Phi(double z) { return 0.5 * std::erfc(-z * inv_sqrt_2); }
double phi(double z) { return inv_sqrt_2pi * std::exp(-0.5 * z * z); }

// log Φ(h), accurate for very negative h (where Φ underflows) and for large
// positive h (where Φ rounds to 1).
double log_Phi(double h) {
    if (h > 5.0)
        return std::log1p(-0.5 * std::erfc(h * inv_sqrt_2));
    if (h > -30.0)
        return std::log(0.5 * std::erfc(-h * inv_sqrt_2));
    // Asymptotic Mills ratio: Φ(h) = φ(h)/|h| · (1 − 1/h² + 3/h⁴ − 15/h⁶ + …).
    const double h2 = h * h;
    return -0.5 * h2 - log_sqrt_2pi - std::log(-h) + std::log1p(-1.0 / h2 + 3.0 / (h2 * h2) - 15.0 / (h2 * h2 * h2));
}

// φ(h)/Φ(h), stable for very negative h (→ −h).
double phi_over_Phi(double h) {
    if (h > -30.0)
        return phi(h) / Phi(h);
    return std::exp(-0.5 * h * h - log_sqrt_2pi - log_Phi(h));
}

}  // namespace

double smith_lambda_of_a(double a) {
    if (std::isnan(a) || a < 0.0)
        throw ArgumentError("Smith Λ needs a = cot θ / σ_s >= 0");
    if (a == 0.0)
        return std::numeric_limits<double>::infinity();
    if (a > 38.0)
        return 0.0;  // below 1e-300
    if (a > 20.0) {
        // φ(a)/a − Q(a) = φ(a)/a³ (1 − 3/a² + 15/a⁴ − 105/a⁶ + 945/a⁸ − 10395/a¹⁰):
        // the two terms agree to 1/a², so beyond a = 20 subtracting them
        // directly would lose more than 3 digits.
        const double u = 1.0 / (a * a);
        const double series = 1.0 - u * (3.0 - u * (15.0 - u * (105.0 - u * (945.0 - u * 10395.0))));
        return phi(a) * u / a * series;
    }
    return phi(a) / a - 0.5 * std::erfc(a * inv_sqrt_2);
}

double smith_lambda(double theta, double sigma_slope) {
    if (!std::isfinite(theta) || !(sigma_slope >= 0.0))
        throw ArgumentError("Smith Λ needs a finite angle and a slope deviation >= 0");
    theta = std::clamp(std::fabs(theta), 0.0, pi / 2);
    const double cos_t = std::cos(theta), sin_t = std::sin(theta);
    if (sin_t == 0.0 || sigma_slope == 0.0) {
        if (theta >= pi / 2 && sigma_slope > 0.0)
            return std::numeric_limits<double>::infinity();
        return 0.0;  // normal incidence, or a flat surface seen from any angle below 90°
    }
    if (theta >= pi / 2)  // cos(π/2) is 6e-17 in double; treat as exactly grazing
        return std::numeric_limits<double>::infinity();
    return smith_lambda_of_a(cos_t / (sin_t * sigma_slope));
}

double average_visibility(double lambda_view, double lambda_light) {
    if (!(lambda_view >= 0.0) || !(lambda_light >= 0.0))
        throw ArgumentError("Λ values must be >= 0");
    if (std::isinf(lambda_light))
        return std::isinf(lambda_view) ? 0.5 : 0.0;
    if (std::isinf(lambda_view))
        return 1.0;
    return (1.0 + lambda_view) / (1.0 + lambda_view + lambda_light);
}

HeightStatistics effective_height_exact(double lambda_sum) {
    if (!(lambda_sum >= 0.0) || std::isinf(lambda_sum))
        throw ArgumentError("the effective height distribution needs a finite Λ(ω_o) + Λ(ω_i) >= 0");
    if (lambda_sum == 0.0)
        return {0.0, 1.0};
    const double L = lambda_sum;
    // log of the unnormalized density: Λ log Φ(h) + log φ(h).
    auto log_density = [L](double h) { return L * log_Phi(h) - 0.5 * h * h; };
    // Mode: Λ φ(h)/Φ(h) = h (the derivative of the log density is zero); the
    // left side falls and the right rises, so bisect.
    double lo = -1.0, hi = std::max(1.0, std::sqrt(2.0 * std::log1p(L)) + 1.0);
    while (L * phi_over_Phi(lo) < lo)
        lo -= 1.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (L * phi_over_Phi(mid) > mid ? lo : hi) = mid;
    }
    const double mode = 0.5 * (lo + hi);
    // Curvature −(log density)'' = 1 + Λ r (h + r), r = φ/Φ: sets the width.
    const double r = phi_over_Phi(mode);
    const double width = 1.0 / std::sqrt(1.0 + L * r * (mode + r));
    // Trapezoid between the points where the density has fallen by e^-60 on
    // each side (the right tail of a high mode falls only like e^{-mode·Δh});
    // the density is smooth and decays fast, so the rule converges spectrally.
    const double peak = log_density(mode);
    double a = mode - width, b = mode + width;
    while (log_density(a) - peak > -60.0)
        a -= width;
    while (log_density(b) - peak > -60.0)
        b += width;
    const int n = 6001;
    const double step = (b - a) / (n - 1);
    double w0 = 0.0, w1 = 0.0, w2 = 0.0;
    for (int i = 0; i < n; ++i) {
        const double h = a + i * step;
        const double w = std::exp(log_density(h) - peak) * ((i == 0 || i == n - 1) ? 0.5 : 1.0);
        w0 += w;
        w1 += w * (h - mode);
        w2 += w * (h - mode) * (h - mode);
    }
    const double m = w1 / w0;
    return {mode + m, std::sqrt(std::max(0.0, w2 / w0 - m * m))};
}

HeightStatistics effective_height_fit(double lambda_sum) {
    if (!(lambda_sum >= 0.0))
        throw ArgumentError("the effective height distribution needs Λ(ω_o) + Λ(ω_i) >= 0");
    constexpr double alpha_mu = 0.39, beta_mu = 4.75, alpha_sigma = 0.26, beta_sigma = 1.13;
    return {alpha_mu * std::log(beta_mu * lambda_sum + 1.0),
            1.0 / (1.0 + alpha_sigma * std::log(beta_sigma * lambda_sum + 1.0))};
}

SlopeShift slope_shift_of_c(double c) {
    if (std::isnan(c))
        throw ArgumentError("slope shift needs a number");
    if (std::isinf(c) && c > 0)
        return {0.0, 1.0};
    // Z0 = cΦ(c) + φ(c) = φ(c)(1 + c Φ/φ). For c < −8 almost no facet faces
    // the viewer; the moments are those of the limit (an exponential tail),
    // reached by clamping.
    c = std::max(c, -8.0);
    const double P = Phi(c), p = phi(c);
    const double z0 = c * P + p;
    const double mean = -P / z0;
    const double second = (c * P + 2.0 * p) / z0;
    return {mean, std::sqrt(std::max(0.0, second - mean * mean))};
}

SlopeStatistics slope_filtering_gaussian(double theta_view, double phi_view, const std::array<double, 2>& slope_mean,
                                         const std::array<double, 3>& cov) {
    if (!std::isfinite(theta_view) || !std::isfinite(phi_view) || !std::isfinite(slope_mean[0]) ||
        !std::isfinite(slope_mean[1]))
        throw ArgumentError("slope filtering needs finite angles and mean slope");
    const double det = cov[0] * cov[2] - cov[1] * cov[1];
    if (!(cov[0] > 0.0) || !(cov[2] > 0.0) || !(det > 0.0) || !std::isfinite(det))
        throw ArgumentError("the slope covariance must be finite and positive definite");
    const double theta = std::clamp(std::fabs(theta_view), 0.0, pi / 2);
    const double d[2] = {std::cos(phi_view), std::sin(phi_view)};
    const double sd[2] = {cov[0] * d[0] + cov[1] * d[1], cov[1] * d[0] + cov[2] * d[1]};  // Σd
    const double var_y = d[0] * sd[0] + d[1] * sd[1];
    const double sigma_y = std::sqrt(var_y);
    const double mu_y = slope_mean[0] * d[0] + slope_mean[1] * d[1];
    const double sin_t = std::sin(theta);
    const double cot = sin_t == 0.0 ? std::numeric_limits<double>::infinity() : std::cos(theta) / sin_t;
    const SlopeShift z = slope_shift_of_c((cot - mu_y) / sigma_y);
    SlopeStatistics out;
    out.mean = {slope_mean[0] + sd[0] / sigma_y * z.mean, slope_mean[1] + sd[1] / sigma_y * z.mean};
    const double shrink = (1.0 - z.stddev * z.stddev) / var_y;
    out.covariance = {cov[0] - sd[0] * sd[0] * shrink, cov[1] - sd[0] * sd[1] * shrink, cov[2] - sd[1] * sd[1] * shrink};
    return out;
}

SlopeStatistics slope_filtering_numerical(double theta_view, double phi_view, const std::array<double, 2>& mean,
                                          const std::array<double, 3>& cov, int grid) {
    const double det = cov[0] * cov[2] - cov[1] * cov[1];
    if (!(det > 0.0) || grid < 3)
        throw ArgumentError("slope covariance must be positive definite and the grid at least 3");
    const double inv[3] = {cov[2] / det, -cov[1] / det, cov[0] / det};
    const double theta = std::clamp(std::fabs(theta_view), 0.0, pi / 2);
    const double w[3] = {std::sin(theta) * std::cos(phi_view), std::sin(theta) * std::sin(phi_view), std::cos(theta)};
    const double rx = 9.0 * std::sqrt(cov[0]), ry = 9.0 * std::sqrt(cov[2]);
    double m0 = 0, mx = 0, my = 0, mxx = 0, mxy = 0, myy = 0;
    for (int j = 0; j < grid; ++j) {
        const double sy = mean[1] - ry + 2.0 * ry * j / (grid - 1);
        for (int i = 0; i < grid; ++i) {
            const double sx = mean[0] - rx + 2.0 * rx * i / (grid - 1);
            const double dx = sx - mean[0], dy = sy - mean[1];
            const double p = std::exp(-0.5 * (inv[0] * dx * dx + 2.0 * inv[1] * dx * dy + inv[2] * dy * dy));
            // The microfacet: its normal, its area per unit macro area.
            const double norm = std::sqrt(1.0 + sx * sx + sy * sy);
            const double n_dot_w = (-sx * w[0] - sy * w[1] + w[2]) / norm;
            const double weight = p * norm * std::max(n_dot_w, 0.0);
            m0 += weight;
            mx += weight * sx;
            my += weight * sy;
            mxx += weight * sx * sx;
            mxy += weight * sx * sy;
            myy += weight * sy * sy;
        }
    }
    SlopeStatistics out;
    out.mean = {mx / m0, my / m0};
    out.covariance = {mxx / m0 - out.mean[0] * out.mean[0], mxy / m0 - out.mean[0] * out.mean[1],
                      myy / m0 - out.mean[1] * out.mean[1]};
    return out;
}

}  // namespace penumbra::colormap
