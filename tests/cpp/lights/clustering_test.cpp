// Greedy light clustering (lights/clustering.hpp): the paper's radius, power
// conservation, and the same clusters as a brute-force pass.
#include <gtest/gtest.h>

#include <cmath>

#include "common/error.hpp"
#include "lights/clustering.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

using testing::random_lights;

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

}  // namespace
}  // namespace penumbra::lights
