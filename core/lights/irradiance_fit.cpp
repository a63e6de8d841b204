#include "lights/irradiance_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "lights/sun_irradiance.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::lights {

namespace {

struct Problem {
    std::vector<Eigen::Vector3d> normals;
    Eigen::MatrixXd target;        // M × 3
    std::vector<double> half;      // sun half-angles
    std::vector<Eigen::Vector3d> start;
    std::vector<double> bound;     // max angle from start
    SunModel model;
    int threads;
};

// A(i, k) = K(n_i·d_k, h_k); with slopes, also K'(n_i·d_k, h_k).
void kernels(const Problem& p, const std::vector<Eigen::Vector3d>& dirs, Eigen::MatrixXd& a, Eigen::MatrixXd* slope) {
    const Eigen::Index m = Eigen::Index(p.normals.size()), n = Eigen::Index(dirs.size());
    a.resize(m, n);
    if (slope) slope->resize(m, n);
    parallel_for(std::size_t(m), {p.threads, 64, "lights.irradiance_fit"}, [&](std::size_t b, std::size_t e) {
        for (Eigen::Index i = Eigen::Index(b); i < Eigen::Index(e); ++i)
            for (Eigen::Index k = 0; k < n; ++k) {
                const double c = p.normals[i].dot(dirs[k]);
                a(i, k) = sun_kernel(c, p.half[k], p.model);
                if (slope) (*slope)(i, k) = sun_kernel_slope(c, p.half[k], p.model);
            }
    });
}

// min ‖A x − t‖² over x ≥ 0 for each column of t: projected coordinate
// descent on the normal equations G x = b, warm-started at `x`.
void nonnegative_colours(const Eigen::MatrixXd& a, const Eigen::MatrixXd& target, Eigen::MatrixXd& x) {
    Eigen::MatrixXd g = a.transpose() * a;
    const Eigen::MatrixXd b = a.transpose() * target;
    // A whisper of ridge keeps coincident lights' 2×2 blocks from stalling.
    const double ridge = 1e-12 * std::max(g.diagonal().maxCoeff(), 1e-300);
    g.diagonal().array() += ridge;
    const Eigen::Index n = g.rows();
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
        Eigen::VectorXd xc = x.col(c).cwiseMax(0.0);
        Eigen::VectorXd grad = g * xc - b.col(c);
        const double scale = std::max(b.col(c).cwiseAbs().maxCoeff(), 1e-300);
        for (int sweep = 0; sweep < 400; ++sweep) {
            double largest = 0.0;
            for (Eigen::Index k = 0; k < n; ++k) {
                const double next = std::max(0.0, xc[k] - grad[k] / g(k, k));
                const double delta = next - xc[k];
                if (delta == 0.0) continue;
                grad += delta * g.col(k);
                xc[k] = next;
                largest = std::max(largest, std::abs(delta) * g(k, k));
            }
            if (largest < 1e-10 * scale) break;
        }
        x.col(c) = xc;
    }
}

double objective(const Eigen::MatrixXd& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& target) {
    return (a * x - target).squaredNorm();
}

void tangent_frame(const Eigen::Vector3d& d, Eigen::Vector3d& u, Eigen::Vector3d& v) {
    const Eigen::Vector3d helper = std::abs(d.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    u = helper.cross(d).normalized();
    v = d.cross(u);
}

// d moved by (du, dv) in its tangent plane, then held within `bound` of start.
Eigen::Vector3d moved(const Eigen::Vector3d& d, double du, double dv, const Eigen::Vector3d& start, double bound) {
    Eigen::Vector3d u, v;
    tangent_frame(d, u, v);
    Eigen::Vector3d out = (d + du * u + dv * v).normalized();
    const double angle = std::atan2(out.cross(start).norm(), out.dot(start));
    if (angle > bound) {
        const Eigen::Vector3d axis = start.cross(out);
        if (axis.norm() < 1e-300) return start;
        out = Eigen::AngleAxisd(bound, axis.normalized()) * start;
    }
    return out;
}

// One Levenberg–Marquardt step of every direction, colours x fixed. The
// Gauss–Newton matrix of channel-summed residuals factors as
// H[(k,α),(l,β)] = (x xᵀ)(k,l) · (gᵀg)[(k,α),(l,β)], g(i,(k,α)) = K'·(n_i·t_kα).
bool direction_step(const Problem& p, std::vector<Eigen::Vector3d>& dirs, const Eigen::MatrixXd& x, double& mu) {
    const Eigen::Index m = Eigen::Index(p.normals.size()), n = Eigen::Index(dirs.size());
    Eigen::MatrixXd a, slope;
    kernels(p, dirs, a, &slope);
    const Eigen::MatrixXd residual = a * x - p.target;
    const double before = residual.squaredNorm();
    Eigen::MatrixXd g(m, 2 * n);
    for (Eigen::Index k = 0; k < n; ++k) {
        Eigen::Vector3d u, v;
        tangent_frame(dirs[k], u, v);
        for (Eigen::Index i = 0; i < m; ++i) {
            g(i, 2 * k) = slope(i, k) * p.normals[i].dot(u);
            g(i, 2 * k + 1) = slope(i, k) * p.normals[i].dot(v);
        }
    }
    Eigen::MatrixXd h = g.transpose() * g;
    const Eigen::MatrixXd w = x * x.transpose();
    const Eigen::MatrixXd gr = g.transpose() * residual;  // 2N × 3
    Eigen::VectorXd grad(2 * n);
    for (Eigen::Index k = 0; k < n; ++k)
        for (int s = 0; s < 2; ++s) grad[2 * k + s] = gr.row(2 * k + s).dot(x.row(k));
    for (Eigen::Index r = 0; r < 2 * n; ++r)
        for (Eigen::Index c = 0; c < 2 * n; ++c) h(r, c) *= w(r / 2, c / 2);
    const double floor = 1e-12 * std::max(h.diagonal().maxCoeff(), 1e-300);
    for (int attempt = 0; attempt < 6; ++attempt) {
        Eigen::MatrixXd damped = h;
        damped.diagonal() += (mu * h.diagonal().array() + floor).matrix();
        const Eigen::VectorXd step = damped.ldlt().solve(-grad);
        std::vector<Eigen::Vector3d> trial(dirs.size());
        for (Eigen::Index k = 0; k < n; ++k)
            trial[k] = step.allFinite() ? moved(dirs[k], step[2 * k], step[2 * k + 1], p.start[k], p.bound[k])
                                        : dirs[k];
        Eigen::MatrixXd at;
        kernels(p, trial, at, nullptr);
        if (objective(at, x, p.target) < before) {
            dirs = std::move(trial);
            mu = std::max(mu / 3.0, 1e-9);
            return true;
        }
        mu *= 4.0;
    }
    return false;
}

double luminance_error(const Eigen::MatrixXd& estimate, const Eigen::MatrixXd& target,
                       const std::array<double, 3>& y) {
    return relative_rmse(estimate, target, y);
}

}  // namespace

double fit_reach(const EnvironmentMap& map, const Light& light, double reach) {
    const double row_angle = map.theta_max() / std::max(1, map.height);
    return reach * std::max(light.spread, row_angle);
}

IrradianceFitResult fit_irradiance(const EnvironmentMap& map, std::vector<Light>& lights,
                                   const IrradianceFitOptions& options) {
    if (options.normal_count < 16) throw ArgumentError("the irradiance fit needs at least 16 normals");
    if (options.reference_width < 0) throw ArgumentError("reference_width must be >= 0 (0: the full map)");
    if (options.iterations < 0) throw ArgumentError("the irradiance fit's iterations must be >= 0");
    if (!(options.reach >= 0.0) || !std::isfinite(options.reach))
        throw ArgumentError("the irradiance fit's reach must be a finite number >= 0");
    IrradianceFitResult result;
    if (lights.empty() || map.width == 0) return result;

    // Target: the exact irradiance of an energy-exact reduced copy.
    Problem p;
    p.model = options.sun_model;
    p.threads = options.threads;
    p.normals = sh::fibonacci_sphere(options.normal_count).directions;
    const EnvironmentMap* reference = &map;
    EnvironmentMap small;
    if (options.reference_width > 0 && map.width > options.reference_width) {
        MapOptions reduce;
        reduce.projection = map.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
        reduce.max_width = options.reference_width;
        reduce.threads = options.threads;
        Image copy(map.width, map.height, 3);
        copy.pixels = map.rgb;
        small = make_environment(copy, reduce);
        reference = &small;
    }
    p.target = exact_irradiance(*reference, p.normals, options.threads);
    if (!(p.target.cwiseAbs().maxCoeff() > 0.0)) {
        for (Light& l : lights) l.rgb.setZero(), l.power = 0.0;
        return result;
    }

    const Eigen::Index n = Eigen::Index(lights.size());
    std::vector<Eigen::Vector3d> dirs(lights.size());
    Eigen::MatrixXd x(n, 3);
    for (Eigen::Index k = 0; k < n; ++k) {
        const Light& l = lights[k];
        dirs[k] = l.direction;
        x.row(k) = l.rgb.cwiseMax(0.0).transpose();
        p.half.push_back(sun_half_angle(l.spread));
        p.start.push_back(l.direction);
        p.bound.push_back(fit_reach(map, l, options.reach));
    }
    Eigen::MatrixXd a;
    kernels(p, dirs, a, nullptr);
    result.error_before = luminance_error(a * x, p.target, options.luminance);

    // Alternate: colours for these directions, then a step of the directions.
    double mu = 1e-3;
    nonnegative_colours(a, p.target, x);
    for (int it = 0; it < options.iterations; ++it) {
        if (!direction_step(p, dirs, x, mu)) break;
        kernels(p, dirs, a, nullptr);
        nonnegative_colours(a, p.target, x);
    }
    result.error_after = luminance_error(a * x, p.target, options.luminance);

    for (Eigen::Index k = 0; k < n; ++k) {
        Light& l = lights[k];
        l.direction = dirs[k];
        l.rgb = x.row(k).transpose();
        l.power = options.luminance[0] * l.rgb[0] + options.luminance[1] * l.rgb[1] + options.luminance[2] * l.rgb[2];
    }
    return result;
}

}  // namespace penumbra::lights
