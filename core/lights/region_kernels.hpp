// The inner loops of region powers (frame_lights.cpp, region_assignment.cpp),
// compiled once per SIMD target by Highway (SSE4, AVX2, AVX-512, and EMU128
// as the one-lane reference) and chosen at run time, so the portable
// x86-64-v2 build runs AVX2/AVX-512 code where the CPU has it.
//
// Every per-cell value is computed lane by lane in the same arithmetic on
// every target (region_kernels.cpp is compiled without floating-point
// contraction), so the nearest-site decisions are bit-identical to chord2()
// (region_assignment.hpp) whatever the target. A run's sums add cell by
// cell in 4-lane vectors, whatever the target's width, so they too are the
// same on every target.
#pragma once

#include <cstddef>

namespace penumbra::lights::detail {

// Points given as coordinate arrays (x[i], y[i], z[i]).
struct Points {
    const double* x;
    const double* y;
    const double* z;
};

// out[i] = chord2(p_i, c) for i < n; returns the smallest (+inf for n = 0).
double chord2_to(Points p, std::size_t n, double cx, double cy, double cz, double* out);

// The points i < n with distance[i] <= bound2, in order, with their index,
// written to x, y, z and kept (each with room for n); returns how many.
std::size_t keep_within(Points from, const int* index, std::size_t n, const double* distance, double bound2,
                        double* x, double* y, double* z, int* kept);

// For each of `cells` points, the lowest `index` among the `candidates`
// points at the smallest chord2 from it (candidates in ascending index).
void nearest_candidates(Points candidates, const int* index, std::size_t count, Points cells, std::size_t cells_count,
                        int* nearest);

// Cells j < `cells` of a run along a map row: RGB radiance rgb[3j..3j+2]
// (scene-linear floats), weight w[j] = Y·Ω, the row's sin θ and cos θ and
// the cells' cos φ and sin φ. `readable`: how many cells from rgb and weight
// on are in memory (to the end of the map), so a load may pass the run's end
// and mask it; the cos φ and sin φ tables must be readable kMaxLanes past it.
constexpr std::size_t kMaxLanes = 16;
struct RowRun {
    const float* rgb;
    const double* weight;
    const double* cos_phi;
    const double* sin_phi;
    double sin_theta, cos_theta;
    std::size_t cells, readable;
};

// out[j] = w[j] θ_j² for the cells j < run.cells, θ_j the angle between the
// cell's centre, (sin θ cos φ_j, sin θ sin φ_j, cos θ), and the unit vector
// l_j = (lights.x[j], lights.y[j], lights.z[j]): the asin² series of the
// chord up to 29° (exact to ~1e-16 there), atan2 beyond. Taken a whole row
// at a time (one call, not one per run of a few cells), so `lights` and
// `out` must be readable and writable kMaxLanes past run.cells.
void weighted_squared_angles(const RowRun& run, Points lights, double* out);

// Over the run: Σ RGB, Σ w, Σ w cos φ, Σ w sin φ, whether some cell has
// w <= 0 (every black cell has w = 0; weights are never negative), and
// whether any value is negative (never in a sanitized map: then the black
// cells, all zeros, added nothing).
struct RunSums {
    double rgb[3];
    double w, w_cos, w_sin;
    bool unweighted;
    bool negative;
};
RunSums run_sums(const RowRun& run);

}  // namespace penumbra::lights::detail
