// Lights that follow a video frame by frame (issue #14 goal 2).
//
// The paper keeps light k = Halton point k pushed through each frame's CDF.
// When the map changes (it turns, a cloud passes) the CDF changes
// everywhere and every light moves; where a CDF row changes steeply, light k
// lands somewhere else altogether. Measured on a courtyard turning 1° per
// frame: a flux-weighted 95th percentile step of 2.2° once the turn is
// removed, and lights carrying 1% of the flux jumping by up to 26°.
//
// FOLLOW (default) carries every light over from the previous frame instead:
//   1. the map's own motion: the rotation R_t from frame t−1 to t
//      (motion.hpp), counted only as far as it explains the change;
//   2. every light is turned by R_t (direction, seed) and its colour scaled
//      by the change of the map's total ∫L dω per channel;
//   3. with the irradiance fit (irradiance_fit.hpp) the lights are refitted
//      from there, each direction held within `max_step` of where R_t put
//      it, the previous colours as a prior; without it, each light becomes
//      the region of its turned seed (region_lights), its direction held
//      within `max_step` of the turned one.
// A frame whose change is no rotation at all (motion residual above
// `cut_residual`: another shot) starts afresh, as the first frame does:
// sampling, region powers and, when on, the full fit. `cut` tells the
// temporal filter, which does not blend across it.
//
// RESAMPLE is the paper's: each frame's lights from its own CDF (used for
// the adaptive count, whose light count changes from frame to frame).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "lights/frame_lights.hpp"
#include "lights/motion.hpp"

namespace penumbra::lights {

enum class Tracking { follow, resample };

struct TrackingOptions {
    double max_step = 0.5 * 3.14159265358979323846 / 180.0;  // radians a light may move per frame, motion removed
    double cut_residual = 0.25;  // motion residual (motion.hpp) from which a frame starts a new shot
    int fit_iterations = 4;      // Levenberg–Marquardt steps of the refit per frame
};

class LightTracker {
public:
    LightTracker(LightOptions lights, TrackingOptions tracking = {});

    // The lights of the next frame. `cut`: this frame starts a shot (the first does).
    FrameLights next(const EnvironmentMap& map, bool& cut);

    // The rotation counted for the last frame (identity at a cut).
    const Eigen::Matrix3d& last_motion() const { return motion_; }

private:
    FrameLights start(const EnvironmentMap& map);
    FrameLights follow(const EnvironmentMap& map, const Eigen::Matrix3d& rotation);

    LightOptions options_;
    TrackingOptions tracking_;
    std::vector<Light> lights_;  // the previous frame's
    Eigen::Vector3d total_ = Eigen::Vector3d::Zero();
    MapSignature signature_;
    Eigen::Matrix3d motion_ = Eigen::Matrix3d::Identity();
    bool started_ = false;
};

}  // namespace penumbra::lights
