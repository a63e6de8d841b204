// Vertex frames and mesh topology (visibility/mesh_frames.hpp): orthonormal
// frames whose tangent follows the reference edge, neighbours from polygons.
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility_test_util.hpp"

namespace penumbra::visibility {
namespace {

using testing::TestMesh;
using testing::add_sphere;

TEST(VisibilityFrames, tangent_follows_the_reference_edge_and_frames_are_orthonormal) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    std::vector<float> frames(9 * m.mesh.vertex_count());
    vertex_frames(m.mesh.positions, m.normals, m.mesh.triangles, neighbours, frames.data());
    for (std::size_t v = 0; v < m.mesh.vertex_count(); ++v) {
        Eigen::Matrix3d f;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) f(i, j) = frames[9 * v + 3 * i + j];
        EXPECT_LT((f * f.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-5);
        EXPECT_NEAR(f.determinant(), 1.0, 1e-5);
        const Eigen::Vector3d edge(m.mesh.positions[3 * neighbours[v]] - m.mesh.positions[3 * v],
                                   m.mesh.positions[3 * neighbours[v] + 1] - m.mesh.positions[3 * v + 1],
                                   m.mesh.positions[3 * neighbours[v] + 2] - m.mesh.positions[3 * v + 2]);
        EXPECT_GT(f.row(0).dot(edge), 0.0);
        EXPECT_NEAR(f.row(1).dot(edge), 0.0, 1e-5);
    }
}

TEST(VisibilityFrames, neighbours_come_from_polygons_not_their_triangulation) {
    // One quad 0-1-2-3: vertex 0's neighbour is 1 whichever diagonal splits it.
    const auto n = reference_neighbours(4, {4}, {0, 1, 2, 3});
    EXPECT_EQ(n[0], 1u);
    EXPECT_EQ(n[3], 0u);
    EXPECT_THROW(reference_neighbours(4, {3}, {0, 1, 2, 3}), ArgumentError);
    EXPECT_NE(topology_hash(4, {4}, {0, 1, 2, 3}), topology_hash(4, {4}, {0, 1, 3, 2}));
    EXPECT_EQ(topology_hash(4, {4}, {0, 1, 2, 3}), topology_hash(4, {4}, {0, 1, 2, 3}));
}

}  // namespace
}  // namespace penumbra::visibility
