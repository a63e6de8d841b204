#include "colormap/lookup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "common/parallel.hpp"

namespace penumbra::colormap {

namespace {

constexpr double inv_sqrt_2 = 0.70710678118654752440;
constexpr double inv_sqrt_2pi = 0.39894228040143267794;
// Beyond |z| = 10 a Gaussian tail holds < 1e-23 of the mass.
constexpr double negligible_z = 10.0;

double Phi(double z) { return 0.5 * std::erfc(-z * inv_sqrt_2); }
double phi(double z) { return inv_sqrt_2pi * std::exp(-0.5 * z * z); }

// Φ(b) − Φ(a) for a <= b, from the tail on the side where it is small, so a
// narrow interval far out keeps its relative precision.
double Phi_difference(double a, double b) {
    if (a > 0.0)
        return 0.5 * (std::erfc(a * inv_sqrt_2) - std::erfc(b * inv_sqrt_2));
    return 0.5 * (std::erfc(-b * inv_sqrt_2) - std::erfc(-a * inv_sqrt_2));
}

// φ(a) − φ(b) without cancellation when a and b are close (huge σ):
// factor out the larger of the two and use expm1 for the rest.
double phi_difference(double a, double b) {
    const double half_diff_sq = 0.5 * (b - a) * (b + a);  // (b² − a²)/2
    if (std::fabs(a) <= std::fabs(b))
        return -phi(a) * std::expm1(-half_diff_sq);
    return phi(b) * std::expm1(half_diff_sq);
}

// ∫_a^b C(v) N(v; mean, σ²) dv over a linear piece of C from colour ca at a
// to cb at b, as wa·ca + wb·cb: with ΔΦ = `mass` and φ(za) − φ(zb) = `dphi`,
// wb = ΔΦ/2 + g and wa = ΔΦ − wb, where
//   g = ∫_a^b (v − x_mid)/(b − a) N dv = ((mean − x_mid) ΔΦ + σ (φ(za) − φ(zb))) / (b − a)
// lies in [−ΔΦ/2, ΔΦ/2]. Weights, not a slope: a steep piece far from a huge
// mean and σ made the slope form Inf·0 = NaN (fuzz crasher
// steep_piece_under_huge_mean_and_sigma). Clamping g to its bounds keeps the
// colour within the map's range whatever cancels.
struct PieceWeights {
    double a, b;
};
PieceWeights linear_piece_weights(double a, double b, double mean, double sigma, double mass, double dphi) {
    double g = ((mean - 0.5 * (a + b)) * mass + sigma * dphi) / (b - a);
    if (std::isnan(g)) g = 0.0;  // Inf − Inf or Inf / Inf: only at the ends of double's range
    const double piece = std::max(mass, 0.0);  // rounding may leave −1e-17
    const double wb = std::clamp(0.5 * piece + g, 0.0, piece);
    return {piece - wb, wb};
}

}  // namespace

void filtered_color(const ColorMap& map, double mean, double sigma, double* out) {
    const int channels = map.channels;
    const int n = map.knot_count();
    if (!(sigma >= 0.0))
        throw ArgumentError("the filter's standard deviation must be >= 0");
    if (std::isnan(mean)) {
        std::fill(out, out + channels, std::numeric_limits<double>::quiet_NaN());
        return;
    }
    if (sigma == 0.0 || n == 1) {
        map.evaluate(mean, out);
        return;
    }
    if (std::isinf(sigma)) {
        const double* first = map.color(0);
        const double* last = map.color(n - 1);
        for (int c = 0; c < channels; ++c)
            out[c] = 0.5 * (first[c] + last[c]);
        return;
    }
    if (std::isinf(mean)) {
        map.evaluate(mean, out);
        return;
    }
    const double* x = map.positions.data();
    auto z_of = [&](int k) { return (x[k] - mean) / sigma; };

    // Tails: C is held at the end colours outside the knots.
    const double z_first = z_of(0), z_last = z_of(n - 1);
    const double w_left = Phi(z_first);
    const double w_right = 0.5 * std::erfc(z_last * inv_sqrt_2);  // 1 − Φ(z_last)
    for (int c = 0; c < channels; ++c)
        out[c] = w_left * map.color(0)[c] + w_right * map.color(n - 1)[c];

    const bool linear = map.interpolation == MapInterpolation::linear;
    // Only knots within ±10σ of the mean matter; pieces further out hold
    // < 1e-23 of the Gaussian's mass (the tails above carry the rest).
    const int first = std::max(0, static_cast<int>(std::lower_bound(x, x + n, mean - negligible_z * sigma) - x) - 1);
    const int last = std::min(n - 1, static_cast<int>(std::upper_bound(x, x + n, mean + negligible_z * sigma) - x));
    // For σ <= 1 each knot's Φ and φ are computed once and shared by the two
    // pieces that meet there (differences lose at most ~1e-16 · slope · σ);
    // wider filters use the cancellation-free per-piece forms.
    const bool shared = sigma <= 1.0;
    double upper_prev = 0.0, lower_prev = 0.0, phi_prev = 0.0;  // Q(z), Φ(z), φ(z) at knot k
    auto knot_terms = [&](int k, double& upper, double& lower, double& density) {
        const double z = z_of(k);
        // One erfc, on the side where the tail is small and kept precisely.
        if (z > 0.0) {
            upper = 0.5 * std::erfc(z * inv_sqrt_2);
            lower = 1.0 - upper;
        } else {
            lower = 0.5 * std::erfc(-z * inv_sqrt_2);
            upper = 1.0 - lower;
        }
        density = phi(z);
    };
    if (shared && first < last)
        knot_terms(first, upper_prev, lower_prev, phi_prev);
    for (int k = first; k < last; ++k) {
        const double a = x[k], b = x[k + 1];
        double upper = 0.0, lower = 0.0, density = 0.0;
        if (shared)
            knot_terms(k + 1, upper, lower, density);
        const double za = z_of(k), zb = z_of(k + 1);
        double mass = 0.0, dphi = 0.0;
        if (b > a) {
            if (shared) {
                mass = za > 0.0 ? upper_prev - upper : lower - lower_prev;
                dphi = phi_prev - density;
            } else {
                mass = Phi_difference(za, zb);
                dphi = phi_difference(za, zb);
            }
        }
        if (shared) {
            upper_prev = upper;
            lower_prev = lower;
            phi_prev = density;
        }
        if (!(b > a))
            continue;  // a jump: no mass at a single point
        const double* ca = map.color(k);
        if (!linear) {
            for (int c = 0; c < channels; ++c)
                out[c] += mass * ca[c];
            continue;
        }
        const double* cb = map.color(k + 1);
        const PieceWeights w = linear_piece_weights(a, b, mean, sigma, mass, dphi);
        for (int c = 0; c < channels; ++c)
            out[c] += w.a * ca[c] + w.b * cb[c];
    }
}

void LookupSpec::validate() const {
    check_range("the lookup table's width", width, size_range);
    check_range("the lookup table's height", height, size_range);
    if (!std::isfinite(sigma_max))
        throw ArgumentError("sigma_max must be a finite number > 0 (the widest filter the table holds)");
    check_range("sigma_max (the widest filter the table holds)", sigma_max, sigma_max_range);
    // The width too: mean_min −1e308, mean_max 1e308 would fill the table with NaN.
    if (!std::isfinite(mean_min) || !std::isfinite(mean_max) || !(mean_max > mean_min) ||
        !std::isfinite(mean_max - mean_min))
        throw ArgumentError("the mean range must be finite with mean_min < mean_max, and its width finite");
}

double LookupSpec::mean_of_column(double x) const { return mean_min + (mean_max - mean_min) * x / (width - 1); }

double LookupSpec::sigma_of_row(double y) const {
    const double t = y / (height - 1);
    return sigma_spacing == SigmaSpacing::linear ? sigma_max * t : sigma_max * t * t;
}

double LookupSpec::column_of_mean(double mean) const { return (mean - mean_min) / (mean_max - mean_min) * (width - 1); }

double LookupSpec::row_of_sigma(double sigma) const {
    const double t = sigma / sigma_max;
    return (sigma_spacing == SigmaSpacing::linear ? t : std::sqrt(std::max(t, 0.0))) * (height - 1);
}

Image build_lookup(const ColorMap& map, const LookupSpec& spec, const Progress& progress, int threads) {
    spec.validate();
    if (map.knot_count() < 1 || map.channels < 1)
        throw ArgumentError("the colour map is empty");
    // The table is float32: a colour beyond its range would become Inf there.
    for (int k = 0; k < map.knot_count(); ++k)
        for (int c = 0; c < map.channels; ++c)
            if (!(std::fabs(map.color(k)[c]) <= std::numeric_limits<float>::max()))
                throw ArgumentError("the colour map has a value (" + std::to_string(map.color(k)[c]) +
                                    ") beyond float32's range, which the lookup image stores");
    Image table(spec.width, spec.height, map.channels);
    // A row per block: a few milliseconds even for wide tables, so cancel is prompt.
    parallel_for(std::size_t(spec.height), {threads, 1, "colormap.lookup"}, [&](std::size_t begin, std::size_t end) {
        for (int y = int(begin); y < int(end); ++y) {
            const double sigma = spec.sigma_of_row(y);
            double value[4];
            for (int x = 0; x < spec.width; ++x) {
                filtered_color(map, spec.mean_of_column(x), sigma, value);
                for (int c = 0; c < map.channels; ++c)
                    table.at(x, y, c) = static_cast<float>(value[c]);
            }
        }
    }, progress);
    return table;
}

void bilinear_lookup(const Image& table, const LookupSpec& spec, double mean, double sigma, double* out) {
    // A NaN survives std::clamp, and its cast to int reads outside the table.
    if (std::isnan(mean) || std::isnan(sigma))
        throw ArgumentError("a lookup needs a mean and a sigma that are numbers, not NaN");
    const double fx = std::clamp(spec.column_of_mean(mean), 0.0, static_cast<double>(table.width - 1));
    const double fy = std::clamp(spec.row_of_sigma(sigma), 0.0, static_cast<double>(table.height - 1));
    const int x0 = std::min(static_cast<int>(fx), table.width - 2);
    const int y0 = std::min(static_cast<int>(fy), table.height - 2);
    const double tx = fx - x0, ty = fy - y0;
    for (int c = 0; c < table.channels; ++c) {
        const double top = (1 - tx) * table.at(x0, y0, c) + tx * table.at(x0 + 1, y0, c);
        const double bottom = (1 - tx) * table.at(x0, y0 + 1, c) + tx * table.at(x0 + 1, y0 + 1, c);
        out[c] = (1 - ty) * top + ty * bottom;
    }
}

LookupAccuracy measure_lookup_accuracy(const ColorMap& map, const LookupSpec& spec, const Image& table,
                                       int probes_per_axis) {
    spec.validate();
    if (table.width != spec.width || table.height != spec.height || table.channels != map.channels)
        throw ArgumentError("the table does not have the spec's size and the map's channels");
    if (probes_per_axis < 2)
        throw ArgumentError("probes_per_axis must be at least 2");
    LookupAccuracy acc;
    double sum_sq = 0.0;
    std::size_t count = 0;
    double exact[4], looked_up[4];
    for (int j = 0; j < probes_per_axis; ++j) {
        // Probe rows spread over the row axis (the spacing's own parameter), so
        // every table row interval is visited whatever the spacing.
        const double sigma = spec.sigma_of_row((j + 0.37) / probes_per_axis * (spec.height - 1));
        for (int i = 0; i < probes_per_axis; ++i) {
            const double mean = spec.mean_of_column((i + 0.41) / probes_per_axis * (spec.width - 1));
            filtered_color(map, mean, sigma, exact);
            bilinear_lookup(table, spec, mean, sigma, looked_up);
            for (int c = 0; c < map.channels; ++c) {
                const double e = std::fabs(looked_up[c] - exact[c]);
                sum_sq += e * e;
                ++count;
                if (e > acc.max_abs_error) {
                    acc.max_abs_error = e;
                    acc.worst_mean = mean;
                    acc.worst_sigma = sigma;
                }
            }
        }
    }
    acc.rms_error = std::sqrt(sum_sq / static_cast<double>(count));
    return acc;
}

}  // namespace penumbra::colormap
