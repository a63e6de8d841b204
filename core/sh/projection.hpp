// Projection of lighting and of sampled functions onto the SH basis of
// basis.hpp: c_i = ∫_{S²} f(ω) y_i(ω) dω. Sums are accumulated in double.
//
// Equirectangular images are mapped to directions as Blender's World maps
// them: common/latlong.hpp, the one place that convention is written down.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "common/progress.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::sh {

// Σ_i weights[i] · values(i, :) · y(directions[i]) for (N, k) values: returns
// (order², k). Directions are normalized (zero/non-finite: ArgumentError).
// An empty `weights` means equal weights 4π/N (Fibonacci or uniform random
// samples).
Eigen::MatrixXd project_samples(int order, const std::vector<Eigen::Vector3d>& directions,
                                const Eigen::MatrixXd& values, const std::vector<double>& weights = {});

// The same over a PointSet.
Eigen::MatrixXd project_samples(int order, const PointSet& points, const Eigen::MatrixXd& values);

// Distant delta lights: light i arrives from directions[i] (the direction
// towards the light) with irradiance rgb(i, :) on a surface facing it, so it
// projects to rgb(i, :) · y(directions[i]). Returns (order², 3).
Eigen::MatrixXd project_lights(int order, const std::vector<Eigen::Vector3d>& directions,
                               const Eigen::MatrixXd& rgb);

// Pixel (row, column) centre direction and the pixel's exact solid angle
// Δφ · (cos θ_top − cos θ_bottom) of a full-sphere map: latlong::pixel_direction
// and latlong::pixel_solid_angle.
Eigen::Vector3d equirectangular_direction(int row, int column, int height, int width);
double equirectangular_solid_angle(int row, int height, int width);

struct EnvironmentProjection {
    Eigen::MatrixXd coefficients;          // (order², 3) RGB
    std::size_t non_finite_pixels = 0;     // pixels with a NaN/Inf channel; those channels counted as 0
    std::size_t negative_pixels = 0;       // pixels with a negative channel; kept as they are
};

// Projects an equirectangular radiance image (row-major, `channels` floats per
// pixel, 3 = RGB or 4 = RGBA with alpha ignored; row 0 = top row of the file)
// oriented as Blender's World shows it (common/latlong.hpp). Each pixel is a
// constant over its exact footprint on the sphere: the φ integral of
// cos(mφ)/sin(mφ) is taken in closed form per column and the θ integral of
// the Legendre factor by Gauss–Legendre in θ (smooth there up to the poles)
// with theta_nodes + ⌈order·π/H⌉ nodes per row, so a constant image projects
// exactly (to rounding) at any resolution. NaN/Inf channels count as 0 and are
// counted; negative values are kept (they are valid in some HDRs) and
// counted. Pixels are scene-linear radiance (colour conversion is the
// caller's); Blender filters the texture linearly between pixel centres, which
// differs from the constant-per-pixel model only below the pixel scale.
// Reports progress after every 32 rows; throws Cancelled if asked.
// H, W >= 1, channels in {3, 4}, 1 <= theta_nodes <= 64, else ArgumentError.
EnvironmentProjection project_equirectangular(int order, const float* pixels, int height, int width,
                                              int channels, const Progress& progress = {},
                                              int theta_nodes = 6);

}  // namespace penumbra::sh
