#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "lights/angular_regions.hpp"
#include "lights/clustering.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

std::vector<Light> random_lights(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> p(0.1, 2.0);
    std::vector<Light> lights(n);
    for (int i = 0; i < n; ++i) {
        lights[i].index = i;
        lights[i].direction = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        lights[i].power = p(rng);
        lights[i].rgb = Eigen::Vector3d::Constant(lights[i].power);
    }
    return lights;
}

TEST(LightsClustering, radius_follows_the_papers_formula) {
    ClusterOptions o;
    o.max_clusters = 32;
    o.full_sphere = false;
    EXPECT_NEAR(cluster_radius(o), 1.85 * std::asin(std::sqrt(2.0 / 32)), 1e-15);
    o.full_sphere = true;
    EXPECT_NEAR(cluster_radius(o), 1.85 * std::asin(std::sqrt(4.0 / 32)), 1e-15);
    o.max_clusters = 0;
    EXPECT_THROW(cluster_radius(o), ArgumentError);
}

TEST(LightsClustering, greedy_clusters_are_bounded_conserve_power_and_match_brute_force) {
    const auto lights = random_lights(300, 1);
    for (int q : {1, 8, 40, 300}) {
        ClusterOptions o;
        o.max_clusters = q;
        const Clustering c = cluster_lights(lights, o);
        EXPECT_LE(int(c.clusters.size()), q);
        double in = 0, out = 0;
        for (const auto& l : lights) in += l.power;
        for (const auto& l : c.clusters) out += l.power;
        EXPECT_NEAR(in, out, 1e-9);
        // Brute force with the same final radius.
        std::vector<int> owner(lights.size(), -1);
        int clusters = 0;
        for (std::size_t i = 0; i < lights.size(); ++i) {
            if (owner[i] >= 0) continue;
            for (std::size_t j = 0; j < lights.size(); ++j)
                if (owner[j] < 0 && lights[j].direction.dot(lights[i].direction) >= std::cos(c.radius) - 1e-12)
                    owner[j] = clusters;
            owner[i] = clusters;
            ++clusters;
        }
        EXPECT_EQ(owner, c.cluster_of) << "Q = " << q;
        for (std::size_t k = 0; k < c.clusters.size(); ++k) {
            int lowest = 1 << 30;
            for (std::size_t j = 0; j < lights.size(); ++j)
                if (c.cluster_of[j] == int(k)) lowest = std::min(lowest, lights[j].index);
            EXPECT_EQ(c.clusters[k].index, lowest);
        }
    }
}

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
