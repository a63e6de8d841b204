#include "lights/irradiance_fit.hpp"

#include <algorithm>
#include <limits>
#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/Eigenvalues>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "lights/exact_irradiance.hpp"
#include "lights/sun_irradiance.hpp"
#include "lights/sun_kernel_table.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::lights {

namespace {

struct Problem {
    std::vector<Eigen::Vector3d> normals;
    Eigen::MatrixXd target;        // M × 3
    std::vector<Eigen::Vector3d> start;
    std::vector<double> bound;     // max angle from start
    double max_half = 0.0;         // > 0: half-angles are fitted in [0, max_half]
    bool upper_hemisphere = false; // a hemispherical map's lights stay at z ≥ 0
    Eigen::MatrixXd prior;         // N × 3 expected colours (empty: none)
    double ridge = 0.0;            // weight of ‖x − prior‖²
    Eigen::RowVector3d flux;       // the map's ∫L dω per channel, the colours' sum (keep_flux)
    double flux_weight = 0.0;      // weight of Σ_c (Σ_k x_kc − flux_c)²; 0: free
    SunModel model = SunModel::blender4_cone;
    int threads = 0;
};

// What the fit moves: each light's direction and its sun's half-angle.
struct Shape {
    std::vector<Eigen::Vector3d> dirs;
    std::vector<double> half;
};

// A(i, k) = K(n_i·d_k, h_k); with slopes, also ∂K/∂c and ∂K/∂h.
void kernels(const Problem& p, const Shape& s, Eigen::MatrixXd& a, Eigen::MatrixXd* slope, Eigen::MatrixXd* dh) {
    const Eigen::Index m = Eigen::Index(p.normals.size()), n = Eigen::Index(s.dirs.size());
    std::vector<TabulatedSun> suns;
    suns.reserve(s.dirs.size());
    for (double h : s.half) suns.emplace_back(h, p.model);
    a.resize(m, n);
    if (slope) slope->resize(m, n);
    if (dh) dh->resize(m, n);
    parallel_for(std::size_t(m), {p.threads, 64, "lights.irradiance_fit"}, [&](std::size_t b, std::size_t e) {
        for (Eigen::Index i = Eigen::Index(b); i < Eigen::Index(e); ++i)
            for (Eigen::Index k = 0; k < n; ++k) {
                const SunKernelValue v = suns[std::size_t(k)](p.normals[i].dot(s.dirs[k]));
                a(i, k) = v.value;
                if (slope) (*slope)(i, k) = v.slope;
                if (dh) (*dh)(i, k) = v.angle_slope;
            }
    });
}

// aᵀb, its column blocks on the worker threads (Eigen's own products run
// on one).
Eigen::MatrixXd product_tn(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, int threads) {
    Eigen::MatrixXd out(a.cols(), b.cols());
    parallel_for(std::size_t(b.cols()), {threads, 32, "lights.irradiance_fit"}, [&](std::size_t c0, std::size_t c1) {
        out.middleCols(Eigen::Index(c0), Eigen::Index(c1 - c0)) =
            a.transpose() * b.middleCols(Eigen::Index(c0), Eigen::Index(c1 - c0));
    });
    return out;
}

// aᵀa: each block of rows of its upper triangle on a worker thread, then mirrored.
Eigen::MatrixXd gram(const Eigen::MatrixXd& a, int threads) {
    const Eigen::Index q = a.cols();
    Eigen::MatrixXd out(q, q);
    parallel_for(std::size_t(q), {threads, 48, "lights.irradiance_fit"}, [&](std::size_t r0, std::size_t r1) {
        const Eigen::Index b = Eigen::Index(r0), rows = Eigen::Index(r1 - r0);
        out.block(b, b, rows, q - b) = a.middleCols(b, rows).transpose() * a.rightCols(q - b);
    });
    out.triangularView<Eigen::StrictlyLower>() = out.transpose();
    return out;
}

// min ‖A x − t‖² over x ≥ 0 for one channel, on the normal equations
// G x = b: projected coordinate descent sweeps, each round finished by the
// exact solve on the lights it left lit (lights on one sun have nearly equal
// columns, where coordinate descent alone crawls), stepped back to x ≥ 0.
void nonnegative_channel(const Eigen::MatrixXd& g, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    const Eigen::Index n = g.rows();
    const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
    x = x.cwiseMax(0.0);
    Eigen::VectorXd grad = g * x - b;
    for (int round = 0; round < 20; ++round) {
        double largest = 0.0;
        for (int sweep = 0; sweep < 10; ++sweep) {
            largest = 0.0;
            for (Eigen::Index k = 0; k < n; ++k) {
                const double delta = std::max(0.0, x[k] - grad[k] / g(k, k)) - x[k];
                if (delta == 0.0) continue;
                grad += delta * g.col(k);
                x[k] += delta;
                largest = std::max(largest, std::abs(delta) * g(k, k));
            }
        }
        std::vector<Eigen::Index> lit;
        for (Eigen::Index k = 0; k < n; ++k)
            if (x[k] > 0.0) lit.push_back(k);
        if (lit.empty()) return;
        const Eigen::Index f = Eigen::Index(lit.size());
        Eigen::MatrixXd gf(f, f);
        Eigen::VectorXd bf(f), xf(f);
        for (Eigen::Index i = 0; i < f; ++i) {
            for (Eigen::Index j = 0; j < f; ++j) gf(i, j) = g(lit[i], lit[j]);
            bf[i] = b[lit[i]];
            xf[i] = x[lit[i]];
        }
        const Eigen::VectorXd exact = gf.ldlt().solve(bf);
        if (!exact.allFinite()) return;
        // Longest step towards the exact solve that keeps x ≥ 0 (convex: the error drops).
        double step = 1.0;
        for (Eigen::Index i = 0; i < f; ++i)
            if (exact[i] < 0.0) step = std::min(step, xf[i] / (xf[i] - exact[i]));
        for (Eigen::Index i = 0; i < f; ++i) x[lit[i]] = std::max(0.0, xf[i] + step * (exact[i] - xf[i]));
        grad = g * x - b;
        if (step == 1.0 && largest < 1e-10 * scale) return;
    }
}

// Every channel's colours for kernel matrix A, warm-started at x, with the
// prior's ridge when there is one.
void nonnegative_colours(const Problem& p, const Eigen::MatrixXd& a, Eigen::MatrixXd& x) {
    Eigen::MatrixXd g = gram(a, p.threads);
    Eigen::MatrixXd b = a.transpose() * p.target;
    // A whisper of ridge keeps coincident lights' blocks from being singular.
    g.diagonal().array() += 1e-12 * std::max(g.diagonal().maxCoeff(), 1e-300);
    if (p.prior.size()) {
        g.diagonal().array() += p.ridge;
        b += p.ridge * p.prior;
    }
    if (p.flux_weight > 0.0) {
        g.array() += p.flux_weight;
        b.rowwise() += p.flux_weight * p.flux;
    }
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
        Eigen::VectorXd xc = x.col(c);
        nonnegative_channel(g, b.col(c), xc);
        x.col(c) = xc;
    }
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

// A trial shape: each direction moved in its tangent plane and held within
// its bound, each half-angle moved and clamped.
Shape trial_shape(const Problem& p, const Shape& s, const Eigen::VectorXd& step, int per_light) {
    Shape out = s;
    if (!step.allFinite()) return out;
    for (std::size_t k = 0; k < s.dirs.size(); ++k) {
        const Eigen::Index o = Eigen::Index(k) * per_light;
        out.dirs[k] = moved(s.dirs[k], step[o], step[o + 1], p.start[k], p.bound[k]);
        if (p.upper_hemisphere && out.dirs[k].z() < 0.0) {
            // Onto the horizon (a light of a hemispherical map is never below it).
            const Eigen::Vector3d flat(out.dirs[k].x(), out.dirs[k].y(), 0.0);
            out.dirs[k] = flat.norm() > 1e-12 ? Eigen::Vector3d(flat.normalized()) : s.dirs[k];
        }
        // K is nearly flat in h for a narrow sun (1 − O(h²)), where the
        // Gauss–Newton step can be huge: at most half of h (or of a degree).
        if (per_light == 3) {
            const double most = 0.5 * std::max(s.half[k], 0.0175);
            out.half[k] = std::clamp(s.half[k] + std::clamp(step[o + 2], -most, most), 0.0, p.max_half);
        }
    }
    return out;
}

// g(i,(k,α)) = ∂K(n_i·d_k, h_k)/∂α: K'·(n_i·t_kα) along the two tangent
// directions t_kα, and ∂K/∂h for the angle.
Eigen::MatrixXd shape_jacobian(const Problem& p, const Shape& s, const Eigen::MatrixXd& slope,
                               const Eigen::MatrixXd& dh, int per_light) {
    const Eigen::Index m = Eigen::Index(p.normals.size()), n = Eigen::Index(s.dirs.size());
    Eigen::MatrixXd g(m, per_light * n);
    for (Eigen::Index k = 0; k < n; ++k) {
        Eigen::Vector3d u, v;
        tangent_frame(s.dirs[k], u, v);
        for (Eigen::Index i = 0; i < m; ++i) {
            g(i, per_light * k) = slope(i, k) * p.normals[i].dot(u);
            g(i, per_light * k + 1) = slope(i, k) * p.normals[i].dot(v);
            if (per_light == 3) g(i, per_light * k + 2) = dh(i, k);
        }
    }
    return g;
}

// Gauss–Newton matrix of the shape with the colours re-solved (variable
// projection, Kaufman's form). For fixed colours the residual's Jacobian in
// channel c is J_c = g·diag(x_c); once the colours follow, only its part
// outside the span of the lit lights' kernel columns A_U counts:
//   H = Σ_c diag(x_c) gᵀ(I − P_U) g diag(x_c) = Σ_c (x_c x_cᵀ) ∘ (gᵀg − Cᵀ G⁺ C),
//   C = A_Uᵀ g, G = A_Uᵀ A_U,
// U the lights lit in any channel (one dark in a channel is treated as free
// there too: a slightly smaller H, which the damping absorbs). G⁺ drops
// eigenvalues below 1e-12 of the largest: lights on one sun have nearly
// equal columns. `unprojected` gets the diagonal of Σ_c (x_c x_cᵀ) ∘ (gᵀg),
// the damping's scale.
Eigen::MatrixXd projected_gauss_newton(const Problem& p, const Eigen::MatrixXd& a, const Eigen::MatrixXd& g,
                                       const Eigen::MatrixXd& x, int per_light, Eigen::VectorXd& unprojected) {
    const Eigen::Index n = a.cols(), q = g.cols();
    Eigen::MatrixXd curvature = gram(g, p.threads);
    std::vector<Eigen::Index> lit;
    for (Eigen::Index k = 0; k < n; ++k)
        if (x.row(k).maxCoeff() > 0.0) lit.push_back(k);
    if (!lit.empty()) {
        Eigen::MatrixXd au(a.rows(), Eigen::Index(lit.size()));
        for (std::size_t i = 0; i < lit.size(); ++i) au.col(Eigen::Index(i)) = a.col(lit[i]);
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram(au, p.threads));
        const Eigen::VectorXd lambda = eig.eigenvalues();
        const double cut = 1e-12 * std::max(lambda.maxCoeff(), 1e-300);
        Eigen::VectorXd root(lambda.size());
        for (Eigen::Index i = 0; i < lambda.size(); ++i) root[i] = lambda[i] > cut ? 1.0 / std::sqrt(lambda[i]) : 0.0;
        // Cᵀ G⁺ C = WᵀW with W = Λ^{-1/2} Vᵀ C.
        const Eigen::MatrixXd w = root.asDiagonal() * eig.eigenvectors().transpose() * product_tn(au, g, p.threads);
        curvature -= gram(w, p.threads);
    }
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(q, q);
    unprojected = Eigen::VectorXd::Zero(q);
    const Eigen::VectorXd gg = g.colwise().squaredNorm().transpose();
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
        Eigen::VectorXd xs(q);
        for (Eigen::Index r = 0; r < q; ++r) xs[r] = x(r / per_light, c);
        h += (xs * xs.transpose()).cwiseProduct(curvature);
        unprojected += xs.cwiseAbs2().cwiseProduct(gg);
    }
    return h;
}

// Σ_c min over x_c ≥ 0 of ‖A x_c − t_c‖² for a shape; x warm-starts and is updated.
double objective(const Problem& p, const Eigen::MatrixXd& a, const Eigen::MatrixXd& x) {
    double f = (a * x - p.target).squaredNorm();
    if (p.prior.size()) f += p.ridge * (x - p.prior).squaredNorm();
    if (p.flux_weight > 0.0) f += p.flux_weight * (x.colwise().sum() - p.flux).squaredNorm();
    return f;
}

double solved_objective(const Problem& p, const Shape& s, Eigen::MatrixXd& x) {
    Eigen::MatrixXd a;
    kernels(p, s, a, nullptr, nullptr);
    nonnegative_colours(p, a, x);
    return objective(p, a, x);
}

// One Levenberg–Marquardt step of every light's shape with the colours
// re-solved at each trial; `error` is the current squared error, updated.
// Damping is scaled by the unprojected curvature: the projected one is ~0
// along moves the colours absorb (lights on one sun), where an undamped
// step would be unbounded.
bool shape_step(const Problem& p, Shape& s, Eigen::MatrixXd& x, double& mu, double& error) {
    const int per_light = p.max_half > 0.0 ? 3 : 2;
    const Eigen::Index q = per_light * Eigen::Index(s.dirs.size());
    Eigen::MatrixXd a, slope, dh;
    kernels(p, s, a, &slope, per_light == 3 ? &dh : nullptr);
    const Eigen::MatrixXd residual = a * x - p.target;
    const Eigen::MatrixXd g = shape_jacobian(p, s, slope, dh, per_light);
    Eigen::VectorXd scale;
    const Eigen::MatrixXd h = projected_gauss_newton(p, a, g, x, per_light, scale);
    const Eigen::MatrixXd gr = g.transpose() * residual;  // q × 3
    Eigen::VectorXd grad(q);
    for (Eigen::Index r = 0; r < q; ++r) grad[r] = gr.row(r).dot(x.row(r / per_light));
    const double floor = 1e-12 * std::max(scale.maxCoeff(), 1e-300);
    for (int attempt = 0; attempt < 8; ++attempt) {
        Eigen::MatrixXd damped = h;
        damped.diagonal() += (mu * scale.array() + floor).matrix();
        const Shape trial = trial_shape(p, s, damped.ldlt().solve(-grad), per_light);
        Eigen::MatrixXd xt = x;
        const double after = solved_objective(p, trial, xt);
        if (after < error) {
            s = trial;
            x = xt;
            error = after;
            mu = std::max(mu / 3.0, 1e-9);
            return true;
        }
        mu *= 4.0;
    }
    return false;
}

void check_options(const IrradianceFitOptions& options, std::size_t lights) {
    if (options.normal_count != 0 && options.normal_count < 16)
        throw ArgumentError("the irradiance fit needs at least 16 normals (0: automatic)");
    if (options.reference_width < 0) throw ArgumentError("reference_width must be >= 0 (0: the full map)");
    if (options.iterations < 0) throw ArgumentError("the irradiance fit's iterations must be >= 0");
    if (!(options.tolerance >= 0.0)) throw ArgumentError("the irradiance fit's tolerance must be >= 0");
    if (!(options.reach >= 0.0)) throw ArgumentError("the irradiance fit's reach must be >= 0");
    if (!options.move_bound.empty() && options.move_bound.size() != lights)
        throw ArgumentError("move_bound needs one angle per light");
    if (!options.prior_rgb.empty() && options.prior_rgb.size() != lights)
        throw ArgumentError("prior_rgb needs one colour per light");
    if (!(options.prior_weight >= 0.0)) throw ArgumentError("the prior's weight must be >= 0");
    for (double b : options.move_bound)
        if (!(b >= 0.0)) throw ArgumentError("every move_bound must be >= 0");
}

// The target: the exact irradiance of the map (or of an energy-exact
// reduced copy) on the fitting normals.
Eigen::MatrixXd target_irradiance(const EnvironmentMap& map, const std::vector<Eigen::Vector3d>& normals,
                                  const IrradianceFitOptions& options) {
    if (options.reference_width == 0 || map.width <= options.reference_width)
        return IrradianceReference(map).evaluate(normals, options.threads);
    MapOptions reduce;
    reduce.projection = map.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
    reduce.max_width = options.reference_width;
    reduce.threads = options.threads;
    Image copy(map.width, map.height, 3);
    copy.pixels = map.rgb;
    return IrradianceReference(make_environment(copy, reduce)).evaluate(normals, options.threads);
}

}  // namespace

double fit_reach(const EnvironmentMap& map, const Light& light, double reach) {
    if (std::isinf(reach)) return reach;
    const double row_angle = map.theta_max() / std::max(1, map.height);
    return reach * std::max(light.spread, row_angle);
}

namespace {

// The problem and the starting shape and colours of `lights`.
Problem make_problem(const EnvironmentMap& map, const std::vector<Light>& lights, const IrradianceFitOptions& options,
                     Shape& shape, Eigen::MatrixXd& x) {
    Problem p;
    p.model = options.sun_model;
    p.threads = options.threads;
    p.upper_hemisphere = !map.full_sphere;
    // Six normals per light (18 residuals for its 6 unknowns), at least 642.
    const int normals = options.normal_count > 0 ? options.normal_count
                                                 : std::clamp(6 * int(lights.size()), 642, 2562);
    p.normals = sh::fibonacci_sphere(normals).directions;
    p.target = target_irradiance(map, p.normals, options);
    const double widest = p.model == SunModel::blender3_disc ? max_disc_half_angle : 0.5 * std::numbers::pi;
    p.max_half = options.fit_angles && p.model != SunModel::point ? widest : 0.0;
    const Eigen::Index n = Eigen::Index(lights.size());
    x.resize(n, 3);
    for (Eigen::Index k = 0; k < n; ++k) {
        const Light& l = lights[std::size_t(k)];
        shape.dirs.push_back(l.direction);
        const double h = sun_half_angle(l.spread);
        shape.half.push_back(options.fit_angles ? std::min(h, widest) : h);
        x.row(k) = l.rgb.cwiseMax(0.0).transpose();
        p.start.push_back(l.direction);
        p.bound.push_back(options.move_bound.empty() ? fit_reach(map, l, options.reach)
                                                     : options.move_bound[std::size_t(k)]);
    }
    if (!options.prior_rgb.empty() && options.prior_weight > 0.0) {
        Eigen::MatrixXd a;
        kernels(p, shape, a, nullptr, nullptr);
        p.prior.resize(n, 3);
        for (Eigen::Index k = 0; k < n; ++k) p.prior.row(k) = options.prior_rgb[std::size_t(k)].transpose();
        p.ridge = options.prior_weight * a.colwise().squaredNorm().mean();
    }
    return p;
}

// The colours once more for the final shape, their sum held to the map's
// ∫L dω by a penalty strong enough that it is off by ~1e-8 (rank one on the
// normal equations: with G ≈ diagonal the sum's error shrinks by
// 1 + w·N/mean G_kk), then rescaled to it exactly.
void hold_the_flux(const EnvironmentMap& map, const Shape& shape, Problem& p, Eigen::MatrixXd& x) {
    Eigen::MatrixXd a;
    kernels(p, shape, a, nullptr, nullptr);
    p.flux = integral_rgb(map).transpose();
    p.flux_weight = 1e4 * a.colwise().squaredNorm().mean() / double(x.rows());
    nonnegative_colours(p, a, x);
    for (int c = 0; c < 3; ++c) {
        const double sum = x.col(c).sum();
        if (sum > 0.0) x.col(c) *= p.flux[c] / sum;
    }
}

// EEVEE Next cuts a shadowed sun under each receiver's horizon
// (eevee_next_shadowed); the flux held, only narrower suns lose less. The
// shape is fitted as the cone, whose kernel the fit converges on, then the
// suns are narrowed by the factor, of these, whose colours (solved again,
// flux held) light the fit's normals closest to the map as EEVEE draws them.
constexpr double eevee_narrowing[] = {1.0, 0.7, 0.5, 0.35, 0.25, 0.15};

void narrow_for_eevee(const EnvironmentMap& map, Shape& shape, Problem& p, Eigen::MatrixXd& x,
                      const IrradianceFitOptions& options) {
    p.model = SunModel::eevee_next_shadowed;
    Shape best = shape;
    Eigen::MatrixXd best_x = x;
    double best_error = std::numeric_limits<double>::infinity();
    for (double factor : eevee_narrowing) {
        Shape narrowed = shape;
        for (double& h : narrowed.half) h *= factor;
        Eigen::MatrixXd colours = x;
        hold_the_flux(map, narrowed, p, colours);
        Eigen::MatrixXd a;
        kernels(p, narrowed, a, nullptr, nullptr);
        const double error = relative_rmse(a * colours, p.target, options.luminance);
        if (error < best_error) best_error = error, best = narrowed, best_x = colours;
    }
    shape = best;
    x = best_x;
}

}  // namespace

IrradianceFitResult fit_irradiance(const EnvironmentMap& map, std::vector<Light>& lights,
                                   const IrradianceFitOptions& options) {
    check_options(options, lights.size());
    IrradianceFitResult result;
    if (lights.empty() || map.width == 0) return result;
    Shape shape;
    Eigen::MatrixXd x;
    Problem p = make_problem(map, lights, options, shape, x);
    if (!(p.target.cwiseAbs().maxCoeff() > 0.0)) {
        for (Light& l : lights) l.rgb.setZero(), l.power = 0.0;
        return result;
    }
    Eigen::MatrixXd a;
    kernels(p, shape, a, nullptr, nullptr);
    result.error_before = relative_rmse(a * x, p.target, options.luminance);
    const bool for_eevee_next = p.model == SunModel::eevee_next_shadowed;
    if (for_eevee_next) p.model = SunModel::blender4_cone;

    double mu = 0.1;
    double error = solved_objective(p, shape, x);
    for (int it = 0; it < options.iterations; ++it) {
        const double before = error;
        if (!shape_step(p, shape, x, mu, error)) break;
        ++result.steps;
        if (before - error < options.tolerance * before) break;
    }
    if (options.keep_flux) hold_the_flux(map, shape, p, x);
    if (for_eevee_next && p.max_half > 0.0) narrow_for_eevee(map, shape, p, x, options);
    p.model = options.sun_model;
    kernels(p, shape, a, nullptr, nullptr);
    result.error_after = relative_rmse(a * x, p.target, options.luminance);

    for (std::size_t k = 0; k < lights.size(); ++k) {
        Light& l = lights[k];
        l.direction = shape.dirs[k];
        // The add-on draws a sun of half-angle √2·spread (sun_half_angle).
        if (p.max_half > 0.0) l.spread = shape.half[k] / std::numbers::sqrt2;
        l.rgb = x.row(Eigen::Index(k)).transpose();
        l.power = options.luminance[0] * l.rgb[0] + options.luminance[1] * l.rgb[1] + options.luminance[2] * l.rgb[2];
    }
    return result;
}

}  // namespace penumbra::lights
