// The baseline the bake benchmark compares against: raw Embree occlusion
// throughput on the same mesh, with nothing else in the loop (no frames, no
// projection, no task scheduler: plain threads taking blocks of 64 vertices).
// Directions are drawn in advance (uniform on each vertex's upper
// hemisphere, fixed seed) and only the casting is timed. A benchmark
// baseline, so it lives in bench/, not in the library.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace penumbra::visibility {

struct ThroughputResult {
    std::size_t rays = 0;
    double seconds = 0.0;
    double rays_per_second = 0.0;
    double occluded_fraction = 0.0;
    int packet_width = 1;
};

// mode: "single" (rtcOccluded1 per ray) or "packet" (the bake's bundles).
ThroughputResult measure_occlusion_throughput(const std::vector<float>& positions, const std::vector<float>& normals,
                                              const std::vector<std::uint32_t>& triangles, int rays_per_vertex,
                                              int threads, const std::string& mode);

}  // namespace penumbra::visibility
