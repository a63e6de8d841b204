// Importance sampling of an environment map (paper §3): the luminance PDF,
// the two inverse transforms, and the progressive point set.
//
// PDF. Each grid cell weighs Y·Ω: luminance times its exact solid angle
// (the paper's sin θ factor, integrated over the cell). Sums are double, so a
// map spanning eight orders of magnitude keeps its dim cells; a black map has
// total 0 and samples as if it were uniform (the lights then carry no power).
//
// STANDARD (Pharr–Humphreys / the paper §3.1). u → a row by the marginal CDF
// of row masses, v → a column by that row's conditional CDF; both linear
// inside a cell, so θ and φ are linear in (u, v) within a cell. The map is
// discontinuous where a step in u crosses a row with a different conditional
// CDF and along φ = ±π (the image's left/right edge).
//
// HAVRAN (Havran, Dmitriev, Seidel 2003; the paper §3.1). Four stages:
//   1. (u, v) → unit disc by Shirley–Chiu's concentric map (continuous,
//      area-preserving): radius r_d, angle φ_d;
//   2. r_d² → an area coordinate t ∈ [0, 1] by the 1D CDF of row masses
//      (rows are t-intervals: t = (1 − cos θ)/(1 − cos θ_max));
//   3. φ_d/2π → the azimuth by a 1D CDF over columns that is linearly
//      interpolated between the CDFs of the two rows whose centres bracket t,
//      so a small step in (u, v) is always a small step in direction;
//   4. t → θ = acos(1 − t(1 − cos θ_max)), area-preserving (Lambert's
//      azimuthal equal-area projection).
// Hemisphere: θ_max = π/2, the disc is the hemisphere seen from above. Full
// sphere: θ_max = π, the same construction with the disc's rim collapsed to
// the nadir (−z): continuous everywhere and one-to-one inside the disc; only
// the rim (a set of measure zero) meets at one point, as the standard map's
// top and bottom edges meet at the poles. Where the PDF is positive the map
// is a bijection (tested by inverting it).
//
// POINTS. The 2D Halton sequence in bases 2 and 3 starting at index 1 (index
// 0 is the corner (0, 0)): light k is always point k, so a different count
// adds or removes lights and never moves the others. Optional blue noise:
// the first 4096 points are moved once by one discrete Lloyd step on the
// torus (deterministic; computed once per process); later points are plain
// Halton. Progressiveness holds either way.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "lights/environment.hpp"

namespace penumbra::lights {

struct LuminanceDistribution {
    int width = 0, height = 0;
    bool full_sphere = true;
    std::vector<double> weight;  // Y·Ω per cell, row-major
    std::vector<double> row_mass;  // Σ of each row
    double total = 0.0;
};

LuminanceDistribution luminance_distribution(const EnvironmentMap& map,
                                             const std::array<double, 3>& luminance = rec709_luminance,
                                             int threads = 0);

enum class SamplerKind { standard, havran };

struct Sample {
    Eigen::Vector3d direction;
    int row = 0, column = 0;  // the grid cell it fell in
};

class Sampler {
public:
    virtual ~Sampler() = default;
    // (u, v) ∈ [0, 1]² → direction.
    virtual Sample sample(double u, double v) const = 0;
    // direction → (u, v), the inverse transform (where the PDF is positive).
    virtual Eigen::Vector2d invert(const Eigen::Vector3d& direction) const = 0;
};

std::unique_ptr<Sampler> make_sampler(SamplerKind kind, const LuminanceDistribution& distribution);

// Radical inverse of `index` in `base`.
double radical_inverse(std::uint64_t index, int base);

// The first `count` points: Halton (2, 3) from index 1, optionally relaxed.
std::vector<Eigen::Vector2d> sample_points(int count, bool blue_noise);

// Shirley–Chiu concentric map [0,1]² → unit disc and its inverse.
Eigen::Vector2d concentric_square_to_disc(double u, double v);
Eigen::Vector2d concentric_disc_to_square(const Eigen::Vector2d& disc);

}  // namespace penumbra::lights
