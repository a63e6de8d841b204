// Irradiance fit: once the lights' directions are chosen (sampling + region
// powers), refit their colours, directions and sun angles so that the suns,
// as Blender will draw them (sun_irradiance.hpp), light a diffuse surface as
// the map does.
//
// Minimised over rgb_k ≥ 0 (per channel), directions d_k and half-angles h_k:
//   Σ_i Σ_c (Σ_k rgb_kc · K(n_i·d_k, h_k) − E_c(n_i))²
// over `normal_count` Fibonacci normals n_i, E = the exact irradiance of the
// map (exact_irradiance.hpp; or of a copy reduced to `reference_width`
// columns). The problem is linear in the colours: they are eliminated
// (variable projection, Golub & Pereyra 1973, in Kaufman's form) and the
// shape (d_k, h_k) is moved by Levenberg–Marquardt steps, the colours
// re-solved (non-negative least squares) at every trial. docs/lights.md,
// "Irradiance fit", has the derivation and the measurements. A light may be
// held within an angle of where it started (`reach` × its spread, or
// `move_bound` per light: the video tracker's per-frame step).
#pragma once

#include <array>
#include <limits>
#include <vector>

#include "lights/environment.hpp"
#include "lights/frame_lights.hpp"

namespace penumbra::lights {

struct IrradianceFitOptions {
    SunModel sun_model = SunModel::blender4_cone;
    int normal_count = 0;          // fitting normals (Fibonacci); 0: 6 per light, within [642, 2562]
    int reference_width = 0;       // map reduced to this width for the target irradiance (0: as it is)
    int iterations = 15;           // Levenberg–Marquardt steps at most
    double tolerance = 1e-3;       // stop once a step lowers the squared error by less than this share
    bool fit_angles = true;        // also fit each sun's half-angle (the disc's at most max_disc_half_angle)
    // The colours sum to the map's ∫L dω per channel, as region powers do
    // (a constraint the exact fit nearly meets by itself: the mean of any
    // light's irradiance over all normals is its flux / 4).
    bool keep_flux = true;
    // Bound on a light's move from where it started, × max(spread, one map
    // row); infinite: free. `move_bound` (radians, one per light) replaces it.
    double reach = std::numeric_limits<double>::infinity();
    std::vector<double> move_bound;
    // Colours expected (the video tracker's: the previous frame's, turned
    // and rescaled), one per light, or none: adds prior_weight · mean of
    // diag(AᵀA) · Σ_k ‖rgb_k − prior_k‖² to the error, so that lights
    // sharing a sun (nearly equal kernel columns) do not trade their power
    // from frame to frame while the irradiance stays the same.
    std::vector<Eigen::Vector3d> prior_rgb;
    double prior_weight = 1e-3;
    std::array<double, 3> luminance = rec709_luminance;
    int threads = 0;
};

struct IrradianceFitResult {
    double error_before = 0.0;  // relative RMSE (luminance) on the fitting normals
    double error_after = 0.0;
    int steps = 0;              // Levenberg–Marquardt steps taken
};

// Angle a light may move from its starting direction (radians).
double fit_reach(const EnvironmentMap& map, const Light& light, double reach);

// Fits `lights` in place: rgb, power, direction and (with fit_angles) spread,
// written as h/√2 so the add-on's sun has the fitted half-angle h
// (sun_half_angle). sample_direction and index stay. ArgumentError on bad
// options. A black map leaves every rgb 0.
IrradianceFitResult fit_irradiance(const EnvironmentMap& map, std::vector<Light>& lights,
                                   const IrradianceFitOptions& options = {});

}  // namespace penumbra::lights
