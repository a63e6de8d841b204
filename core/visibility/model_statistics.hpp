// Counts about a fitted pose model (pose_model.hpp) that reports and
// benchmarks show: how many vertices keep one set of lobes for every pose,
// and how many joint blocks each vertex's lobes depend on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visibility/pose_model.hpp"

namespace penumbra::visibility {

// Vertices with no joint block: their lobes are the bias in every pose.
std::size_t constant_vertex_count(const PoseModel& model);

// Joint blocks per vertex (vertex_count values).
std::vector<std::uint32_t> joints_per_vertex(const PoseModel& model);

}  // namespace penumbra::visibility
