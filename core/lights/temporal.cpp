#include "lights/temporal.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

void normalize_dc(FirFilter& f) {
    double sum = 0.0;
    for (double t : f.taps) sum += t;
    for (double& t : f.taps) t /= sum;
}

// Parks–McClellan for a type I (odd length 2L+1) low-pass with equal band
// weights: Remez exchange over a dense grid of cos ω on [0, ωp] ∪ [ωs, π].
std::vector<double> remez_lowpass(int taps, double wp, double ws) {
    const int L = (taps - 1) / 2;
    const int r = L + 2;  // extremal frequencies
    std::vector<double> grid, desired;
    const int density = 32 * r;
    const double span = wp + (pi - ws);
    const int np = std::max(r, int(std::ceil(density * wp / span)));
    const int ns = std::max(r, int(std::ceil(density * (pi - ws) / span)));
    for (int i = 0; i < np; ++i) { grid.push_back(wp * i / (np - 1)); desired.push_back(1.0); }
    for (int i = 0; i < ns; ++i) { grid.push_back(ws + (pi - ws) * i / (ns - 1)); desired.push_back(0.0); }
    const int g = int(grid.size());

    std::vector<int> ext(r);
    for (int i = 0; i < r; ++i) ext[i] = int(std::lround(double(i) * (g - 1) / (r - 1)));

    std::vector<double> x(r), b(r), c(r);
    double delta = 0.0;
    auto response = [&](double w) {
        // Barycentric Lagrange interpolation through the first r−1 points.
        const double xw = std::cos(w);
        double num = 0.0, den = 0.0;
        for (int k = 0; k < r - 1; ++k) {
            const double diff = xw - x[k];
            if (std::abs(diff) < 1e-15) return c[k];
            const double t = b[k] / diff;
            num += t * c[k];
            den += t;
        }
        return num / den;
    };
    for (int iteration = 0; iteration < 100; ++iteration) {
        for (int k = 0; k < r; ++k) x[k] = std::cos(grid[ext[k]]);
        // Weights over all r points for δ.
        for (int k = 0; k < r; ++k) {
            double p = 1.0;
            for (int j = 0; j < r; ++j)
                if (j != k) p *= 2.0 * (x[k] - x[j]);
            b[k] = 1.0 / p;
        }
        double num = 0.0, den = 0.0;
        for (int k = 0; k < r; ++k) {
            num += b[k] * desired[ext[k]];
            den += ((k % 2) ? -1.0 : 1.0) * b[k];
        }
        delta = num / den;
        for (int k = 0; k < r; ++k) c[k] = desired[ext[k]] - ((k % 2) ? -1.0 : 1.0) * delta;
        // Barycentric weights over the first r−1 points for interpolation.
        for (int k = 0; k < r - 1; ++k) {
            double p = 1.0;
            for (int j = 0; j < r - 1; ++j)
                if (j != k) p *= 2.0 * (x[k] - x[j]);
            b[k] = 1.0 / p;
        }
        std::vector<double> err(g);
        for (int i = 0; i < g; ++i) err[i] = desired[i] - response(grid[i]);
        // Local extrema (band edges included), then alternation.
        std::vector<int> cand;
        for (int i = 0; i < g; ++i) {
            const bool left_edge = i == 0 || i == np;
            const bool right_edge = i == np - 1 || i == g - 1;
            const double e = err[i];
            const bool ge_left = left_edge || std::abs(e) >= std::abs(err[i - 1]);
            const bool ge_right = right_edge || std::abs(e) >= std::abs(err[i + 1]);
            if (ge_left && ge_right && std::abs(e) >= std::abs(delta) * (1 - 1e-9)) cand.push_back(i);
        }
        std::vector<int> alt;
        for (int i : cand) {
            if (!alt.empty() && (err[i] > 0) == (err[alt.back()] > 0)) {
                if (std::abs(err[i]) > std::abs(err[alt.back()])) alt.back() = i;
            } else {
                alt.push_back(i);
            }
        }
        while (int(alt.size()) > r) {
            if (std::abs(err[alt.front()]) < std::abs(err[alt.back()])) alt.erase(alt.begin());
            else alt.pop_back();
        }
        if (int(alt.size()) < r) break;  // converged as far as the grid allows
        if (alt == ext) break;
        ext = alt;
    }
    // Sample A(ω) at the DFT frequencies and invert to the impulse response.
    const int n = 2 * L + 1;
    std::vector<double> a(L + 1);
    for (int k = 0; k <= L; ++k) a[k] = response(2.0 * pi * k / n);
    std::vector<double> h(n);
    for (int m = 0; m < n; ++m) {
        double s = a[0];
        for (int k = 1; k <= L; ++k) s += 2.0 * a[k] * std::cos(2.0 * pi * k * (m - L) / n);
        h[m] = s / n;
    }
    return h;
}

}  // namespace

double FirFilter::gain(double frequency, double rate) const {
    const double w = 2.0 * pi * frequency / rate;
    const int d = delay();
    double s = 0.0;
    for (int i = 0; i < int(taps.size()); ++i) s += taps[i] * std::cos(w * (i - d));
    return std::abs(s);
}

FirFilter paper_filter() {
    FirFilter f;
    f.taps = {0.06216, 0.01296, -0.13816, 0.28315, 0.65223, 0.28315, -0.13816, 0.01296, 0.06216};
    normalize_dc(f);
    return f;
}

FirFilter design_lowpass(double rate, double pass, double stop, int taps) {
    if (!(rate > 0.0) || !(pass > 0.0) || !(stop > pass))
        throw ArgumentError("a low-pass filter needs 0 < pass < stop and a positive frame rate (got pass " +
                            std::to_string(pass) + " Hz, stop " + std::to_string(stop) + " Hz, rate " +
                            std::to_string(rate) + " Hz)");
    if (stop >= 0.5 * rate)
        throw ArgumentError("the stop frequency " + std::to_string(stop) + " Hz must lie below the Nyquist frequency " +
                            std::to_string(0.5 * rate) + " Hz of " + std::to_string(rate) + " frames per second");
    if (taps == 0) {
        // Kaiser: N − 1 ≈ (−20 log10 δ − 7.95) / (14.36 Δf), δ = 0.09 as in the paper's filter.
        const double df = (stop - pass) / rate;
        const double order = (-20.0 * std::log10(0.09) - 7.95) / (14.36 * df);
        taps = int(std::ceil(order)) + 1;
        if (taps % 2 == 0) ++taps;
        taps = std::clamp(taps, 3, 255);
    }
    if (taps < 3 || taps % 2 == 0 || taps > 1023)
        throw ArgumentError("taps must be odd and between 3 and 1023, got " + std::to_string(taps));
    FirFilter f;
    f.taps = remez_lowpass(taps, 2.0 * pi * pass / rate, 2.0 * pi * stop / rate);
    normalize_dc(f);
    return f;
}

FirFilter filter_for_rate(double rate, double pass, double stop) {
    if (!(rate > 0.0)) throw ArgumentError("the frame rate must be positive");
    if (std::abs(rate - 21.0) <= 0.5 && pass == 5.9 && stop == 8.05) return paper_filter();
    if (stop >= 0.5 * rate) {
        pass = rate * 5.9 / 21.0;
        stop = rate * 8.05 / 21.0;
    }
    return design_lowpass(rate, pass, stop);
}

std::vector<double> FirFilter::window(int t, int n) const {
    // The widest centred window that stays inside [0, n) whose taps still sum
    // to at least half (a window cut between the paper's negative taps sums
    // to 0.86), renormalized.
    for (int half = std::min({delay(), t, n - 1 - t}); half > 0; --half) {
        double sum = 0.0;
        for (int j = -half; j <= half; ++j) sum += taps[std::size_t(delay() + j)];
        if (sum < 0.5) continue;
        std::vector<double> w(std::size_t(2 * half + 1));
        for (int j = -half; j <= half; ++j) w[std::size_t(j + half)] = taps[std::size_t(delay() + j)] / sum;
        return w;
    }
    return {1.0};
}

std::vector<double> filter_sequence(const std::vector<double>& x, const FirFilter& filter) {
    const int n = int(x.size());
    std::vector<double> y(n, 0.0);
    for (int t = 0; t < n; ++t) {
        const std::vector<double> w = filter.window(t, n);
        const int half = int(w.size() / 2);
        for (int j = -half; j <= half; ++j) y[t] += w[std::size_t(j + half)] * x[t + j];
    }
    return y;
}

void filter_lights(std::vector<FrameLights>& frames, const FirFilter& filter, bool filter_brightness) {
    const int n = int(frames.size());
    if (n == 0 || filter.taps.size() <= 1) return;
    std::size_t slots = 0;
    for (const auto& f : frames) slots = std::max(slots, f.lights.size());

    // Each frame's own total (the lights' summed luminance), and filtered.
    const Eigen::Vector3d w(rec709_luminance[0], rec709_luminance[1], rec709_luminance[2]);
    std::vector<double> total(n, 0.0);
    for (int t = 0; t < n; ++t)
        for (const Light& l : frames[t].lights) total[t] += w.dot(l.rgb);
    const std::vector<double> total_f = filter_brightness ? filter_sequence(total, filter) : total;

    std::vector<std::vector<Light>> out(n);
    for (int t = 0; t < n; ++t) out[t] = frames[t].lights;
    for (std::size_t k = 0; k < slots; ++k) {
        // Per-frame values of light k (missing → power 0, nearest frame's direction).
        std::vector<Eigen::Vector3d> dir(n), rgb(n, Eigen::Vector3d::Zero());
        std::vector<double> spread(n, 0.0);
        std::vector<bool> present(n, false);
        for (int t = 0; t < n; ++t)
            if (k < frames[t].lights.size()) {
                present[t] = true;
                dir[t] = frames[t].lights[k].direction;
                rgb[t] = frames[t].lights[k].rgb;
                spread[t] = frames[t].lights[k].spread;
            }
        for (int t = 0; t < n; ++t)
            if (!present[t])
                for (int step = 1; step < n; ++step) {
                    if (t - step >= 0 && present[t - step]) { dir[t] = dir[t - step]; spread[t] = spread[t - step]; break; }
                    if (t + step < n && present[t + step]) { dir[t] = dir[t + step]; spread[t] = spread[t + step]; break; }
                }
        for (int t = 0; t < n; ++t) {
            if (k >= out[t].size()) continue;
            Eigen::Vector3d v = Eigen::Vector3d::Zero(), c = Eigen::Vector3d::Zero();
            double s = 0.0;
            const std::vector<double> w = filter.window(t, n);
            const int half = int(w.size() / 2);
            for (int j = -half; j <= half; ++j) {
                v += w[std::size_t(j + half)] * dir[t + j];
                c += w[std::size_t(j + half)] * rgb[t + j];
                s += w[std::size_t(j + half)] * spread[t + j];
            }
            Light& l = out[t][k];
            if (v.norm() > 1e-6) l.direction = v.normalized();
            l.rgb = c.cwiseMax(0.0);
            l.spread = std::max(0.0, s);
        }
    }
    // Each frame's sum back to its own total, or to the filtered one.
    for (int t = 0; t < n; ++t) {
        double sum = 0.0;
        for (auto& l : out[t]) {
            l.power = w.dot(l.rgb);
            sum += l.power;
        }
        const double target = std::max(0.0, total_f[t]);
        if (sum > 0.0) {
            const double scale = target / sum;
            for (auto& l : out[t]) {
                l.rgb *= scale;
                l.power *= scale;
            }
        }
        frames[t].total_rgb = Eigen::Vector3d::Zero();
        frames[t].total_power = 0.0;
        for (const auto& l : out[t]) {
            frames[t].total_rgb += l.rgb;
            frames[t].total_power += l.power;
        }
        frames[t].lights = std::move(out[t]);
    }
}

}  // namespace penumbra::lights
