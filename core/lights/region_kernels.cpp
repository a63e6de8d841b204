// region_kernels.hpp, compiled once per SIMD target by Highway's
// foreach_target and chosen at run time by its dynamic dispatch, in the
// manner of sh/pose_shading_kernel.cpp: every per-cell quantity is a lane
// vector of doubles (GCC/Clang vector extensions, which Highway's per-target
// `#pragma GCC target` turns into that target's instructions), a partial
// batch repeats its last cell in the spare lanes, and choices are lane masks.

#ifndef HWY_COMPILE_ALL_ATTAINABLE
#define HWY_COMPILE_ALL_ATTAINABLE
#endif
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS HWY_SSSE3
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "lights/region_kernels.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "lights/region_kernels.hpp"

#ifndef PENUMBRA_LIGHTS_REGION_KERNELS_ONCE
#define PENUMBRA_LIGHTS_REGION_KERNELS_ONCE
namespace penumbra::lights::detail {

// θ² = 4 asin²(√u) = Σ_n 2(4u)ⁿ/(n² C(2n, n)), u = c²/4 for the chord c
// (θ = 2 asin(c/2)); the terms shrink by at least u each, so 8 terms are
// exact to ~2e-16 for u ≤ 1/64 (θ ≤ 14.4°) and 14 to ~1e-16 for u ≤ 1/16
// (θ ≤ 29°).
constexpr int asin2_terms = 14;
constexpr std::array<double, asin2_terms> asin2_series = [] {
    std::array<double, asin2_terms> a{};
    double central = 1.0, power = 1.0;  // C(2n, n), 4ⁿ
    for (int n = 1; n <= asin2_terms; ++n) {
        central = central * (2.0 * n) * (2.0 * n - 1.0) / (double(n) * n);
        power *= 4.0;
        a[std::size_t(n - 1)] = 2.0 * power / (double(n) * n * central);
    }
    return a;
}();

}  // namespace penumbra::lights::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace penumbra::lights::detail::HWY_NAMESPACE {

// One lane vector = one SIMD register of doubles for the target; EMU128 gets
// one lane, the scalar reference.
#if HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR
constexpr int kLanes = 1;
#else
constexpr int kLanes = HWY_LANES(double);
#endif

typedef double VecD __attribute__((vector_size(kLanes * sizeof(double))));
typedef long long MaskD __attribute__((vector_size(kLanes * sizeof(double))));

inline VecD splat(double value) {
    VecD v{};
    for (int k = 0; k < kLanes; ++k) v[k] = value;
    return v;
}

inline bool any(const MaskD& m) {
    long long a = 0;
    for (int k = 0; k < kLanes; ++k) a |= m[k];
    return a != 0;
}

// Lanes from a[start ..]: the last element repeats past `n`.
inline VecD load(const double* a, std::size_t start, std::size_t n) {
    VecD v;
    if (start + kLanes <= n) {
        std::memcpy(&v, a + start, sizeof v);
    } else {
        for (int k = 0; k < kLanes; ++k) v[k] = a[std::min(start + std::size_t(k), n - 1)];
    }
    return v;
}

inline void store(const VecD& v, double* a, std::size_t start, std::size_t n) {
    if (start + kLanes <= n) {
        std::memcpy(a + start, &v, sizeof v);
        return;
    }
    for (int k = 0; k < kLanes && start + std::size_t(k) < n; ++k) a[start + std::size_t(k)] = v[k];
}

// The lanes of a[start ..] below `n` (zeros above): one whole load when
// `readable` elements from `a` allow it, else element by element.
inline VecD load_masked(const double* a, std::size_t start, std::size_t n, std::size_t readable) {
    VecD v{};
    if (start + kLanes <= readable) {
        std::memcpy(&v, a + start, sizeof v);
        if (start + kLanes > n)
            for (int k = 0; k < kLanes; ++k)
                if (start + std::size_t(k) >= n) v[k] = 0.0;
    } else {
        for (int k = 0; k < kLanes && start + std::size_t(k) < n; ++k) v[k] = a[start + std::size_t(k)];
    }
    return v;
}

double chord2_to(Points p, std::size_t n, double cx, double cy, double cz, double* out) {
    VecD nearest = splat(std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < n; i += kLanes) {
        const VecD dx = load(p.x, i, n) - cx, dy = load(p.y, i, n) - cy, dz = load(p.z, i, n) - cz;
        const VecD d2 = (dx * dx + dy * dy) + dz * dz;
        nearest = d2 < nearest ? d2 : nearest;
        store(d2, out, i, n);
    }
    double m = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kLanes; ++k) m = std::min(m, nearest[k]);
    return m;
}

void nearest_candidates(Points candidates, const int* index, std::size_t count, Points cells, std::size_t cells_count,
                        int* nearest) {
    for (std::size_t j = 0; j < cells_count; j += kLanes) {
        const VecD x = load(cells.x, j, cells_count), y = load(cells.y, j, cells_count), z = load(cells.z, j, cells_count);
        VecD best = splat(std::numeric_limits<double>::infinity());
        VecD best_index = splat(-1.0);
        // Ascending candidates and a strict <: the lowest index wins a tie.
        for (std::size_t i = 0; i < count; ++i) {
            const VecD dx = candidates.x[i] - x, dy = candidates.y[i] - y, dz = candidates.z[i] - z;
            const VecD d2 = (dx * dx + dy * dy) + dz * dz;
            const MaskD nearer = d2 < best;
            best = nearer ? d2 : best;
            best_index = nearer ? splat(double(index[i])) : best_index;
        }
        for (int k = 0; k < kLanes && j + std::size_t(k) < cells_count; ++k) nearest[j + std::size_t(k)] = int(best_index[k]);
    }
}

template <int kTerms>
inline VecD asin2_sum(const VecD& u) {
    VecD sum = splat(asin2_series[kTerms - 1]);
    for (int i = kTerms - 2; i >= 0; --i) sum = sum * u + asin2_series[std::size_t(i)];
    return sum * u;
}

// θ² by atan2(|x × l|, x · l) (accurate at every angle) for the wide cells.
inline double squared_angle(double x, double y, double z, double lx, double ly, double lz) {
    const double cx = y * lz - z * ly, cy = z * lx - x * lz, cz = x * ly - y * lx;
    const double angle = std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), x * lx + y * ly + z * lz);
    return angle * angle;
}

double weighted_squared_angles(const RowRun& run, double lx, double ly, double lz) {
    const double st = run.sin_theta, ct = run.cos_theta, dz = ct - lz, dz2 = dz * dz;
    const std::size_t n = run.cells;
    VecD sum{};
    for (std::size_t j = 0; j < n; j += kLanes) {
        VecD cos_lanes, sin_lanes;  // the grid's tables are padded: whole loads
        std::memcpy(&cos_lanes, run.cos_phi + j, sizeof cos_lanes);
        std::memcpy(&sin_lanes, run.sin_phi + j, sizeof sin_lanes);
        const VecD dx = st * cos_lanes - lx, dy = st * sin_lanes - ly;
        const VecD u = 0.25 * ((dx * dx + dy * dy) + dz2);
        const VecD weight = load_masked(run.weight, j, n, run.readable);  // 0 past the run
        if (!any(u > 1.0 / 64.0)) {
            sum += weight * asin2_sum<8>(u);
            continue;
        }
        VecD t = asin2_sum<asin2_terms>(u);
        const MaskD wide = u > 1.0 / 16.0;
        if (any(wide))
            for (int k = 0; k < kLanes; ++k)
                if (wide[k]) t[k] = squared_angle(st * cos_lanes[k], st * sin_lanes[k], ct, lx, ly, lz);
        sum += weight * t;
    }
    double total = 0.0;
    for (int k = 0; k < kLanes; ++k) total += sum[k];
    return total;
}

typedef float VecF __attribute__((vector_size(kLanes * sizeof(float))));

// 3·kLanes floats into three lane vectors (lane e of vector i: float
// kLanes·i + e of the chunk), tracking the lowest value.
struct FloatSums {
    VecD a0{}, a1{}, a2{};
    VecF lowest{};
};
[[gnu::always_inline]] inline void add_chunk(const float* f, FloatSums& s) {
    VecF v0, v1, v2;
    std::memcpy(&v0, f, sizeof v0);
    std::memcpy(&v1, f + kLanes, sizeof v1);
    std::memcpy(&v2, f + 2 * kLanes, sizeof v2);
    s.lowest = v0 < s.lowest ? v0 : s.lowest;
    s.lowest = v1 < s.lowest ? v1 : s.lowest;
    s.lowest = v2 < s.lowest ? v2 : s.lowest;
    s.a0 += __builtin_convertvector(v0, VecD);
    s.a1 += __builtin_convertvector(v1, VecD);
    s.a2 += __builtin_convertvector(v2, VecD);
}

// kLanes cells' weight, w cos φ and w sin φ, and which weights are 0.
struct WeightSums {
    VecD w{}, c{}, s{};
    MaskD zero{};
};
[[gnu::always_inline]] inline void add_cells(const double* w, const double* c, const double* s, WeightSums& sums) {
    VecD weight, cv, sv;
    std::memcpy(&weight, w, sizeof weight);
    std::memcpy(&cv, c, sizeof cv);
    std::memcpy(&sv, s, sizeof sv);
    sums.zero -= weight == 0.0;  // a true lane is −1
    sums.w += weight;
    sums.c += weight * cv;
    sums.s += weight * sv;
}

// The RGB floats are summed as one flat array, 3·kLanes at a time, so no lane
// needs to gather a pixel: lane e of vector i holds channel (kLanes·i + e) mod 3.
// Past the run's end lanes hold zeros, which add nothing.
RunSums run_sums(const RowRun& run) {
    typedef int IntF __attribute__((vector_size(kLanes * sizeof(float))));
    const std::size_t n = run.cells;
    FloatSums f;
    WeightSums ws;
    std::size_t j = 0;
    for (; j + kLanes <= n; j += kLanes) {
        add_chunk(run.rgb + 3 * j, f);
        add_cells(run.weight + j, run.cos_phi + j, run.sin_phi + j, ws);
    }
    std::size_t padding = 0;
    if (j < n) {
        float tail[3 * kLanes] = {};
        double tw[kLanes] = {};
        const int floats = int(3 * (n - j));
        if (j + kLanes <= run.readable) {
            std::memcpy(tail, run.rgb + 3 * j, sizeof tail);
            std::memcpy(tw, run.weight + j, sizeof tw);
            IntF lane{};
            for (int k = 0; k < kLanes; ++k) lane[k] = k;
            for (int v = 0; v < 3; ++v) {
                VecF x;
                std::memcpy(&x, tail + v * kLanes, sizeof x);
                x = lane + v * kLanes < floats ? x : VecF{};
                std::memcpy(tail + v * kLanes, &x, sizeof x);
            }
            for (int k = 0; k < kLanes; ++k)
                if (j + std::size_t(k) >= n) tw[k] = 0.0;
        } else {
            for (int k = 0; k < floats; ++k) tail[k] = run.rgb[3 * j + std::size_t(k)];
            for (std::size_t k = j; k < n; ++k) tw[k - j] = run.weight[k];
        }
        add_chunk(tail, f);
        add_cells(tw, run.cos_phi + j, run.sin_phi + j, ws);
        padding = j + kLanes - n;
    }

    RunSums out{{0.0, 0.0, 0.0}, 0.0, 0.0, 0.0, 0, false};
    for (int k = 0; k < kLanes; ++k) {
        out.rgb[k % 3] += f.a0[k];
        out.rgb[(kLanes + k) % 3] += f.a1[k];
        out.rgb[(2 * kLanes + k) % 3] += f.a2[k];
        out.negative |= f.lowest[k] < 0.0f;
        out.w += ws.w[k];
        out.w_cos += ws.c[k];
        out.w_sin += ws.s[k];
        out.zero_weight += std::size_t(ws.zero[k]);
    }
    out.zero_weight -= padding;
    return out;
}

}  // namespace penumbra::lights::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra::lights::detail {

HWY_EXPORT(chord2_to);
HWY_EXPORT(nearest_candidates);
HWY_EXPORT(weighted_squared_angles);
HWY_EXPORT(run_sums);

double chord2_to(Points p, std::size_t n, double cx, double cy, double cz, double* out) {
    return HWY_DYNAMIC_DISPATCH(chord2_to)(p, n, cx, cy, cz, out);
}

void nearest_candidates(Points candidates, const int* index, std::size_t count, Points cells, std::size_t cells_count,
                        int* nearest) {
    HWY_DYNAMIC_DISPATCH(nearest_candidates)(candidates, index, count, cells, cells_count, nearest);
}

double weighted_squared_angles(const RowRun& run, double lx, double ly, double lz) {
    return HWY_DYNAMIC_DISPATCH(weighted_squared_angles)(run, lx, ly, lz);
}

RunSums run_sums(const RowRun& run) { return HWY_DYNAMIC_DISPATCH(run_sums)(run); }

}  // namespace penumbra::lights::detail
#endif  // HWY_ONCE
