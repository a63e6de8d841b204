#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "lights/environment.hpp"
#include "lights/mapping.hpp"
#include "sh/projection.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

TEST(LightsMapping, equirectangular_centres_agree_with_the_sh_engine_convention) {
    for (int h : {1, 3, 90, 512}) {
        const int w = 2 * h + 1;
        for (int r = 0; r < h; r += std::max(1, h / 7))
            for (int c = 0; c < w; c += std::max(1, w / 9)) {
                Eigen::Vector3d d;
                ASSERT_TRUE(image_to_direction(Projection::equirectangular, {}, w, h, c + 0.5, r + 0.5, d));
                EXPECT_LT((d - sh::equirectangular_direction(r, c, h, w)).norm(), 1e-12);
                EXPECT_NEAR(pixel_solid_angle(Projection::equirectangular, {}, w, h, c, r),
                            sh::equirectangular_solid_angle(r, h, w), 1e-15);
            }
    }
}

TEST(LightsMapping, landmarks_of_each_projection) {
    Eigen::Vector3d d;
    // Equirectangular: centre +x, quarter from the left +y, top +z.
    image_to_direction(Projection::equirectangular, {}, 400, 200, 200, 100, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitX()).norm(), 1e-12);
    image_to_direction(Projection::equirectangular, {}, 400, 200, 100, 100, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitY()).norm(), 1e-12);
    // Polar: bottom row is the horizon.
    image_to_direction(Projection::hemisphere_polar, {}, 360, 90, 180, 90, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitX()).norm(), 1e-12);
    // Fisheye: centre zenith, top edge +y, right edge −x.
    image_to_direction(Projection::fisheye, {}, 200, 200, 100, 100, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    image_to_direction(Projection::fisheye, {}, 200, 200, 100, 0, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitY()).norm(), 1e-9);
    image_to_direction(Projection::fisheye, {}, 200, 200, 200, 100, d);
    EXPECT_LT((d + Eigen::Vector3d::UnitX()).norm(), 1e-9);
    EXPECT_FALSE(image_to_direction(Projection::fisheye, {}, 200, 200, 1, 1, d));
    // Mirror ball: centre reflects −y (towards the camera), top +z, right +x.
    image_to_direction(Projection::mirror_ball, {}, 200, 200, 100, 100, d);
    EXPECT_LT((d + Eigen::Vector3d::UnitY()).norm(), 1e-12);
    image_to_direction(Projection::mirror_ball, {}, 200, 200, 100, 100 - 100 * std::sqrt(0.5), d);
    EXPECT_LT((d - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
    image_to_direction(Projection::mirror_ball, {}, 200, 200, 100 + 100 * std::sqrt(0.5), 100, d);
    EXPECT_LT((d - Eigen::Vector3d::UnitX()).norm(), 1e-9);
}

TEST(LightsMapping, direction_to_image_inverts_image_to_direction) {
    FisheyeLens kb;
    kb.k = {-0.05, 0.01, 0.0, 0.0};
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.02, 0.98);
    for (auto p : {Projection::equirectangular, Projection::hemisphere_polar, Projection::fisheye, Projection::mirror_ball})
        for (const FisheyeLens& lens : {FisheyeLens{}, kb})
            for (int i = 0; i < 500; ++i) {
                const double x = 300 * u(rng), y = 200 * u(rng);
                Eigen::Vector3d d;
                if (!image_to_direction(p, lens, 300, 200, x, y, d)) continue;
                double x2, y2;
                ASSERT_TRUE(direction_to_image(p, lens, 300, 200, d, x2, y2));
                EXPECT_NEAR(x, x2, 1e-7) << projection_name(p);
                EXPECT_NEAR(y, y2, 1e-7) << projection_name(p);
            }
}

TEST(LightsMapping, pixel_solid_angles_integrate_to_the_covered_sphere) {
    auto total = [](Projection p, const FisheyeLens& lens, int w, int h) {
        double s = 0.0;
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) s += pixel_solid_angle(p, lens, w, h, c, r);
        return s;
    };
    EXPECT_NEAR(total(Projection::equirectangular, {}, 64, 32), 4 * pi, 1e-12);
    EXPECT_NEAR(total(Projection::hemisphere_polar, {}, 360, 90), 2 * pi, 1e-12);
    EXPECT_NEAR(total(Projection::fisheye, {}, 400, 400), 2 * pi, 2 * pi * 0.01);
    FisheyeLens kb;
    kb.k = {-0.05, 0.01, 0.0, 0.0};
    EXPECT_NEAR(total(Projection::fisheye, kb, 400, 400), 2 * pi, 2 * pi * 0.01);
    EXPECT_NEAR(total(Projection::mirror_ball, {}, 400, 400), 4 * pi, 4 * pi * 0.01);
}

TEST(LightsMapping, bad_lenses_are_argument_errors) {
    FisheyeLens bad;
    bad.k = {-1.0, 0.0, 0.0, 0.0};
    EXPECT_THROW(bad.check(), ArgumentError);
}

}  // namespace
}  // namespace penumbra::lights
