#include "lights/clustering.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "lights/direction_index.hpp"

namespace penumbra::lights {

double cluster_radius(const ClusterOptions& o) {
    if (o.max_clusters < 1) throw ArgumentError("cluster_max must be at least 1, got " + std::to_string(o.max_clusters));
    if (!(o.correction > 0.0)) throw ArgumentError("the clustering correction factor must be positive");
    const double share = (o.full_sphere ? 4.0 : 2.0) / o.max_clusters;
    return o.correction * std::asin(std::sqrt(std::min(1.0, share)));
}

Clustering cluster_lights(const std::vector<Light>& lights, const ClusterOptions& options) {
    Clustering out;
    out.radius = cluster_radius(options);
    std::vector<Eigen::Vector3d> dirs(lights.size());
    for (std::size_t i = 0; i < lights.size(); ++i) dirs[i] = lights[i].direction;
    const DirectionIndex index(dirs);
    std::vector<int> near;
    for (int attempt = 0; attempt < 200; ++attempt) {
        out.clusters.clear();
        out.cluster_of.assign(lights.size(), -1);
        std::vector<std::vector<int>> members;
        for (std::size_t i = 0; i < lights.size(); ++i) {
            if (out.cluster_of[i] >= 0) continue;
            const int id = int(members.size());
            members.push_back({});
            index.within(dirs[i], out.radius, near);
            for (int j : near)
                if (out.cluster_of[j] < 0) {
                    out.cluster_of[j] = id;
                    members.back().push_back(j);
                }
            if (out.cluster_of[i] < 0) {  // rounding: the seed always joins its own cluster
                out.cluster_of[i] = id;
                members.back().push_back(int(i));
            }
        }
        if (int(members.size()) > options.max_clusters && out.radius < std::numbers::pi) {
            out.radius = std::min(std::numbers::pi, out.radius * 1.1);
            continue;
        }
        for (const auto& m : members) {
            Light c;
            c.index = lights[m.front()].index;
            c.sample_direction = lights[m.front()].sample_direction;
            for (int j : m) {
                c.rgb += lights[j].rgb;
                c.power += lights[j].power;
            }
            // Power-weighted mean; plain mean when every member is dark.
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            for (int j : m) mean += (c.power > 0.0 ? lights[j].power : 1.0) * lights[j].direction;
            c.direction = mean.norm() > 1e-12 ? Eigen::Vector3d(mean.normalized()) : lights[m.front()].direction;
            double second = 0.0, weight = 0.0;
            for (int j : m) {
                const double a = std::atan2(lights[j].direction.cross(c.direction).norm(),
                                            lights[j].direction.dot(c.direction));
                const double w = c.power > 0.0 ? lights[j].power : 1.0;
                second += w * (a * a + lights[j].spread * lights[j].spread);
                weight += w;
            }
            c.spread = weight > 0.0 ? std::sqrt(second / weight) : 0.0;
            out.clusters.push_back(c);
        }
        return out;
    }
    return out;
}

}  // namespace penumbra::lights
