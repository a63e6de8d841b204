#include "lights/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "common/math.hpp"
#include "common/parallel.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

// Cumulative sums normalized to end at 1; all-zero input gives a uniform CDF.
std::vector<double> make_cdf(const double* mass, int n) {
    std::vector<double> cdf(std::size_t(n) + 1, 0.0);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += mass[i];
    if (!(sum > 0.0) || !std::isfinite(sum)) {
        for (int i = 0; i <= n; ++i) cdf[i] = double(i) / n;
        return cdf;
    }
    double run = 0.0;
    for (int i = 0; i < n; ++i) {
        run += mass[i];
        cdf[i + 1] = run / sum;
    }
    cdf[n] = 1.0;
    return cdf;
}

// Index i with cdf[i] <= u < cdf[i+1] and cdf[i+1] > cdf[i] (a cell with mass),
// and the fraction of u inside it.
int invert_cdf(const std::vector<double>& cdf, double u, double& fraction) {
    const int n = int(cdf.size()) - 1;
    u = std::clamp(u, 0.0, 1.0);
    int i = int(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1;
    i = std::clamp(i, 0, n - 1);
    while (i < n - 1 && cdf[i + 1] <= cdf[i]) ++i;  // skip empty cells
    while (i > 0 && cdf[i + 1] <= cdf[i]) --i;
    const double width = cdf[i + 1] - cdf[i];
    fraction = width > 0.0 ? std::clamp((u - cdf[i]) / width, 0.0, 1.0) : 0.5;
    return i;
}

double wrap01(double x) { return x - std::floor(x); }

// The distribution's geometry shared by both samplers.
struct Grid {
    int width, height;
    double theta_max;
    std::vector<double> row_cdf;                 // marginal, height + 1
    std::vector<std::vector<double>> col_cdf;    // conditional, width + 1 each

    explicit Grid(const LuminanceDistribution& d)
        : width(d.width), height(d.height),
          theta_max(d.full_sphere ? latlong::full_sphere : latlong::upper_hemisphere) {
        // A black map samples as a uniform one (the lights carry no power).
        std::vector<double> weight = d.weight, rows = d.row_mass;
        if (!(d.total > 0.0) || !std::isfinite(d.total)) {
            for (int r = 0; r < height; ++r) {
                const double omega = latlong::pixel_solid_angle(r, height, width, theta_max);
                std::fill(weight.begin() + std::size_t(r) * width, weight.begin() + std::size_t(r + 1) * width, omega);
                rows[r] = omega * width;
            }
        }
        row_cdf = make_cdf(rows.data(), height);
        col_cdf.resize(height);
        for (int r = 0; r < height; ++r) col_cdf[r] = make_cdf(weight.data() + std::size_t(r) * width, width);
        // A row without mass is never chosen, but Havran's interpolation
        // blends it with its neighbours: give it the nearest lit row's CDF so
        // the blend does not send samples to dark columns.
        int last_lit = -1;
        std::vector<int> nearest(height, -1);
        for (int r = 0; r < height; ++r) {
            if (rows[r] > 0.0) last_lit = r;
            nearest[r] = last_lit;
        }
        int next_lit = -1;
        for (int r = height - 1; r >= 0; --r) {
            if (rows[r] > 0.0) next_lit = r;
            if (rows[r] > 0.0) continue;
            const int a = nearest[r], b = next_lit;
            const int pick = a < 0 ? b : (b < 0 ? a : (r - a <= b - r ? a : b));
            if (pick >= 0) col_cdf[r] = col_cdf[pick];
        }
    }

    Eigen::Vector3d direction(double theta, double x) const {
        return latlong::direction_of_angles(theta, latlong::phi_of_x(x, width));
    }
    // Column coordinate x ∈ [0, W) of a direction's azimuth.
    double column_of(const Eigen::Vector3d& d) const {
        return std::min(latlong::x_of_phi(latlong::phi_of_direction(d), width), std::nextafter(double(width), 0.0));
    }
};

class StandardSampler final : public Sampler {
public:
    explicit StandardSampler(const LuminanceDistribution& d) : g_(d) {}

    Sample sample(double u, double v) const override {
        double fy, fx;
        const int r = invert_cdf(g_.row_cdf, u, fy);
        const int c = invert_cdf(g_.col_cdf[r], v, fx);
        return {g_.direction(latlong::theta_of_y(r + fy, g_.height, g_.theta_max), c + fx), r, c};
    }

    Eigen::Vector2d invert(const Eigen::Vector3d& d) const override {
        const double theta = latlong::theta_of_direction(d);
        const double y = std::clamp(theta / g_.theta_max * g_.height, 0.0, std::nextafter(double(g_.height), 0.0));
        const int r = int(y);
        const double x = g_.column_of(d);
        const int c = int(x);
        const auto& M = g_.row_cdf;
        const auto& C = g_.col_cdf[r];
        return {M[r] + (y - r) * (M[r + 1] - M[r]), C[c] + (x - c) * (C[c + 1] - C[c])};
    }

private:
    Grid g_;
};

class HavranSampler final : public Sampler {
public:
    explicit HavranSampler(const LuminanceDistribution& d) : g_(d) {
        const double span = 1.0 - std::cos(g_.theta_max);
        t_edge_.resize(std::size_t(g_.height) + 1);
        for (int r = 0; r <= g_.height; ++r)
            t_edge_[r] = (1.0 - std::cos(latlong::theta_of_y(r, g_.height, g_.theta_max))) / span;
        t_edge_[g_.height] = 1.0;
        t_centre_.resize(g_.height);
        for (int r = 0; r < g_.height; ++r) t_centre_[r] = 0.5 * (t_edge_[r] + t_edge_[r + 1]);
    }

    Sample sample(double u, double v) const override {
        // 1. Concentric map to the disc.
        const Eigen::Vector2d disc = concentric_square_to_disc(u, v);
        const double xi_t = std::min(1.0, disc.squaredNorm());
        const double xi_phi = wrap01(std::atan2(disc.y(), disc.x()) / (2.0 * pi));
        // 2. Area coordinate t by the marginal CDF (linear inside a row).
        double ft;
        const int r = invert_cdf(g_.row_cdf, xi_t, ft);
        const double t = t_edge_[r] + ft * (t_edge_[r + 1] - t_edge_[r]);
        // 3. Azimuth by the interpolated conditional CDF.
        int a, b;
        double lambda;
        bracket(t, a, b, lambda);
        const auto& A = g_.col_cdf[a];
        const auto& B = g_.col_cdf[b];
        auto mixed = [&](int i) { return (1.0 - lambda) * A[i] + lambda * B[i]; };
        int lo = 0, hi = g_.width;  // find c: mixed(c) <= xi < mixed(c+1)
        while (hi - lo > 1) {
            const int mid = (lo + hi) / 2;
            if (mixed(mid) <= xi_phi) lo = mid; else hi = mid;
        }
        int c = lo;
        while (c < g_.width - 1 && mixed(c + 1) <= mixed(c)) ++c;
        const double width = mixed(c + 1) - mixed(c);
        const double fx = width > 0.0 ? std::clamp((xi_phi - mixed(c)) / width, 0.0, 1.0) : 0.5;
        // 4. Equal-area map from t to θ.
        const double theta = std::acos(std::clamp(1.0 - t * (1.0 - std::cos(g_.theta_max)), -1.0, 1.0));
        return {g_.direction(theta, c + fx), r, c};
    }

    Eigen::Vector2d invert(const Eigen::Vector3d& d) const override {
        const double z = std::clamp(d.z(), -1.0, 1.0);
        const double t = std::clamp((1.0 - z) / (1.0 - std::cos(g_.theta_max)), 0.0, 1.0);
        int r = int(std::upper_bound(t_edge_.begin(), t_edge_.end(), t) - t_edge_.begin()) - 1;
        r = std::clamp(r, 0, g_.height - 1);
        const double ft = (t - t_edge_[r]) / (t_edge_[r + 1] - t_edge_[r]);
        const auto& M = g_.row_cdf;
        const double xi_t = M[r] + ft * (M[r + 1] - M[r]);
        int a, b;
        double lambda;
        bracket(t, a, b, lambda);
        const double x = g_.column_of(d);
        const int c = int(x);
        auto mixed = [&](int i) { return (1.0 - lambda) * g_.col_cdf[a][i] + lambda * g_.col_cdf[b][i]; };
        const double xi_phi = mixed(c) + (x - c) * (mixed(c + 1) - mixed(c));
        const double radius = std::sqrt(std::max(0.0, xi_t));
        const Eigen::Vector2d disc(radius * std::cos(2 * pi * xi_phi), radius * std::sin(2 * pi * xi_phi));
        return concentric_disc_to_square(disc);
    }

private:
    // Rows a <= b whose centres bracket t and the blend weight of b.
    void bracket(double t, int& a, int& b, double& lambda) const {
        const int n = g_.height;
        if (t <= t_centre_[0]) { a = b = 0; lambda = 0.0; return; }
        if (t >= t_centre_[n - 1]) { a = b = n - 1; lambda = 0.0; return; }
        a = int(std::upper_bound(t_centre_.begin(), t_centre_.end(), t) - t_centre_.begin()) - 1;
        a = std::clamp(a, 0, n - 2);
        b = a + 1;
        lambda = std::clamp((t - t_centre_[a]) / (t_centre_[b] - t_centre_[a]), 0.0, 1.0);
    }

    Grid g_;
    std::vector<double> t_edge_, t_centre_;
};

// One discrete Lloyd step on the torus over a 1024² density grid.
std::vector<Eigen::Vector2d> relax_once(std::vector<Eigen::Vector2d> points) {
    const int n = int(points.size());
    const int buckets = std::max(1, int(std::sqrt(double(n))));
    std::vector<std::vector<int>> grid(std::size_t(buckets) * buckets);
    for (int i = 0; i < n; ++i) {
        const int bx = std::min(buckets - 1, int(points[i].x() * buckets));
        const int by = std::min(buckets - 1, int(points[i].y() * buckets));
        grid[std::size_t(by) * buckets + bx].push_back(i);
    }
    auto torus = [](double d) { return d - std::round(d); };
    constexpr int density = 1024;
    std::vector<Eigen::Vector2d> offset(n, Eigen::Vector2d::Zero());
    std::vector<int> hits(n, 0);
    for (int sy = 0; sy < density; ++sy) {
        for (int sx = 0; sx < density; ++sx) {
            const Eigen::Vector2d s((sx + 0.5) / density, (sy + 0.5) / density);
            const int bx = int(s.x() * buckets), by = int(s.y() * buckets);
            int best = -1;
            double best_d2 = 1e9;
            for (int ring = 1; ring <= buckets; ++ring) {
                for (int dy = -ring; dy <= ring; ++dy)
                    for (int dx = -ring; dx <= ring; ++dx) {
                        const int gx = ((bx + dx) % buckets + buckets) % buckets;
                        const int gy = ((by + dy) % buckets + buckets) % buckets;
                        for (int i : grid[std::size_t(gy) * buckets + gx]) {
                            const double ex = torus(points[i].x() - s.x()), ey = torus(points[i].y() - s.y());
                            const double d2 = ex * ex + ey * ey;
                            if (d2 < best_d2 || (d2 == best_d2 && i < best)) { best_d2 = d2; best = i; }
                        }
                    }
                // Everything within `ring` buckets has been seen: stop once the
                // best point is closer than the unseen ones can be.
                const double safe = double(ring) / buckets;
                if (best >= 0 && best_d2 <= safe * safe) break;
            }
            offset[best] += Eigen::Vector2d(torus(s.x() - points[best].x()), torus(s.y() - points[best].y()));
            ++hits[best];
        }
    }
    for (int i = 0; i < n; ++i)
        if (hits[i] > 0) {
            const Eigen::Vector2d p = points[i] + offset[i] / hits[i];
            points[i] = {wrap01(p.x()), wrap01(p.y())};
        }
    return points;
}

constexpr int relaxed_point_count = 4096;

const std::vector<Eigen::Vector2d>& relaxed_points() {
    static std::once_flag once;
    static std::vector<Eigen::Vector2d> points;
    std::call_once(once, [] { points = relax_once(sample_points(relaxed_point_count, false)); });
    return points;
}

}  // namespace

LuminanceDistribution luminance_distribution(const EnvironmentMap& map, const std::array<double, 3>& y, int threads) {
    LuminanceDistribution d;
    d.width = map.width;
    d.height = map.height;
    d.full_sphere = map.full_sphere;
    d.weight.assign(std::size_t(map.width) * map.height, 0.0);
    d.row_mass.assign(map.height, 0.0);
    parallel_for(std::size_t(map.height), {threads, 8, "lights.luminance"}, [&](std::size_t b, std::size_t e) {
        for (int r = int(b); r < int(e); ++r) {
            const double omega = map.solid_angle(r);
            double sum = 0.0;
            for (int c = 0; c < map.width; ++c) {
                const float* p = map.pixel(r, c);
                // Sanitized maps only hold finite non-negative values; guard anyway.
                double lum = y[0] * p[0] + y[1] * p[1] + y[2] * p[2];
                if (!(lum > 0.0) || !std::isfinite(lum)) lum = 0.0;
                const double w = lum * omega;
                d.weight[std::size_t(r) * map.width + c] = w;
                sum += w;
            }
            d.row_mass[r] = sum;
        }
    });
    for (double m : d.row_mass) d.total += m;
    return d;
}

std::unique_ptr<Sampler> make_sampler(SamplerKind kind, const LuminanceDistribution& distribution) {
    if (distribution.width < 1 || distribution.height < 1 ||
        distribution.weight.size() != std::size_t(distribution.width) * distribution.height)
        throw ArgumentError("cannot sample an empty luminance distribution");
    if (kind == SamplerKind::standard) return std::make_unique<StandardSampler>(distribution);
    return std::make_unique<HavranSampler>(distribution);
}

double radical_inverse(std::uint64_t index, int base) {
    const double inv = 1.0 / base;
    double f = inv, result = 0.0;
    while (index > 0) {
        result += f * double(index % base);
        index /= base;
        f *= inv;
    }
    return result;
}

std::vector<Eigen::Vector2d> sample_points(int count, bool blue_noise) {
    if (count < 0) throw ArgumentError("point count must be non-negative, got " + std::to_string(count));
    std::vector<Eigen::Vector2d> points(count);
    const std::vector<Eigen::Vector2d>* relaxed = blue_noise ? &relaxed_points() : nullptr;
    for (int k = 0; k < count; ++k) {
        if (relaxed && k < int(relaxed->size()))
            points[k] = (*relaxed)[k];
        else
            points[k] = {radical_inverse(std::uint64_t(k) + 1, 2), radical_inverse(std::uint64_t(k) + 1, 3)};
    }
    return points;
}

Eigen::Vector2d concentric_square_to_disc(double u, double v) {
    const double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
    if (a == 0.0 && b == 0.0) return {0.0, 0.0};
    double r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = (pi / 4) * (b / a);
    } else {
        r = b;
        phi = pi / 2 - (pi / 4) * (a / b);
    }
    return {r * std::cos(phi), r * std::sin(phi)};
}

Eigen::Vector2d concentric_disc_to_square(const Eigen::Vector2d& p) {
    const double x = p.x(), y = p.y();
    const double r = length_2d(x, y);
    if (r == 0.0) return {0.5, 0.5};
    double a, b;
    if (std::abs(x) >= std::abs(y)) {
        a = std::copysign(r, x);
        b = a * (4.0 / pi) * std::atan(y / x);
    } else {
        b = std::copysign(r, y);
        a = b * (4.0 / pi) * std::atan(x / y);
    }
    return {std::clamp(0.5 * (a + 1.0), 0.0, 1.0), std::clamp(0.5 * (b + 1.0), 0.0, 1.0)};
}

}  // namespace penumbra::lights
