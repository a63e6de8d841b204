// Irradiance fit: once the lights' directions are chosen (sampling + region
// powers), refit their colours and nudge their directions so that the suns,
// as Blender will draw them (sun_irradiance.hpp), light a diffuse surface as
// the map does.
//
// Minimised over rgb_k ≥ 0 (per channel) and directions d_k:
//   Σ_i Σ_c (Σ_k rgb_kc · K(n_i·d_k, h_k) − E_c(n_i))²
// over `normal_count` Fibonacci normals n_i, E = the exact irradiance of the
// map reduced to `reference_width` columns (energy-exact). h_k (the sun's
// half-angle from the region's spread) stays. Alternation (docs/lights.md,
// "Irradiance fit"): non-negative least squares of the colours for fixed
// directions (projected coordinate descent on the normal equations), then a
// Levenberg–Marquardt step of the directions for fixed colours; each light
// may move at most `reach` × max(its spread, one map row) from where it
// started, so light k still stands for region k and tracks over video.
#pragma once

#include <array>
#include <vector>

#include "lights/environment.hpp"
#include "lights/lights.hpp"

namespace penumbra::lights {

struct IrradianceFitOptions {
    SunModel sun_model = SunModel::blender4_cone;
    int normal_count = 2562;       // fitting normals (not the benchmark's 1000)
    int reference_width = 0;       // map reduced to this width for the target irradiance
    int iterations = 12;           // colour solve + direction step rounds
    double reach = 1.0;            // bound on a light's move, × max(spread, row angle)
    std::array<double, 3> luminance = rec709_luminance;
    int threads = 0;
};

struct IrradianceFitResult {
    double error_before = 0.0;  // relative RMSE (luminance) on the fitting normals
    double error_after = 0.0;
};

// Angle a light may move from its starting direction (radians).
double fit_reach(const EnvironmentMap& map, const Light& light, double reach);

// Fits `lights` in place (rgb, power, direction); spread and sample_direction
// stay. ArgumentError on bad options. A black map leaves every rgb 0.
IrradianceFitResult fit_irradiance(const EnvironmentMap& map, std::vector<Light>& lights,
                                   const IrradianceFitOptions& options = {});

}  // namespace penumbra::lights
