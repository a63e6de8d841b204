// region_kernels.hpp, compiled once per SIMD target by Highway's
// foreach_target and chosen at run time by its dynamic dispatch, in the
// manner of sh/pose_shading_kernel.cpp: every per-cell quantity is a lane
// vector of doubles (GCC/Clang vector extensions, which Highway's per-target
// `#pragma GCC target` turns into that target's instructions), a partial
// batch repeats its last cell in the spare lanes, and choices are lane masks.

#include "common/simd_compiled_targets.hpp"  // before any Highway header
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

#include "common/simd_lanes-inl.h"
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

// compress_order[b]: the positions of the set bits of b, lowest first, then
// zeros: the lane order that moves a vector's kept lanes (mask bits b) to its
// front. A table at namespace scope: Highway 1.0.3's Compress of 64-bit
// lanes copies its own 2 KB table onto the stack on every call.
constexpr std::array<std::array<std::int64_t, 8>, 256> compress_order = [] {
    std::array<std::array<std::int64_t, 8>, 256> t{};
    for (int b = 0; b < 256; ++b) {
        int m = 0;
        for (int k = 0; k < 8; ++k)
            if (b & (1 << k)) t[std::size_t(b)][std::size_t(m++)] = k;
    }
    return t;
}();

}  // namespace penumbra::lights::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace penumbra::lights::detail::HWY_NAMESPACE {

using namespace simd::HWY_NAMESPACE;

inline bool any(const MaskD& m) {
    long long a = 0;
    for (int k = 0; k < kDoubleLanes; ++k) a |= m[k];
    return a != 0;
}

// Lanes from a[start ..]: the last element repeats past `n`.
inline VecD load(const double* a, std::size_t start, std::size_t n) {
    VecD v;
    if (start + kDoubleLanes <= n) {
        std::memcpy(&v, a + start, sizeof v);
    } else {
        for (int k = 0; k < kDoubleLanes; ++k) v[k] = a[std::min(start + std::size_t(k), n - 1)];
    }
    return v;
}

inline void store(const VecD& v, double* a, std::size_t start, std::size_t n) {
    if (start + kDoubleLanes <= n) {
        std::memcpy(a + start, &v, sizeof v);
        return;
    }
    for (int k = 0; k < kDoubleLanes && start + std::size_t(k) < n; ++k) a[start + std::size_t(k)] = v[k];
}

// The lanes of a[start ..] below `n` (zeros above): one whole load when
// `readable` elements from `a` allow it, else element by element.
inline VecD load_masked(const double* a, std::size_t start, std::size_t n, std::size_t readable) {
    VecD v{};
    if (start + kDoubleLanes <= readable) {
        std::memcpy(&v, a + start, sizeof v);
        if (start + kDoubleLanes > n)
            for (int k = 0; k < kDoubleLanes; ++k)
                if (start + std::size_t(k) >= n) v[k] = 0.0;
    } else {
        for (int k = 0; k < kDoubleLanes && start + std::size_t(k) < n; ++k) v[k] = a[start + std::size_t(k)];
    }
    return v;
}

double chord2_to(Points p, std::size_t n, double cx, double cy, double cz, double* out) {
    VecD nearest = splat(std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < n; i += kDoubleLanes) {
        const VecD dx = load(p.x, i, n) - cx, dy = load(p.y, i, n) - cy, dz = load(p.z, i, n) - cz;
        const VecD d2 = (dx * dx + dy * dy) + dz * dz;
        nearest = d2 < nearest ? d2 : nearest;
        store(d2, out, i, n);
    }
    double m = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kDoubleLanes; ++k) m = std::min(m, nearest[k]);
    return m;
}

std::size_t keep_within(Points from, const int* index, std::size_t n, const double* distance, double bound2,
                        double* x, double* y, double* z, int* kept) {
    namespace hn = hwy::HWY_NAMESPACE;
    const hn::ScalableTag<double> d;
    const hn::Rebind<int32_t, decltype(d)> d32;
    const std::size_t lanes = hn::Lanes(d);
    const auto limit = hn::Set(d, bound2);
    std::size_t m = 0, i = 0;
    // Whole vectors: the kept lanes moved to the front in order, the whole
    // vector stored at m (m <= i: within the first n entries of the output).
    static_assert(hn::MaxLanes(d) <= 8, "compress_order covers up to 8 lanes");
    for (; i + lanes <= n; i += lanes) {
        const auto keep = hn::Le(hn::LoadU(d, distance + i), limit);
        std::uint8_t bits[8] = {};
        hn::StoreMaskBits(d, keep, bits);
        const auto order = hn::SetTableIndices(d, compress_order[bits[0]].data());
        hn::StoreU(hn::TableLookupLanes(hn::LoadU(d, from.x + i), order), d, x + m);
        hn::StoreU(hn::TableLookupLanes(hn::LoadU(d, from.y + i), order), d, y + m);
        hn::StoreU(hn::TableLookupLanes(hn::LoadU(d, from.z + i), order), d, z + m);
        const auto site = hn::PromoteTo(d, hn::LoadU(d32, index + i));  // exact: |index| < 2^31
        hn::StoreU(hn::DemoteTo(d32, hn::TableLookupLanes(site, order)), d32, kept + m);
        m += std::size_t(__builtin_popcount(bits[0]));
    }
    // The rest one by one: each written, overwritten by the next unless kept.
    for (; i < n; ++i) {
        kept[m] = index[i];
        x[m] = from.x[i];
        y[m] = from.y[i];
        z[m] = from.z[i];
        m += distance[i] <= bound2;
    }
    return m;
}

// kV lane vectors of cells from `first` on against every candidate: each
// candidate's coordinates are loaded once for all of them, and the kV
// running minima are independent chains, so the loop is not held up by the
// latency of one compare-and-select chain. The loops over the vectors are
// unrolled by hand (the pragmas), so the arrays live in registers: left as
// loops, GCC kept them on the stack.
template <int kV>
[[gnu::always_inline]] inline void nearest_vectors(Points candidates, const int* index, std::size_t count, Points cells,
                                                   std::size_t cells_count, std::size_t first, int* nearest) {
    VecD x[kV], y[kV], z[kV], best[kV], best_index[kV];
#pragma GCC unroll 4
    for (int v = 0; v < kV; ++v) {
        const std::size_t j = first + std::size_t(v) * kDoubleLanes;
        x[v] = load(cells.x, j, cells_count);
        y[v] = load(cells.y, j, cells_count);
        z[v] = load(cells.z, j, cells_count);
        best[v] = splat(std::numeric_limits<double>::infinity());
        best_index[v] = splat(-1.0);
    }
    // Ascending candidates and a strict <: the lowest index wins a tie.
    for (std::size_t i = 0; i < count; ++i) {
        const double sx = candidates.x[i], sy = candidates.y[i], sz = candidates.z[i];
        const VecD id = splat(double(index[i]));
#pragma GCC unroll 4
        for (int v = 0; v < kV; ++v) {
            const VecD dx = sx - x[v], dy = sy - y[v], dz = sz - z[v];
            const VecD d2 = (dx * dx + dy * dy) + dz * dz;
            const MaskD nearer = d2 < best[v];
            best[v] = nearer ? d2 : best[v];
            best_index[v] = nearer ? id : best_index[v];
        }
    }
#pragma GCC unroll 4
    for (int v = 0; v < kV; ++v) {
        const std::size_t j = first + std::size_t(v) * kDoubleLanes;
        for (int k = 0; k < kDoubleLanes && j + std::size_t(k) < cells_count; ++k)
            nearest[j + std::size_t(k)] = int(best_index[v][k]);
    }
}

void nearest_candidates(Points candidates, const int* index, std::size_t count, Points cells, std::size_t cells_count,
                        int* nearest) {
    // Four lane vectors at a time where the registers hold them (AVX-512 has
    // 32), two elsewhere; then what is left.
    constexpr int kWide = kDoubleLanes >= 8 ? 4 : 2;
    std::size_t j = 0;
    for (; j + kWide * kDoubleLanes <= cells_count; j += kWide * kDoubleLanes)
        nearest_vectors<kWide>(candidates, index, count, cells, cells_count, j, nearest);
    const std::size_t left = (cells_count - j + kDoubleLanes - 1) / kDoubleLanes;
    switch (left) {
        case 4: return nearest_vectors<4>(candidates, index, count, cells, cells_count, j, nearest);
        case 3: return nearest_vectors<3>(candidates, index, count, cells, cells_count, j, nearest);
        case 2: return nearest_vectors<2>(candidates, index, count, cells, cells_count, j, nearest);
        case 1: return nearest_vectors<1>(candidates, index, count, cells, cells_count, j, nearest);
        default: return;  // none left
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

void weighted_squared_angles(const RowRun& run, Points lights, double* out) {
    const double st = run.sin_theta, ct = run.cos_theta;
    const std::size_t n = run.cells;
    for (std::size_t j = 0; j < n; j += kDoubleLanes) {
        VecD cos_lanes, sin_lanes, lx, ly, lz;  // the tables are padded: whole loads
        std::memcpy(&cos_lanes, run.cos_phi + j, sizeof cos_lanes);
        std::memcpy(&sin_lanes, run.sin_phi + j, sizeof sin_lanes);
        std::memcpy(&lx, lights.x + j, sizeof lx);
        std::memcpy(&ly, lights.y + j, sizeof ly);
        std::memcpy(&lz, lights.z + j, sizeof lz);
        const VecD dx = st * cos_lanes - lx, dy = st * sin_lanes - ly, dz = ct - lz;
        const VecD u = 0.25 * ((dx * dx + dy * dy) + dz * dz);
        const VecD weight = load_masked(run.weight, j, n, run.readable);  // 0 past the row
        VecD t;
        if (!any(u > 1.0 / 64.0)) {
            t = asin2_sum<8>(u);
        } else {
            t = asin2_sum<asin2_terms>(u);
            const MaskD wide = u > 1.0 / 16.0;
            if (any(wide))
                for (int k = 0; k < kDoubleLanes; ++k)
                    if (wide[k])
                        t[k] = squared_angle(st * cos_lanes[k], st * sin_lanes[k], ct, lx[k], ly[k], lz[k]);
        }
        const VecD product = weight * t;
        std::memcpy(out + j, &product, sizeof product);
    }
}

// Runs are short (at 360x90 with 300 lights 12 cells on average, 4 in
// every other one), so a run's sums are kept per cell, not per lane of
// cells: one 4-lane vector gathers a cell's (R, G, B, ·) with one load, the
// other its (w, w cos φ, w sin φ, 0), and nothing is left to reduce across
// lanes at the end. Even and odd cells go to separate sums, so two add
// chains run side by side.
typedef double Vec4D __attribute__((vector_size(4 * sizeof(double))));
typedef float Vec4F __attribute__((vector_size(4 * sizeof(float))));

struct CellSums {
    Vec4D rgb{}, weight{};
};

// Cell j; `f` = its four floats from R on, the fourth the next cell's R:
// left out of the sums and, unless `next_in_run`, of the lowest value.
template <bool next_in_run>
[[gnu::always_inline]] inline void add_cell(const RowRun& run, std::size_t j, Vec4F f, CellSums& sums, Vec4F& lowest,
                                            double& lowest_weight) {
    // B again for the next R (lane by lane: clang, which builds the fuzzers, has no __builtin_shuffle).
    const Vec4F rgb = next_in_run ? f : Vec4F{f[0], f[1], f[2], f[2]};
    lowest = rgb < lowest ? rgb : lowest;
    sums.rgb += __builtin_convertvector(f, Vec4D);
    const double w = run.weight[j];
    lowest_weight = std::min(lowest_weight, w);
    sums.weight += Vec4D{w, w * run.cos_phi[j], w * run.sin_phi[j], 0.0};
}

RunSums run_sums(const RowRun& run) {
    const std::size_t n = run.cells;
    // A cell's 4-float load reads one float past it: within the map for every
    // cell but the map's last.
    const std::size_t loadable = std::min(n, run.readable - 1);
    CellSums even, odd;
    Vec4F lowest = {0.0f, 0.0f, 0.0f, 0.0f};
    double lowest_weight = std::numeric_limits<double>::infinity();
    std::size_t j = 0;
    auto cell = [&](std::size_t k) {
        Vec4F f;
        std::memcpy(&f, run.rgb + 3 * k, sizeof f);
        return f;
    };
    // Pairs of cells followed by another of the run (so every load is in the map).
    for (; j + 3 <= n; j += 2) {
        add_cell<true>(run, j, cell(j), even, lowest, lowest_weight);
        add_cell<true>(run, j + 1, cell(j + 1), odd, lowest, lowest_weight);
    }
    for (; j < n; ++j) {
        Vec4F f = {0.0f, 0.0f, 0.0f, 0.0f};
        if (j < loadable) f = cell(j);
        else std::memcpy(&f, run.rgb + 3 * j, 3 * sizeof(float));
        add_cell<false>(run, j, f, j % 2 == 0 ? even : odd, lowest, lowest_weight);
    }
    const Vec4D rgb = even.rgb + odd.rgb, weight = even.weight + odd.weight;
    return {{rgb[0], rgb[1], rgb[2]},
            weight[0],
            weight[1],
            weight[2],
            lowest_weight <= 0.0,
            lowest[0] < 0.0f || lowest[1] < 0.0f || lowest[2] < 0.0f || lowest[3] < 0.0f};
}

}  // namespace penumbra::lights::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra::lights::detail {

HWY_EXPORT(chord2_to);
double chord2_to(Points p, std::size_t n, double cx, double cy, double cz, double* out) {
    return HWY_DYNAMIC_DISPATCH(chord2_to)(p, n, cx, cy, cz, out);
}

HWY_EXPORT(keep_within);
std::size_t keep_within(Points from, const int* index, std::size_t n, const double* distance, double bound2,
                        double* x, double* y, double* z, int* kept) {
    return HWY_DYNAMIC_DISPATCH(keep_within)(from, index, n, distance, bound2, x, y, z, kept);
}

HWY_EXPORT(nearest_candidates);
void nearest_candidates(Points candidates, const int* index, std::size_t count, Points cells, std::size_t cells_count,
                        int* nearest) {
    HWY_DYNAMIC_DISPATCH(nearest_candidates)(candidates, index, count, cells, cells_count, nearest);
}

HWY_EXPORT(weighted_squared_angles);
void weighted_squared_angles(const RowRun& run, Points lights, double* out) {
    HWY_DYNAMIC_DISPATCH(weighted_squared_angles)(run, lights, out);
}

HWY_EXPORT(run_sums);
RunSums run_sums(const RowRun& run) { return HWY_DYNAMIC_DISPATCH(run_sums)(run); }

}  // namespace penumbra::lights::detail
#endif  // HWY_ONCE
