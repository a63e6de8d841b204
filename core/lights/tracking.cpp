#include "lights/tracking.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "lights/irradiance_fit.hpp"
#include "lights/sampling.hpp"

namespace penumbra::lights {

namespace {

double luma(const std::array<double, 3>& y, const Eigen::Vector3d& rgb) {
    return y[0] * rgb[0] + y[1] * rgb[1] + y[2] * rgb[2];
}

// The share of the estimated rotation that is counted. A cross-fade or a
// flicker changes the signature in ways a small turn partly mimics (0.3–0.6°
// per frame measured on a forest → sunset fade, where the turn explains
// under a third of the change); a real turn explains nearly all of it (over
// 95% for the bundled maps turned 0.5–5° per frame, 70% for forest at 0.5°,
// whose resampling noise is largest). Explained share e = 1 − (residual /
// change)²: the turn counts in full from e = 0.7, not at all below 0.3,
// linearly between.
Eigen::Matrix3d counted_rotation(const MapMotion& m) {
    if (!(m.change > 0.0)) return Eigen::Matrix3d::Identity();
    const double explained = 1.0 - (m.residual / m.change) * (m.residual / m.change);
    const double weight = std::clamp((explained - 0.3) / 0.4, 0.0, 1.0);
    const Eigen::AngleAxisd turn(m.rotation);
    return Eigen::AngleAxisd(weight * turn.angle(), turn.axis()).toRotationMatrix();
}

// d moved towards `to`, at most `most` radians from `from` (d's start).
Eigen::Vector3d held_within(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double most) {
    const double angle = std::atan2(from.cross(to).norm(), from.dot(to));
    if (angle <= most) return to;
    const Eigen::Vector3d axis = from.cross(to);
    if (axis.norm() < 1e-300) return from;
    return Eigen::AngleAxisd(most, axis.normalized()) * from;
}

}  // namespace

LightTracker::LightTracker(LightOptions lights, TrackingOptions tracking)
    : options_(std::move(lights)), tracking_(tracking) {
    if (!(tracking_.max_step >= 0.0)) throw ArgumentError("the tracker's max_step must be >= 0");
    if (!(tracking_.cut_residual > 0.0)) throw ArgumentError("the tracker's cut_residual must be > 0");
    if (tracking_.fit_iterations < 0) throw ArgumentError("the tracker's fit_iterations must be >= 0");
}

FrameLights LightTracker::next(const EnvironmentMap& map, bool& cut) {
    MapSignature signature = map_signature(map, options_.luminance, options_.threads);
    cut = !started_;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (started_) {
        const MapMotion m = estimate_rotation(signature_, signature, motion_);
        if (m.residual > tracking_.cut_residual)
            cut = true;
        else
            rotation = counted_rotation(m);
        // A hemispherical map (its lower half unseen) can only turn about +z.
        if (!map.full_sphere)
            rotation = Eigen::AngleAxisd(std::atan2(rotation(1, 0), rotation(0, 0)), Eigen::Vector3d::UnitZ())
                           .toRotationMatrix();
    }
    FrameLights out = cut ? start(map) : follow(map, rotation);
    signature_ = std::move(signature);
    motion_ = rotation;
    lights_ = out.lights;
    total_ = out.total_rgb;
    started_ = true;
    return out;
}

FrameLights LightTracker::start(const EnvironmentMap& map) { return compute_lights(map, options_); }

FrameLights LightTracker::follow(const EnvironmentMap& map, const Eigen::Matrix3d& rotation) {
    FrameLights out;
    out.total_rgb = integral_rgb(map);
    out.total_power = luma(options_.luminance, out.total_rgb);
    // The previous lights turned with the map, their colours scaled by its change.
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    for (int c = 0; c < 3; ++c) scale[c] = total_[c] > 0.0 ? out.total_rgb[c] / total_[c] : 1.0;
    std::vector<Light> turned = lights_;
    for (Light& l : turned) {
        l.direction = (rotation * l.direction).normalized();
        l.sample_direction = (rotation * l.sample_direction).normalized();
        l.rgb = l.rgb.cwiseProduct(scale);
        l.power = luma(options_.luminance, l.rgb);
    }
    if (options_.fit_irradiance && int(turned.size()) <= LightOptions::max_fitted_lights) {
        IrradianceFitOptions fit;
        fit.sun_model = options_.sun_model;
        fit.luminance = options_.luminance;
        fit.threads = options_.threads;
        fit.iterations = tracking_.fit_iterations;
        fit.move_bound.assign(turned.size(), tracking_.max_step);
        for (const Light& l : turned) fit.prior_rgb.push_back(l.rgb);
        out.lights = turned;
        fit_irradiance(map, out.lights, fit);
        return out;
    }
    std::vector<Eigen::Vector3d> seeds;
    for (const Light& l : turned) seeds.push_back(l.sample_direction);
    const LuminanceDistribution dist = luminance_distribution(map, options_.luminance, options_.threads);
    FrameLights regions = region_lights(map, dist, seeds, options_);
    for (std::size_t k = 0; k < regions.lights.size(); ++k)
        regions.lights[k].direction = held_within(turned[k].direction, regions.lights[k].direction, tracking_.max_step);
    return regions;
}

}  // namespace penumbra::lights
