// Shared helpers for the SH tests: a fixed-seed random rotation and an
// independent (angle-based, std::assoc_legendre) reference for y_lm.
#pragma once

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

namespace penumbra::sh::testing {

inline Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    return q.normalized().toRotationMatrix();
}

inline Eigen::Vector3d random_direction(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
}

// y_lm from θ, φ with libstdc++'s std::assoc_legendre (no Condon–Shortley
// phase, as in our convention) and factorials from lgamma: shares no code
// with the Cartesian recurrence under test. Not usable exactly at the poles
// (atan2 is arbitrary there).
inline double reference_y(int l, int m, const Eigen::Vector3d& d) {
    const double theta = std::acos(std::clamp(d.z(), -1.0, 1.0));
    const double phi = std::atan2(d.y(), d.x());
    const int am = std::abs(m);
    const double k = std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi) *
                               std::exp(std::lgamma(l - am + 1.0) - std::lgamma(l + am + 1.0)));
    const double p = std::assoc_legendre(l, am, std::cos(theta));
    if (m == 0) return k * p;
    if (m > 0) return std::numbers::sqrt2 * k * std::cos(am * phi) * p;
    return std::numbers::sqrt2 * k * std::sin(am * phi) * p;
}

}  // namespace penumbra::sh::testing
