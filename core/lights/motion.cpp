#include "lights/motion.hpp"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "sh/basis.hpp"
#include "sh/rotation.hpp"

namespace penumbra::lights {

namespace {

constexpr int signature_width = 256;

Eigen::Matrix3d exp_rotation(const Eigen::Vector3d& w) {
    const double angle = w.norm();
    if (angle < 1e-300) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Eigen::VectorXd rotated(const Eigen::VectorXd& a, const Eigen::Matrix3d& r) {
    Eigen::VectorXd out(a.size());
    sh::ShRotation(motion_order, r).apply(a.data(), out.data());
    return out;
}

// Levenberg–Marquardt on the rotation vector from `start`; the squared residual in `cost`.
Eigen::Matrix3d refine(const Eigen::VectorXd& a, const Eigen::VectorXd& b, Eigen::Matrix3d r, double& cost) {
    Eigen::VectorXd residual = rotated(a, r) - b;
    cost = residual.squaredNorm();
    double mu = 1e-3;
    for (int it = 0; it < 30 && cost > 0.0; ++it) {
        // Central differences along each axis of a turn applied after R.
        Eigen::MatrixXd j(a.size(), 3);
        const double step = 1e-5;
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d e = step * Eigen::Vector3d::Unit(k);
            j.col(k) = (rotated(a, exp_rotation(e) * r) - rotated(a, exp_rotation(-e) * r)) / (2.0 * step);
        }
        const Eigen::Matrix3d h = j.transpose() * j;
        const Eigen::Vector3d g = j.transpose() * residual;
        bool improved = false;
        for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
            Eigen::Matrix3d damped = h;
            damped.diagonal() += mu * h.diagonal() + Eigen::Vector3d::Constant(1e-12);
            const Eigen::Vector3d w = damped.ldlt().solve(-g);
            const Eigen::Matrix3d next = exp_rotation(w) * r;
            const Eigen::VectorXd res = rotated(a, next) - b;
            if (res.squaredNorm() < cost) {
                improved = true;
                const double gain = cost - res.squaredNorm();
                r = next;
                residual = res;
                cost = res.squaredNorm();
                mu = std::max(mu / 3.0, 1e-12);
                if (gain < 1e-14 || w.norm() < 1e-9) return r;
            } else {
                mu *= 4.0;
            }
        }
        if (!improved) break;
    }
    return r;
}

}  // namespace

MapSignature map_signature(const EnvironmentMap& map, const std::array<double, 3>& y, int threads) {
    // The working map averaged down (energy-exact) to at most 256 columns.
    const EnvironmentMap* small = &map;
    EnvironmentMap reduced;
    if (map.width > signature_width) {
        MapOptions reduce;
        reduce.projection = map.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
        reduce.max_width = signature_width;
        reduce.threads = threads;
        Image copy(map.width, map.height, 3);
        copy.pixels = map.rgb;
        reduced = make_environment(copy, reduce);
        small = &reduced;
    }
    const int n = sh::coefficient_count(motion_order);
    MapSignature out;
    out.coefficients = Eigen::VectorXd::Zero(n);
    double total = 0.0, area = 0.0;
    for (int r = 0; r < small->height; ++r)
        for (int c = 0; c < small->width; ++c) {
            const float* p = small->pixel(r, c);
            total += small->solid_angle(r) * (y[0] * p[0] + y[1] * p[1] + y[2] * p[2]);
            area += small->solid_angle(r);
        }
    if (!(total > 0.0)) return out;
    const double mean = total / area;
    std::vector<double> basis(std::size_t(n), 0.0);
    for (int r = 0; r < small->height; ++r) {
        const double omega = small->solid_angle(r);
        for (int c = 0; c < small->width; ++c) {
            const float* p = small->pixel(r, c);
            const double f = std::log1p((y[0] * p[0] + y[1] * p[1] + y[2] * p[2]) / mean);
            if (f <= 0.0) continue;
            sh::eval_unit(motion_order, small->direction(r, c), basis.data());
            out.coefficients += omega * f * Eigen::Map<const Eigen::VectorXd>(basis.data(), n);
        }
    }
    const double norm = out.coefficients.norm();
    if (norm > 0.0) out.coefficients /= norm;
    return out;
}

MapMotion estimate_rotation(const MapSignature& from, const MapSignature& to, const Eigen::Matrix3d& guess) {
    MapMotion out;
    if (from.coefficients.size() == 0 || to.coefficients.size() == 0 || from.coefficients.isZero() ||
        to.coefficients.isZero()) {
        out.residual = from.coefficients.isZero() && to.coefficients.isZero() ? 0.0 : 2.0;
        return out;
    }
    double cost_identity = 0.0, cost_guess = 0.0;
    const Eigen::Matrix3d a = refine(from.coefficients, to.coefficients, Eigen::Matrix3d::Identity(), cost_identity);
    const Eigen::Matrix3d b = guess.isIdentity(1e-12) ? a : refine(from.coefficients, to.coefficients, guess, cost_guess);
    const bool take_guess = !guess.isIdentity(1e-12) && cost_guess < cost_identity;
    out.rotation = take_guess ? b : a;
    out.residual = std::sqrt(take_guess ? cost_guess : cost_identity);
    out.change = (from.coefficients - to.coefficients).norm();
    return out;
}

}  // namespace penumbra::lights
