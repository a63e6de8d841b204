// Blender's world directions and equirectangular mapping (common/latlong.hpp),
// checked against Cycles' own formula (u = 0.5 − atan2(y, x)/2π, v = 1 −
// acos(z)/π with v = 0 the bottom row) written out here independently, and
// against the landmarks the header lists.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/latlong.hpp"

namespace penumbra::latlong {
namespace {

constexpr double pi = std::numbers::pi;

// Continuous pixel position of a direction by Cycles' direction_to_equirectangular,
// flipped to OpenImageIO's top-down rows.
Eigen::Vector2d cycles_pixel(const Eigen::Vector3d& d, int width, int height) {
    const double u = 0.5 - std::atan2(d.y(), d.x()) / (2.0 * pi);
    const double v = 1.0 - std::acos(d.z()) / pi;
    return {u * width, (1.0 - v) * height};
}

TEST(LatLong, world_angles_follow_blender_axes) {
    EXPECT_LT((direction_of_angles(0.0, 0.0) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);       // θ from +z
    EXPECT_LT((direction_of_angles(pi / 2, 0.0) - Eigen::Vector3d::UnitX()).norm(), 1e-15);    // φ from +x
    EXPECT_LT((direction_of_angles(pi / 2, pi / 2) - Eigen::Vector3d::UnitY()).norm(), 1e-15); // towards +y
    EXPECT_LT((direction_of_angles(pi, 1.0) + Eigen::Vector3d::UnitZ()).norm(), 1e-15);
    const Eigen::Vector3d d = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
    EXPECT_LT((direction_of_angles(theta_of_direction(d), phi_of_direction(d)) - d).norm(), 1e-15);
}

TEST(LatLong, pixel_centres_match_cycles_direction_to_equirectangular) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (const auto& [w, h] : {std::pair{2, 1}, std::pair{64, 32}, std::pair{1000, 333}}) {
        for (int k = 0; k < 200; ++k) {
            const int r = int(uniform(rng) * h), c = int(uniform(rng) * w);
            const Eigen::Vector2d p = cycles_pixel(pixel_direction(r, c, h, w), w, h);
            EXPECT_NEAR(p.x(), c + 0.5, 1e-9 * w) << w << "x" << h << " pixel " << r << ", " << c;
            EXPECT_NEAR(p.y(), r + 0.5, 1e-9 * h) << w << "x" << h << " pixel " << r << ", " << c;
        }
    }
}

TEST(LatLong, pixel_centre_to_direction_and_back_is_the_same_position) {
    for (const double theta_max : {full_sphere, upper_hemisphere})
        for (const auto& [w, h] : {std::pair{3, 1}, std::pair{360, 90}, std::pair{2048, 1024}})
            for (int r = 0; r < h; r += std::max(1, h / 13))
                for (int c = 0; c < w; c += std::max(1, w / 17)) {
                    const Eigen::Vector3d d = pixel_direction(r, c, h, w, theta_max);
                    EXPECT_NEAR(d.norm(), 1.0, 1e-15);
                    EXPECT_NEAR(x_of_phi(phi_of_direction(d), w), c + 0.5, 1e-9 * w);
                    EXPECT_NEAR(theta_of_direction(d) / theta_max * h, r + 0.5, 1e-9 * h);
                }
}

TEST(LatLong, landmarks_centre_plus_x_edges_minus_x_quarters_plus_and_minus_y_top_up) {
    const int w = 400, h = 200;
    const auto at = [&](double x, double y) { return direction_at(y, x, h, w); };
    EXPECT_LT((at(200, 100) - Eigen::Vector3d::UnitX()).norm(), 1e-15);  // image centre
    EXPECT_LT((at(0, 100) + Eigen::Vector3d::UnitX()).norm(), 1e-15);    // left edge
    EXPECT_LT((at(400, 100) + Eigen::Vector3d::UnitX()).norm(), 1e-15);  // right edge
    EXPECT_LT((at(100, 100) - Eigen::Vector3d::UnitY()).norm(), 1e-15);  // a quarter from the left
    EXPECT_LT((at(300, 100) + Eigen::Vector3d::UnitY()).norm(), 1e-15);  // three quarters
    EXPECT_LT((at(123, 0) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);    // top row: up
    EXPECT_LT((at(321, 200) + Eigen::Vector3d::UnitZ()).norm(), 1e-15);  // bottom row: down
    // Moving right turns from +x towards −y: clockwise seen from above.
    EXPECT_LT(at(201, 100).y(), 0.0);
    // Upper hemisphere: the bottom row is the horizon.
    EXPECT_LT((direction_at(100, 200, 100, w, upper_hemisphere) - Eigen::Vector3d::UnitX()).norm(), 1e-15);
}

TEST(LatLong, x_of_phi_wraps_into_the_image) {
    EXPECT_EQ(x_of_phi(pi, 8), 0.0);
    EXPECT_EQ(x_of_phi(-pi, 8), 0.0);
    EXPECT_NEAR(x_of_phi(0.0, 8), 4.0, 1e-15);
    EXPECT_NEAR(x_of_phi(pi / 2 + 2 * pi, 8), 2.0, 1e-12);
    EXPECT_NEAR(x_of_phi(-pi / 2, 8), 6.0, 1e-15);
}

TEST(LatLong, pixel_solid_angles_are_exact_and_cover_the_sphere_or_hemisphere) {
    for (const double theta_max : {full_sphere, upper_hemisphere})
        for (const auto& [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{512, 256}}) {
            double total = 0.0;
            for (int r = 0; r < h; ++r) {
                const double omega = pixel_solid_angle(r, h, w, theta_max);
                const double top = theta_max * r / h, bottom = theta_max * (r + 1) / h;
                EXPECT_NEAR(omega, 2 * pi / w * (std::cos(top) - std::cos(bottom)), 1e-15);
                total += w * omega;
            }
            EXPECT_NEAR(total, 2 * pi * (1.0 - std::cos(theta_max)), 1e-12) << w << "x" << h;
        }
}

}  // namespace
}  // namespace penumbra::latlong
