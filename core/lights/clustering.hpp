// Light clustering (paper §4.3): merge lights with similar directions so a
// renderer with a shadow budget draws at most Q of them.
//
// Angular radius ε = c_f · arcsin(√(2/Q)) for lights over a hemisphere (each
// of Q clusters covers 2π/Q sr = π sin²ε before the correction c_f for
// covering a hemisphere with discs, c_f ≈ 1.8–1.9); over the full sphere
// 4π/Q, so ε = c_f · arcsin(√(min(1, 4/Q))). Greedy in sequence order: the
// first unassigned light seeds a cluster and takes every unassigned light
// within ε of it (found with a spatial index). A cluster keeps its seed's
// index (its identity over time, since seeds are the lowest indices and the
// lights are tracked by index), its power is the members' sum, its direction
// the normalized power-weighted mean (the paper's plain mean when powers are
// equal), its spread the power-weighted RMS of the members' angles from it
// combined with their own spreads. If the greedy pass leaves more than Q
// clusters, ε grows by 10% and the pass repeats, so the bound always holds.
// Power is conserved exactly (each light is in exactly one cluster).
#pragma once

#include <vector>

#include "lights/frame_lights.hpp"

namespace penumbra::lights {

struct ClusterOptions {
    int max_clusters = 64;          // Q >= 1
    double correction = 1.85;       // c_f
    bool full_sphere = true;        // the lights' domain (ε formula above)
};

double cluster_radius(const ClusterOptions& options);  // ε in radians (before any growth)

struct Clustering {
    std::vector<Light> clusters;            // in seed order; Light::index = seed's index
    std::vector<int> cluster_of;            // per input light, position in `clusters`
    double radius = 0.0;                    // the ε finally used
};

Clustering cluster_lights(const std::vector<Light>& lights, const ClusterOptions& options);

}  // namespace penumbra::lights
