#include "visibility/zh_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/math.hpp"
#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_operator.hpp"
#include "sh/point_sets.hpp"
#include "visibility/order_limit.hpp"

namespace penumbra::visibility {

namespace {

constexpr int max_fit_order = max_sh_order;
constexpr int max_sh = max_fit_order * max_fit_order;

void check(const ZhFitSettings& s) {
    if (s.order < 1 || s.order > max_fit_order)
        throw ArgumentError("ZH fit order must be in [1, " + std::to_string(max_fit_order) + "], got " +
                            std::to_string(s.order));
    if (s.lobes < 1 || s.lobes > max_lobes)
        throw ArgumentError("lobes must be in [1, 4], got " + std::to_string(s.lobes));
    if (s.iterations < 0) throw ArgumentError("iterations must be >= 0");
    if (!(s.axis_prior >= 0.0)) throw ArgumentError("axis_prior must be >= 0");
}

// u_l(s)_m = sqrt(4π/(2l+1)) y_lm(s): unit vectors per band (Σ_m y_lm² = (2l+1)/4π).
void band_vectors(int order, const Eigen::Vector3d& axis, double* u) {
    static const auto scale = [] {
        std::array<double, max_fit_order> s;
        for (int l = 0; l < max_fit_order; ++l) s[l] = std::sqrt(4.0 * std::numbers::pi / (2.0 * l + 1.0));
        return s;
    }();
    sh::eval_unit(order, axis, u);
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) u[sh::sh_index(l, m)] *= scale[l];
}

using LobeMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, max_lobes, max_lobes>;
using LobeVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, max_lobes, 1>;

// One band's lobe coefficients: solves a·x = b with a the lobes' Gram matrix
// plus the 1e-6 ridge, positive definite by construction, by Cholesky (LLT).
// Like the hand-written Cholesky this replaces, it never stops the fit: that
// one clamped a pivot <= 0 to 1e-150 and went on; should LLT meet such a
// pivot (only a broken input can make one), LDLT, which accepts
// semi-definite matrices, gives the solution with 0 along the null
// directions (what the clamp gave for a consistent system, without its
// 1e300-sized answers for an inconsistent one). NaN in, NaN out, as before.
// Fixed-size matrices (one per lobe count) and Eigen's closed-form inverse
// of up to 4 × 4: the dynamic-size LLT's bookkeeping took as long as the ZH
// fit's own arithmetic. The matrix is positive definite (the ridge) and
// tiny, so the inverse is as accurate here; a singular or non-finite one
// goes to LDLT as before.
template <int N>
LobeVector solve_band_fixed(const LobeMatrix& a, const LobeVector& b) {
    using Matrix = Eigen::Matrix<double, N, N>;
    Matrix inverse;
    bool invertible = false;
    Matrix(a).computeInverseWithCheck(inverse, invertible, 1e-300);
    if (invertible && inverse.allFinite()) return inverse * Eigen::Matrix<double, N, 1>(b);
    return a.ldlt().solve(b);
}

LobeVector solve_band(const LobeMatrix& a, const LobeVector& b) {
    static_assert(max_lobes == 4, "one case per lobe count");
    switch (a.rows()) {
        case 1: return solve_band_fixed<1>(a, b);
        case 2: return solve_band_fixed<2>(a, b);
        case 3: return solve_band_fixed<3>(a, b);
        default: return solve_band_fixed<4>(a, b);
    }
}

struct Problem {
    int order, lobes;
    const double* sh;
    const double* anchor;  // 2·lobes Lambert coordinates, or null
    double prior_weight;   // sqrt of the prior's weight
    int n_sh() const { return order * order; }
    int n_residuals() const { return n_sh() + (anchor ? 2 * lobes : 0); }

    // Given axis coordinates q (2·lobes), the optimal bands (lobes × order)
    // and the residual vector.
    void evaluate(const double* q, double* bands, double* residual) const {
        std::array<double, max_lobes * max_sh> u;
        for (int x = 0; x < lobes; ++x)
            band_vectors(order, lambert_to_axis(q[2 * x], q[2 * x + 1]), u.data() + x * max_sh);
        const int n = n_sh();
        for (int i = 0; i < n; ++i) residual[i] = -sh[i];
        for (int l = 0; l < order; ++l) {
            LobeMatrix a(lobes, lobes);
            LobeVector b(lobes);
            for (int x = 0; x < lobes; ++x) {
                for (int y = 0; y <= x; ++y) {
                    double s = 0.0;
                    for (int m = -l; m <= l; ++m)
                        s += u[x * max_sh + sh::sh_index(l, m)] * u[y * max_sh + sh::sh_index(l, m)];
                    a(x, y) = a(y, x) = s;
                }
                a(x, x) += 1e-6;
                double s = 0.0;
                for (int m = -l; m <= l; ++m) s += u[x * max_sh + sh::sh_index(l, m)] * sh[sh::sh_index(l, m)];
                b[x] = s;
            }
            const LobeVector g = solve_band(a, b);
            for (int x = 0; x < lobes; ++x) {
                bands[x * order + l] = g[x];
                for (int m = -l; m <= l; ++m)
                    residual[sh::sh_index(l, m)] += g[x] * u[x * max_sh + sh::sh_index(l, m)];
            }
        }
        if (anchor)
            for (int k = 0; k < 2 * lobes; ++k) residual[n + k] = prior_weight * (q[k] - anchor[k]);
    }

    double cost(const double* q, double* bands, double* residual) const {
        evaluate(q, bands, residual);
        double s = 0.0;
        for (int i = 0; i < n_residuals(); ++i) s += residual[i] * residual[i];
        return s;
    }
};

// Keeps Lambert coordinates inside the disc of radius 2.
void clamp_disc(double* q, int lobes) {
    for (int x = 0; x < lobes; ++x) {
        const double r = length_2d(q[2 * x], q[2 * x + 1]);
        if (r > 1.999) {
            q[2 * x] *= 1.999 / r;
            q[2 * x + 1] *= 1.999 / r;
        }
    }
}

// Levenberg–Marquardt over the axis coordinates q (in place). Returns the cost.
double refine(const Problem& p, double* q, double* bands, int iterations) {
    const int n_q = 2 * p.lobes, n_r = p.n_residuals();
    std::array<double, max_sh + 2 * max_lobes> r, r_try;
    std::array<double, (max_sh + 2 * max_lobes) * 2 * max_lobes> jac;
    std::array<double, max_lobes * max_fit_order> bands_try;
    double cost = p.cost(q, bands, r.data());
    double lambda = 1e-3;
    for (int it = 0; it < iterations && cost > 0.0; ++it) {
        // Forward-difference Jacobian (the bands are re-solved inside: variable projection).
        const double h = 1e-6;
        for (int k = 0; k < n_q; ++k) {
            std::array<double, 2 * max_lobes> q_h;
            std::copy(q, q + n_q, q_h.begin());
            q_h[k] += h;
            p.evaluate(q_h.data(), bands_try.data(), r_try.data());
            for (int i = 0; i < n_r; ++i) jac[i * n_q + k] = (r_try[i] - r[i]) / h;
        }
        using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * max_lobes, 2 * max_lobes>;
        using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * max_lobes, 1>;
        Small jtj = Small::Zero(n_q, n_q);
        SmallVector jtr = SmallVector::Zero(n_q);
        for (int i = 0; i < n_r; ++i)
            for (int a = 0; a < n_q; ++a) {
                jtr[a] += jac[i * n_q + a] * r[i];
                for (int b = 0; b < n_q; ++b) jtj(a, b) += jac[i * n_q + a] * jac[i * n_q + b];
            }
        bool improved = false;
        for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
            Small damped = jtj;
            for (int a = 0; a < n_q; ++a) damped(a, a) += lambda * (jtj(a, a) + 1e-9);
            const SmallVector step = damped.ldlt().solve(-jtr);
            std::array<double, 2 * max_lobes> q_try;
            for (int k = 0; k < n_q; ++k) q_try[k] = q[k] + step[k];
            clamp_disc(q_try.data(), p.lobes);
            const double c = p.cost(q_try.data(), bands_try.data(), r_try.data());
            if (c < cost) {
                const double gain = cost - c;
                std::copy(q_try.begin(), q_try.begin() + n_q, q);
                std::copy(bands_try.begin(), bands_try.begin() + p.lobes * p.order, bands);
                r = r_try;
                cost = c;
                lambda = std::max(lambda / 3.0, 1e-9);
                improved = true;
                if (gain < 1e-10 * (c + 1e-30)) it = iterations;  // converged
            } else {
                lambda *= 4.0;
            }
        }
        if (!improved) break;
    }
    return cost;
}

const std::vector<Eigen::Vector3d>& candidate_axes() {
    static const std::vector<Eigen::Vector3d> axes = sh::fibonacci_sphere(64).directions;
    return axes;
}

// The band vectors of every candidate axis at every order, computed once:
// each vertex's reference fit scores all 64 candidates per lobe.
const std::vector<std::array<double, max_sh>>& candidate_band_vectors(int order) {
    static const auto tables = [] {
        std::array<std::vector<std::array<double, max_sh>>, max_fit_order + 1> t;
        for (int o = 1; o <= max_fit_order; ++o)
            for (const auto& axis : candidate_axes()) band_vectors(o, axis, t[o].emplace_back().data());
        return t;
    }();
    return tables[order];
}

// Energy of the best single lobe with band vectors u in residual r: Σ_l (u_l·r_l)².
double lobe_energy(int order, const double* u, const double* r) {
    double e = 0.0;
    for (int l = 0; l < order; ++l) {
        double s = 0.0;
        for (int m = -l; m <= l; ++m) s += u[sh::sh_index(l, m)] * r[sh::sh_index(l, m)];
        e += s * s;
    }
    return e;
}

}  // namespace

Eigen::Vector2d axis_to_lambert(const Eigen::Vector3d& a) {
    const double one_plus_z = 1.0 + a.z();
    if (one_plus_z < 1e-12) return Eigen::Vector2d(2.0, 0.0);
    const double s = std::sqrt(2.0 / one_plus_z);
    return Eigen::Vector2d(s * a.x(), s * a.y());
}

Eigen::Vector3d lambert_to_axis(double X, double Y) {
    double r2 = X * X + Y * Y;
    if (!std::isfinite(r2)) return Eigen::Vector3d::UnitZ();
    if (r2 > 4.0) {
        const double s = 2.0 / std::sqrt(r2);
        X *= s;
        Y *= s;
        r2 = 4.0;
    }
    const double s = std::sqrt(std::max(0.0, 1.0 - r2 / 4.0));
    return Eigen::Vector3d(s * X, s * Y, 1.0 - r2 / 2.0).normalized();
}

double fit_zh_lobes(const ZhFitSettings& settings, const double* sh, const double* reference, double* params_out) {
    check(settings);
    const int order = settings.order, lobes = settings.lobes, n_sh = order * order, ppl = params_per_lobe(order);
    double norm2 = 0.0;
    for (int i = 0; i < n_sh; ++i) norm2 += sh[i] * sh[i];
    std::array<double, 2 * max_lobes> q{};
    std::array<double, max_lobes * max_fit_order> bands{};
    std::array<double, max_sh + 2 * max_lobes> residual;
    double cost;
    if (reference) {
        for (int x = 0; x < lobes; ++x) {
            q[2 * x] = reference[x * ppl];
            q[2 * x + 1] = reference[x * ppl + 1];
        }
        clamp_disc(q.data(), lobes);
        std::array<double, 2 * max_lobes> anchor = q;
        Problem p{order, lobes, sh, anchor.data(), std::sqrt(settings.axis_prior * std::max(norm2, 1e-12))};
        refine(p, q.data(), bands.data(), settings.iterations);
        Problem plain{order, lobes, sh, nullptr, 0.0};
        cost = plain.cost(q.data(), bands.data(), residual.data());
    } else {
        // Greedy deterministic start: each new lobe where the residual is largest.
        std::array<double, max_sh> r;
        std::copy(sh, sh + n_sh, r.begin());
        for (int x = 0; x < lobes; ++x) {
            std::array<double, max_sh> u;
            Eigen::Vector3d best = Eigen::Vector3d::UnitZ();
            band_vectors(order, best, u.data());
            double best_energy = lobe_energy(order, u.data(), r.data());
            if (order >= 2) {
                const Eigen::Vector3d bent(r[sh::sh_index(1, 1)], r[sh::sh_index(1, -1)], r[sh::sh_index(1, 0)]);
                if (bent.norm() > 1e-12) {
                    band_vectors(order, bent.normalized(), u.data());
                    const double e = lobe_energy(order, u.data(), r.data());
                    if (e > best_energy) best_energy = e, best = bent.normalized();
                }
            }
            const auto& candidates = candidate_band_vectors(order);
            for (std::size_t c = 0; c < candidates.size(); ++c) {
                const double e = lobe_energy(order, candidates[c].data(), r.data());
                if (e > best_energy * (1.0 + 1e-12) + 1e-300) best_energy = e, best = candidate_axes()[c];
            }
            const Eigen::Vector2d xy = axis_to_lambert(best);
            q[2 * x] = xy.x();
            q[2 * x + 1] = xy.y();
            clamp_disc(q.data(), x + 1);
            Problem p{order, x + 1, sh, nullptr, 0.0};
            refine(p, q.data(), bands.data(), settings.iterations);
            // What lobes 0..x leave for the next one.
            std::array<double, max_sh + 2 * max_lobes> res;
            p.evaluate(q.data(), bands.data(), res.data());
            for (int i = 0; i < n_sh; ++i) r[i] = -res[i];
        }
        Problem p{order, lobes, sh, nullptr, 0.0};
        cost = refine(p, q.data(), bands.data(), settings.iterations);
    }
    for (int x = 0; x < lobes; ++x) {
        params_out[x * ppl] = q[2 * x];
        params_out[x * ppl + 1] = q[2 * x + 1];
        for (int l = 0; l < order; ++l) params_out[x * ppl + 2 + l] = bands[x * order + l];
    }
    return cost;
}

void lobes_to_sh(int order, int lobes, const double* params, double* sh_out) {
    const int ppl = params_per_lobe(order);
    std::array<double, max_sh> y;
    std::fill(sh_out, sh_out + order * order, 0.0);
    for (int x = 0; x < lobes; ++x) {
        const double* p = params + x * ppl;
        band_vectors(order, lambert_to_axis(p[0], p[1]), y.data());
        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m) sh_out[sh::sh_index(l, m)] += p[2 + l] * y[sh::sh_index(l, m)];
    }
}

double ambient_occlusion(int order, const double* sh) {
    static thread_local int cached_order = 0;
    static thread_local std::vector<double> row;
    if (cached_order != order) {
        const sh::ZonalOperator t = sh::diffuse_zonal_operator(order);
        row.assign(order, 0.0);
        for (int l = 0; l < order; ++l) row[l] = t.blocks[0](0, l);
        cached_order = order;
    }
    double s = 0.0;
    for (int l = 0; l < order; ++l) s += row[l] * sh[l * (l + 1)];
    return std::sqrt(4.0 * std::numbers::pi) * s;
}

}  // namespace penumbra::visibility
