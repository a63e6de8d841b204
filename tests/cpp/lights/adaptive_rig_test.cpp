// The adaptive count of a rig (issue 26 item 3): per shot the fewest fitted
// suns, as the target renderer draws them, within the irradiance tolerance.
#include <gtest/gtest.h>

#include <vector>

#include "lights/rig.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

using testing::as_map;

// One sun on a dim sky: a single light nearly carries it.
Image one_sun() { return testing::sky_and_sun(128, 64, 0.02, Eigen::Vector3d(0.4, 0.2, 0.7), 0.08, 200.0); }

// Six suns spread over the sphere: no handful of lights lights it right.
Image many_sources() {
    Image im = testing::sky_and_sun(128, 64, 0.02, Eigen::Vector3d(0.4, 0.2, 0.7), 0.08, 200.0);
    const std::vector<Eigen::Vector3d> suns{{-0.7, 0.3, 0.2}, {0.1, -0.8, 0.3}, {0.2, 0.9, -0.3},
                                            {-0.3, -0.4, -0.8}, {0.9, -0.1, -0.2}};
    for (const auto& d : suns) {
        const Image s = testing::sky_and_sun(128, 64, 0.0, d, 0.08, 200.0);
        for (std::size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] += s.pixels[i];
    }
    return im;
}

RigOptions options(int budget, double tolerance, SunModel model) {
    RigOptions o;
    o.lights.count = budget;
    o.lights.sun_model = model;
    o.adaptive_tolerance = tolerance;
    o.temporal_filter = false;
    return o;
}

LightRig build(const std::vector<Image>& frames, const RigOptions& o) {
    RigBuilder b(o);
    for (const Image& f : frames) b.add_map(as_map(f));
    return b.finish(24.0);
}

// The error of the rig with a fixed count, measured apart from the search.
double fixed_count_error(const Image& frame, int count, SunModel model) {
    RigOptions o = options(count, 0.0, model);
    const LightRig rig = build({frame}, o);
    return rig_error(as_map(frame), rig.frames[0].lights, model);
}

TEST(LightsAdaptiveRig, chosen_count_meets_the_tolerance_and_one_fewer_does_not) {
    constexpr double tolerance = 0.04;
    for (SunModel model : {SunModel::blender4_cone, SunModel::eevee_next_shadowed, SunModel::eevee_legacy}) {
        std::vector<int> counts;
        for (const Image& frame : {one_sun(), many_sources()}) {
            const LightRig rig = build({frame}, options(64, tolerance, model));
            const int n = rig.adaptive_count;
            ASSERT_GE(n, 1);
            ASSERT_LT(n, 64) << "the budget ran out, so the search proved nothing";
            EXPECT_EQ(rig.slots, n);
            EXPECT_LE(rig.adaptive_error, tolerance);
            EXPECT_LE(fixed_count_error(frame, n, model), tolerance);
            if (n > 1) {
                EXPECT_GT(fixed_count_error(frame, n - 1, model), tolerance);
            }
            counts.push_back(n);
        }
        EXPECT_LT(counts[0], counts[1]) << "many sources need more suns than one";
    }
}

TEST(LightsAdaptiveRig, one_count_per_shot_the_largest_its_frames_need) {
    constexpr double tolerance = 0.04;
    const RigOptions o = options(64, tolerance, SunModel::blender4_cone);
    const int alone = build({one_sun()}, o).adaptive_count;
    const int busy = build({many_sources()}, o).adaptive_count;
    ASSERT_LT(alone, busy);
    // Two shots (the change from one map to the other is no rotation): each
    // keeps its own count, and tracking keeps the busy shot's slots.
    const LightRig rig = build({one_sun(), one_sun(), many_sources(), many_sources()}, o);
    ASSERT_EQ(rig.frames.size(), 4u);
    EXPECT_EQ(rig.frames[0].adaptive_count, alone);
    EXPECT_EQ(rig.frames[1].adaptive_count, alone);
    EXPECT_EQ(rig.frames[2].adaptive_count, busy);
    EXPECT_EQ(rig.frames[3].adaptive_count, busy);
    EXPECT_EQ(rig.adaptive_count, busy);
    EXPECT_EQ(rig.frames[1].active, rig.frames[0].active);
    for (int k = 0; k < busy; ++k)  // the same map twice: a followed light stays put
        EXPECT_GT(rig.frames[3].lights[k].direction.dot(rig.frames[2].lights[k].direction), 0.999) << k;
}

TEST(LightsAdaptiveRig, eevee_legacy_draws_at_most_128_lights) {
    RigOptions o = options(200, 1e-9, SunModel::eevee_legacy);
    o.lights.fit_irradiance = false;  // the cap, not the fit, is under test
    EXPECT_EQ(build({many_sources()}, o).adaptive_count, eevee_legacy_max_lights);
    o.lights.sun_model = SunModel::blender4_cone;
    EXPECT_EQ(build({many_sources()}, o).adaptive_count, 200);
}

}  // namespace
}  // namespace penumbra::lights
