#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "lights/motion.hpp"
#include "lights/rig.hpp"
#include "lights/tracking.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double degree = pi / 180.0;

// A sky with structure everywhere: a gradient towards a tilted zenith, a
// bright sun, a dimmer patch, all smooth at the pixel scale (a hard-edged
// disc a few pixels wide changes pixel by pixel as it turns), seen through
// `rotation` (content at d moves to R·d: the map's value at d is the unturned
// sky's at Rᵀ·d).
Image turned_sky(int w, int h, const Eigen::Matrix3d& rotation, double exposure = 1.0) {
    Image im(w, h, 3);
    const Eigen::Vector3d up = Eigen::Vector3d(0.2, -0.1, 1.0).normalized();
    const Eigen::Vector3d sun = Eigen::Vector3d(0.6, 0.3, 0.5).normalized();
    const Eigen::Vector3d patch = Eigen::Vector3d(-0.5, 0.7, -0.2).normalized();
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const double theta = pi * (r + 0.5) / h, phi = pi - 2 * pi * (c + 0.5) / w;
            const Eigen::Vector3d d = rotation.transpose() * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                                                              std::sin(theta) * std::sin(phi),
                                                                              std::cos(theta));
            double v = 0.3 + 0.7 * std::max(0.0, d.dot(up));
            v += 400.0 * std::exp((d.dot(sun) - 1.0) / 0.002);
            v += 3.0 * std::exp((d.dot(patch) - 1.0) / 0.02);
            for (int ch = 0; ch < 3; ++ch) im.at(c, r, ch) = float(exposure * v * (0.8 + 0.2 * ch));
        }
    return im;
}

Eigen::Matrix3d turn(double angle, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

double angle_of(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle(); }

TEST(LightsMotion, recovers_a_turn_about_any_axis_and_ignores_exposure) {
    const EnvironmentMap a = testing::as_map(turned_sky(256, 128, Eigen::Matrix3d::Identity()));
    const MapSignature sa = map_signature(a);
    for (const Eigen::Vector3d& axis : std::vector<Eigen::Vector3d>{Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, -2, 0.5)})
        for (double step : {0.5, 2.0, 6.0}) {
            const Eigen::Matrix3d truth = turn(step * degree, axis);
            const MapMotion m = estimate_rotation(sa, map_signature(testing::as_map(turned_sky(256, 128, truth))));
            EXPECT_LT(angle_of(m.rotation * truth.transpose()), 0.1 * degree) << step << "° about " << axis.transpose();
            EXPECT_LT(m.residual, 0.3 * m.change);
        }
    const MapMotion brighter = estimate_rotation(sa, map_signature(testing::as_map(turned_sky(256, 128, Eigen::Matrix3d::Identity(), 1.7))));
    EXPECT_LT(angle_of(brighter.rotation), 1e-6);
    EXPECT_LT(brighter.residual, 1e-6);
}

TEST(LightsMotion, another_map_is_no_turn) {
    const MapSignature sky = map_signature(testing::as_map(turned_sky(128, 64, Eigen::Matrix3d::Identity())));
    const MapSignature sun = map_signature(testing::as_map(
        testing::sky_and_sun(128, 64, 0.05, Eigen::Vector3d(-0.3, -0.8, 0.2), 0.1, 50.0)));
    EXPECT_GT(estimate_rotation(sky, sun).residual, TrackingOptions{}.cut_residual);
    const MapSignature black = map_signature(testing::as_map(testing::constant_image(64, 32, 0, 0, 0)));
    EXPECT_TRUE(black.coefficients.isZero());
    EXPECT_EQ(estimate_rotation(black, black).residual, 0.0);
    EXPECT_GT(estimate_rotation(sky, black).residual, TrackingOptions{}.cut_residual);
}

// Flux-weighted mean and largest angle the lights moved between consecutive
// frames once the map's turn is removed.
struct Steps {
    double mean = 0.0, largest = 0.0;
};
Steps steps(const std::vector<FrameLights>& frames, const Eigen::Matrix3d& per_frame) {
    Steps out;
    double weight = 0.0;
    for (std::size_t t = 1; t < frames.size(); ++t)
        for (std::size_t k = 0; k < frames[t].lights.size(); ++k) {
            const Light &a = frames[t - 1].lights[k], &b = frames[t].lights[k];
            const Eigen::Vector3d predicted = per_frame * a.direction;
            const double angle = std::atan2(predicted.cross(b.direction).norm(), predicted.dot(b.direction));
            const double w = a.power / frames[t - 1].total_power + b.power / frames[t].total_power;
            out.mean += w * angle;
            weight += w;
            out.largest = std::max(out.largest, angle);
        }
    out.mean /= weight;
    return out;
}

TEST(LightsTracking, lights_turn_with_the_map_where_resampled_ones_jump) {
    const Eigen::Matrix3d per_frame = turn(1.5 * degree, Eigen::Vector3d(0.3, 0.1, 1.0));
    LightOptions o;
    o.count = 24;
    for (bool fit : {false, true}) {
        o.fit_irradiance = fit;
        LightTracker tracker(o);
        std::vector<FrameLights> followed, resampled;
        Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
        for (int t = 0; t < 8; ++t, r = per_frame * r) {
            const EnvironmentMap map = testing::as_map(turned_sky(192, 96, r));
            bool cut = false;
            followed.push_back(tracker.next(map, cut));
            EXPECT_EQ(cut, t == 0);
            resampled.push_back(compute_lights(map, o));
        }
        // No light moves more than max_step from where the estimated turn
        // put it (plus the estimate's error); on average far less. Measured
        // at this coarse 1.9° per pixel: 0.24° (regions: pixels change hands
        // between neighbouring regions as the map turns) and 0.01° (fit),
        // flux-weighted. Resampled lights wander (1.3°, 5.8°), some by tens
        // of degrees.
        const Steps f = steps(followed, per_frame), re = steps(resampled, per_frame);
        EXPECT_LE(f.largest, TrackingOptions{}.max_step + 0.05 * degree) << "fit " << fit;
        EXPECT_LT(f.mean, (fit ? 0.05 : 0.4) * degree) << "fit " << fit;
        EXPECT_GT(re.mean, 1.0 * degree) << "fit " << fit;
        EXPECT_GT(re.largest, 5.0 * degree) << "fit " << fit;
    }
}

TEST(LightsTracking, a_cut_starts_afresh_and_the_filter_does_not_blend_across_it) {
    RigOptions o;
    o.map.max_width = 0;
    o.lights.count = 12;
    RigBuilder rig(o);
    const Image first = turned_sky(128, 64, Eigen::Matrix3d::Identity());
    const Image second = testing::sky_and_sun(128, 64, 0.05, Eigen::Vector3d(-0.3, -0.8, 0.2), 0.1, 50.0);
    for (int t = 0; t < 10; ++t) rig.add_frame(t < 5 ? first : second);
    const LightRig out = rig.finish(21.0);
    // The second shot's lights are the second map's own, frame after frame,
    // from the cut on: as if it were a rig of its own.
    RigBuilder alone(o);
    for (int t = 0; t < 5; ++t) alone.add_frame(second);
    const LightRig own = alone.finish(21.0);
    for (int t = 5; t < 10; ++t)
        for (int k = 0; k < 12; ++k) {
            EXPECT_LT((out.frames[t].lights[k].direction - own.frames[t - 5].lights[k].direction).norm(), 1e-9);
            EXPECT_LT((out.frames[t].lights[k].rgb - own.frames[t - 5].lights[k].rgb).norm(),
                      1e-9 * own.frames[t - 5].total_rgb.norm());
        }
}

TEST(LightsTracking, rejects_bad_options) {
    TrackingOptions t;
    t.max_step = -1.0;
    EXPECT_THROW(LightTracker(LightOptions{}, t), ArgumentError);
    t = {};
    t.cut_residual = 0.0;
    EXPECT_THROW(LightTracker(LightOptions{}, t), ArgumentError);
}

}  // namespace
}  // namespace penumbra::lights
