// A light written as a Blender sun, and the irradiance that sun gives a
// diffuse surface. This file owns how a light becomes a sun (its angle and
// its strength, which the add-on writes through _penumbra.lights.sun_angle
// and sun_strength_per_flux, addon/penumbra/lights/rig_objects.py) and the
// analytic model of what Cycles then draws, which the irradiance fit
// (irradiance_fit.hpp) and the benchmark use (docs/lights.md, "Suns in
// Cycles").
//
// A light of flux rgb (= ∫ L dω of its region) and spread σ (RMS angular
// radius of its region; a uniform disc of radius ρ has RMS radius ρ/√2)
// becomes a sun of angle clip(2√2·σ, 0, π), written as 0 below 1e-6 rad;
// its half-angle is h = angle/2. How Cycles spreads that flux over the
// half-angle h around the sun's direction d:
//   point          h = 0: all of it along d (also the old irradiance()).
//   blender3_disc  Blender 3.x: a disc of radius tan h at unit distance,
//                  sampled uniformly by area, so the flux per solid angle is
//                  ∝ 1/cos³θ (θ from d) and a facing surface receives
//                  rgb·2cos h/(1 + cos h).
//   blender4_cone  Blender ≥ 4.0 (4.5, 5.x): a cone of uniform radiance,
//                  rgb/(2π(1 − cos h)); a facing surface receives
//                  rgb·(1 + cos h)/2 (the add-on's strength).
//   eevee_next_shadowed  EEVEE Next (4.2+) drawing a sun that casts a
//                  shadow: the cone's radiance and horizon-clipped
//                  irradiance, times the fraction of the shadow's cone above
//                  the receiver's horizon. EEVEE traces a sun's shadow with
//                  rays spread uniformly over the whole cone
//                  (shadow_ray_generate_directional) and a ray under the
//                  receiver's horizon meets the receiver in the shadow map,
//                  so the part of the sun already clipped by the horizon is
//                  cut a second time (docs/lights.md, "Suns in EEVEE").
//   eevee_legacy   EEVEE Legacy (3.x): a disc of radius r = tan h at unit
//                  distance, i.e. the cone, of radiance
//                  strength·(1 + r²/2)/(π r²) (eevee_lights.c); its kernel
//                  per unit flux is the cone's, its strength per flux
//                  r²/((2 + r²)(1 − cos h)).
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

// The sun model of a target renderer in a Blender version: `eevee` false is
// Cycles (sun_model_for_blender); true is EEVEE Legacy before 4.2
// (eevee_legacy) and EEVEE Next from 4.2 on, eevee_next_shadowed for a sun
// casting a shadow, the Cycles cone without (docs/lights.md, "Suns in EEVEE").
SunModel sun_model_for_renderer(int major, int minor, bool eevee, bool shadow);

// Fraction of a uniform cone of half-angle h whose axis makes cos β = c with
// a receiver's normal that lies above the receiver's horizon: 1 for
// c ≥ sin h, 0 for c ≤ −sin h.
double cone_fraction_above_horizon(double c, double half_angle);

// Suns narrower than this (radians, full angle) are written with angle 0:
// Cycles drops a sun of angle <= 1e-10 (its cone pdf overflows a float), and
// a one-pixel region's RMS radius is rounding noise (~1e-16); 1e-6 is far
// below a pixel of any map the tool reads (2π/65536 ≈ 1e-4).
constexpr double min_sun_angle = 1e-6;

// Angle (radians, full angular diameter) of the sun the add-on writes for a
// region of RMS angular radius `spread`: clip(2√2·spread, 0, π), 0 below
// min_sun_angle.
double sun_angle(double spread);

// Half-angle h = sun_angle(spread)/2.
double sun_half_angle(double spread);

// The sun's strength (Blender's W/m²) per unit of the light's flux ∫L dω, for
// a sun of `angle` drawn as `model`, so that the sun carries the flux:
// blender4_cone makes the strength the irradiance on a facing surface, and
// its cone carries strength·2/(1 + cos h), hence (1 + cos h)/2; blender3_disc
// makes the strength the disc's ∫L dω, hence 1; a point sun (angle 0) is 1
// in both.
double sun_strength_per_flux(double angle, SunModel model);

// K(c, h): irradiance per unit flux, c = cos β clamped to [−1, 1].
double sun_kernel(double c, double half_angle, SunModel model);

// dK/dc (central difference for h > 0; the kernel is C¹ there).
double sun_kernel_slope(double c, double half_angle, SunModel model);

// Irradiance (RGB, one row per normal) of lights written as suns:
// Σ_k rgb_k · K(n·d_k, sun_half_angle(spread_k)).
Eigen::MatrixXd sun_irradiance(const std::vector<Light>& lights, const std::vector<Eigen::Vector3d>& normals,
                               SunModel model, int threads = 0);

}  // namespace penumbra::lights
