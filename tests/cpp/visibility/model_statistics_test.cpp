// Counts about a pose model (visibility/model_statistics.hpp).
#include <vector>

#include <gtest/gtest.h>

#include "visibility/model_statistics.hpp"

namespace penumbra::visibility {
namespace {

TEST(ModelStatistics, counts_vertices_without_joint_blocks_and_blocks_per_vertex) {
    PoseModel model;
    model.vertex_count = 4;
    model.joint_offsets = {0, 0, 2, 2, 3};
    EXPECT_EQ(constant_vertex_count(model), 2u);
    EXPECT_EQ(joints_per_vertex(model), (std::vector<std::uint32_t>{0, 2, 0, 1}));
}

}  // namespace
}  // namespace penumbra::visibility
