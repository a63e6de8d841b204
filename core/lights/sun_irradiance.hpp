// Irradiance of one Blender sun on a diffuse surface: the analytic disc model
// the irradiance fit (irradiance_fit.hpp) and the benchmark use, matching how
// the add-on writes a light as a sun (addon/penumbra/lights/rig_objects.py and
// docs/lights.md, "Suns in Cycles").
//
// A light of flux rgb (= ∫ L dω of its region) and spread σ (RMS angular
// radius of its region) becomes a sun of angle clip(2√2·σ, 0, π), written as
// 0 below 1e-6 rad; its half-angle is h = angle/2. How Cycles spreads that
// flux over the half-angle h around the sun's direction d:
//   point          h = 0: all of it along d (also the old irradiance()).
//   blender3_disc  Blender 3.x: a disc of radius tan h at unit distance,
//                  sampled uniformly by area, so the flux per solid angle is
//                  ∝ 1/cos³θ (θ from d) and a facing surface receives
//                  rgb·2cos h/(1 + cos h).
//   blender4_cone  Blender ≥ 4.0 (4.5, 5.x): a cone of uniform radiance,
//                  rgb/(2π(1 − cos h)); a facing surface receives
//                  rgb·(1 + cos h)/2 (the add-on's strength).
// The kernel K(c, h) below is the irradiance per unit flux on a surface whose
// normal makes cos β = c with d; it depends on nothing else (the sun is
// rotationally symmetric about d), and is smooth (C¹) in c for h > 0.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "lights/frame_lights.hpp"

namespace penumbra::lights {

// SunModel (point, blender3_disc, blender4_cone) is declared in frame_lights.hpp.

// The sun model of a Blender version (major, minor): blender4_cone from 4.0 on.
SunModel sun_model_for_blender(int major, int minor);

// Suns narrower than this (radians, full angle) are written with angle 0:
// Cycles drops a sun of angle <= 1e-10 (its cone pdf overflows a float).
constexpr double min_sun_angle = 1e-6;

// Half-angle h (radians) of the sun the add-on writes for a region of RMS
// angular radius `spread`.
double sun_half_angle(double spread);

// K(c, h): irradiance per unit flux, c = cos β clamped to [−1, 1].
double sun_kernel(double c, double half_angle, SunModel model);

// dK/dc (central difference for h > 0; the kernel is C¹ there).
double sun_kernel_slope(double c, double half_angle, SunModel model);

// Irradiance (RGB, one row per normal) of lights written as suns:
// Σ_k rgb_k · K(n·d_k, sun_half_angle(spread_k)).
Eigen::MatrixXd sun_irradiance(const std::vector<Light>& lights, const std::vector<Eigen::Vector3d>& normals,
                               SunModel model, int threads = 0);

}  // namespace penumbra::lights
