// The map's own motion between two frames of a video: the rotation that best
// carries one frame's lighting onto the next. The light tracker
// (tracking.hpp) turns its lights by it before refitting them, so a panning
// or rotating capture moves the rig with it instead of re-sampling it.
//
// Each frame is summarised by a signature: the spherical-harmonic
// coefficients (order `motion_order`, sh/basis.hpp) of
//   f(ω) = log(1 + Y(ω)/Ȳ),
// Y the luminance, Ȳ its mean over the map (solid-angle weighted), taken on a
// copy averaged down to at most 256 columns, normalised to unit length. f is
// a pointwise function of the map, so it turns with the map, and it does not
// change with exposure (Y/Ȳ) or let a sun 10⁴ times the sky hide the rest.
// A rotation R acts on coefficients as D(R) (sh/rotation.hpp), so
//   R* = argmin ‖D(R) a − b‖,  a, b the two frames' signatures,
// found by Levenberg–Marquardt on the rotation vector (R = exp([w]×) R₀),
// started from the identity and from a guess (the previous frame's motion)
// and kept from whichever ends lower. The remaining ‖D(R*) a − b‖ ∈ [0, 2]
// says how much of the change is not a rotation: near 0 for a turning map,
// small for a cross-fade or a flicker, large at a cut.
#pragma once

#include <array>

#include <Eigen/Core>

#include "lights/environment.hpp"

namespace penumbra::lights {

constexpr int motion_order = 8;

struct MapSignature {
    Eigen::VectorXd coefficients;  // motion_order², unit length (zero for a black map)
};

MapSignature map_signature(const EnvironmentMap& map, const std::array<double, 3>& luminance = rec709_luminance,
                           int threads = 0);

struct MapMotion {
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // content at d moves to R·d
    double residual = 0.0;                                    // ‖D(R) a − b‖ for unit a, b
    double change = 0.0;                                      // ‖a − b‖: the residual of no motion
};

MapMotion estimate_rotation(const MapSignature& from, const MapSignature& to,
                            const Eigen::Matrix3d& guess = Eigen::Matrix3d::Identity());

}  // namespace penumbra::lights
