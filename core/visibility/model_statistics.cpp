#include "visibility/model_statistics.hpp"

namespace penumbra::visibility {

std::size_t constant_vertex_count(const PoseModel& model) {
    std::size_t n = 0;
    for (std::size_t v = 0; v < model.vertex_count; ++v) n += model.joint_offsets[v] == model.joint_offsets[v + 1];
    return n;
}

std::vector<std::uint32_t> joints_per_vertex(const PoseModel& model) {
    std::vector<std::uint32_t> n(model.vertex_count);
    for (std::size_t v = 0; v < model.vertex_count; ++v) n[v] = model.joint_offsets[v + 1] - model.joint_offsets[v];
    return n;
}

}  // namespace penumbra::visibility
