// Directional lights from one frame (paper §3), their irradiance, and the
// adaptive light count.
//
// Light k is the k-th point of the progressive point set (sampling.hpp)
// pushed through the chosen inverse transform. What each light carries:
//   direction  unit vector towards the light, map coordinates (= Blender
//              world coordinates before the World's Mapping rotation)
//   rgb        irradiance in W/m² per channel on a surface facing the light
//              (Blender's sun strength × colour); Σ over lights = ∫ L dω
//   power      luminance of rgb
//   spread     RMS angular radius (radians) of the map region the light
//              stands for: the add-on sets the sun's angle from it
//
// Power modes:
//   equal   the paper's: every light gets total/N of the luminance integral;
//           its colour is the chromaticity (rgb/Y) of the cell it landed in;
//           its direction is the sample's. Adding a light rescales the others'
//           power but moves none of them.
//   region  each light stands for its region of the map: the cells nearer to
//           its sample than to any other sample (a spherical Voronoi cell of
//           the samples, found with a spatial index). Its rgb is the region's
//           ∫ L dω (so the sum is exactly the map's integral, per channel),
//           its direction the region's energy centroid (normalized Σ Y Ω ω).
//           Identities stay: light k is still anchored at sample k, but adding
//           a light shrinks its neighbours' regions, so their power and
//           centroid change a little.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "common/setting.hpp"
#include "lights/environment.hpp"
#include "lights/sampling.hpp"

namespace penumbra::lights {

enum class PowerMode { equal, region };

// How a renderer spreads a sun's flux over its angle (sun_irradiance.hpp):
// Cycles' models, EEVEE Next's shadowed sun (the cone, its shadow cut at the
// receiver's own horizon) and EEVEE Legacy's sun (the cone, another power).
enum class SunModel { point, blender3_disc, blender4_cone, eevee_next_shadowed, eevee_legacy };

struct LightOptions {
    int count = 64;                 // N, at most the map's cell count
    static constexpr Range<int> count_range{1, unbounded_int};
    SamplerKind sampler = SamplerKind::havran;
    bool blue_noise = false;
    PowerMode power = PowerMode::region;
    std::array<double, 3> luminance = rec709_luminance;
    int threads = 0;                // 0 = all cores
    // Cranley–Patterson shift of the point set (added mod 1). Zero for a rig;
    // the benchmark draws a fresh shift per frame to measure untracked,
    // resampled-every-frame lights.
    Eigen::Vector2d point_shift = Eigen::Vector2d::Zero();
    // After the powers: refit every light's rgb (never negative, summing to
    // the map's ∫L dω), direction and sun angle so the suns' irradiance,
    // under `sun_model`, matches the map's (irradiance_fit.hpp). Only up to
    // `max_fitted_lights`: the fit's cost grows as N³ (60 s at 512 lights),
    // and region lights are already as accurate as median cut there.
    bool fit_irradiance = true;
    static constexpr int max_fitted_lights = 256;
    SunModel sun_model = SunModel::blender4_cone;
};

struct Light {
    int index = 0;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
    double power = 0.0;
    double spread = 0.0;
    Eigen::Vector3d sample_direction = Eigen::Vector3d::UnitZ();
};

struct FrameLights {
    std::vector<Light> lights;
    Eigen::Vector3d total_rgb = Eigen::Vector3d::Zero();  // ∫ L dω of the map
    double total_power = 0.0;                              // ∫ Y dω
};

// Lights of one map. ArgumentError when count < 1 or count exceeds the
// number of grid cells (more lights than pixels cannot be told apart).
FrameLights compute_lights(const EnvironmentMap& map, const LuminanceDistribution& distribution,
                           const Sampler& sampler, const LightOptions& options);

// Region lights anchored at given seeds instead of the sampler's points
// (the video tracker's, tracking.hpp): light k stands for the cells nearer
// to seeds[k] than to any other seed; its sample_direction is seeds[k].
// No irradiance fit (the caller's).
FrameLights region_lights(const EnvironmentMap& map, const LuminanceDistribution& distribution,
                          const std::vector<Eigen::Vector3d>& seeds, const LightOptions& options);

// Convenience: distribution + sampler + lights.
FrameLights compute_lights(const EnvironmentMap& map, const LightOptions& options);

// Irradiance (RGB, one row per normal) of a diffuse surface: Σ_k rgb_k max(0, n·d_k).
Eigen::MatrixXd irradiance(const std::vector<Light>& lights, const std::vector<Eigen::Vector3d>& normals);

// The map's own irradiance Σ_cells L Ω max(0, n·ω) (cell-centre rule), the
// reference every error is measured against: exact, summed by tiles
// (exact_irradiance.hpp). Parallel over normals.
Eigen::MatrixXd exact_irradiance(const EnvironmentMap& map, const std::vector<Eigen::Vector3d>& normals,
                                 int threads = 0);

// sqrt(Σ_n (Y(E_n) − Y(R_n))²) / sqrt(Σ_n Y(R_n)²), Y = luminance; 0 when
// the reference is black and the estimate too.
double relative_rmse(const Eigen::MatrixXd& estimate, const Eigen::MatrixXd& reference,
                     const std::array<double, 3>& luminance = rec709_luminance);

// Adaptive count: the fewest lights (searched over 1, 2, 3, 4, 6, 8, 12, ...
// up to max_count, then bisected between the last failing and the first
// passing count) whose irradiance relative RMSE is at most `tolerance`;
// max_count when none is. Each count is measured as it will be drawn: the
// lights fitted as compute_lights fits them (options.fit_irradiance) and
// their irradiance that of suns under options.sun_model (rig_error).
// max_count is capped by max_lights(options.sun_model).
struct AdaptiveResult {
    int count = 0;
    double error = 0.0;
};
AdaptiveResult adaptive_count(const EnvironmentMap& map, const LightOptions& options, double tolerance,
                              int max_count, int normal_count = 128);

// The relative RMSE (luminance) of `lights`, drawn as suns under `model`,
// against the map's irradiance over `normal_count` Fibonacci normals, the
// reference taken on a copy of the map reduced to at most 256 columns.
double rig_error(const EnvironmentMap& map, const std::vector<Light>& lights, SunModel model,
                 const std::array<double, 3>& luminance = rec709_luminance, int normal_count = 128,
                 int threads = 0);

// The most lights a renderer draws: EEVEE Legacy (Blender 2.8–4.1) keeps at
// most 128 (MAX_LIGHT in its eevee_private.h) and ignores the rest.
constexpr int eevee_legacy_max_lights = 128;
int max_lights(SunModel model);

}  // namespace penumbra::lights
