// Angular-region culling of directional lights (lights/angular_regions.hpp):
// the culled irradiance equals the brute-force sum while visiting fewer lights.
#include <gtest/gtest.h>

#include <random>

#include "lights/angular_regions.hpp"
#include "lights/frame_lights.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

using testing::random_lights;

TEST(LightsAngularRegions, culled_irradiance_equals_brute_force_with_fewer_visits) {
    const auto lights = random_lights(300, 2);
    std::vector<Eigen::Vector3d> dirs;
    for (const auto& l : lights) dirs.push_back(l.direction);
    const AngularRegionTable table(dirs, 6);
    EXPECT_EQ(table.region_count(), 216);
    for (int r = 0; r < table.region_count(); ++r) EXPECT_EQ(table.region_of(table.centre(r)), r);
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<Eigen::Vector3d> normals(1000);
    for (auto& n : normals) n = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    std::size_t visits = 0;
    const Eigen::MatrixXd a = irradiance_culled(table, lights, normals, &visits);
    const Eigen::MatrixXd b = irradiance(lights, normals);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
    const double ratio = double(visits) / (normals.size() * lights.size());
    EXPECT_LT(ratio, 0.75);
    EXPECT_GT(ratio, 0.5);
}

}  // namespace
}  // namespace penumbra::lights
