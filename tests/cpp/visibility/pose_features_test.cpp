// The pose vector (visibility/pose_features.hpp): each joint's features and
// the principal directions kept of them, on joints whose motion is known.
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "visibility/pose_features.hpp"

namespace penumbra::visibility {
namespace {

// Row-major rotation by `angle` about z: a hinge.
std::array<float, 9> about_z(double angle) {
    const float c = float(std::cos(angle)), s = float(std::sin(angle));
    return {c, -s, 0.0f, s, c, 0.0f, 0.0f, 0.0f, 1.0f};
}

// Frames × 2 joints: joint 0 a hinge swinging over `angles`, joint 1 still
// (rotated, but the same in every frame).
Eigen::MatrixXd hinge_and_still(PoseFeatures features, const std::vector<double>& angles) {
    const int fpj = features_per_joint(features);
    const std::array<float, 9> still = about_z(0.3);
    Eigen::MatrixXd raw(Eigen::Index(angles.size()), 2 * fpj);
    for (std::size_t f = 0; f < angles.size(); ++f) {
        double phi[9];
        joint_features(features, about_z(angles[f]).data(), phi);
        for (int a = 0; a < fpj; ++a) raw(Eigen::Index(f), a) = phi[a];
        joint_features(features, still.data(), phi);
        for (int a = 0; a < fpj; ++a) raw(Eigen::Index(f), fpj + a) = phi[a];
    }
    return raw;
}

TEST(PoseFeatures, a_rotation_gives_r_minus_i_or_its_rotation_vector) {
    const std::array<float, 9> r = about_z(std::numbers::pi / 2);
    double m[9], v[3];
    joint_features(PoseFeatures::RotationMatrix, r.data(), m);
    const double expected[9] = {-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(m[i], expected[i], 1e-7) << i;
    joint_features(PoseFeatures::RotationVector, r.data(), v);
    EXPECT_NEAR(v[0], 0.0, 1e-7);
    EXPECT_NEAR(v[1], 0.0, 1e-7);
    EXPECT_NEAR(v[2], std::numbers::pi / 2, 1e-6);
    EXPECT_NEAR(rotation_angle_between(about_z(0.2).data(), about_z(-0.5).data()), 0.7, 1e-6);
}

TEST(PoseFeatures, a_hinge_keeps_the_directions_it_spans_and_a_still_joint_none) {
    const std::vector<double> angles = {-0.8, -0.3, 0.0, 0.4, 0.9, 1.2};
    const std::vector<std::size_t> rows = {0, 1, 2, 3, 4, 5};
    // R − I of a hinge moves in a plane (cos θ − 1 and sin θ); its rotation
    // vector along one axis.
    for (auto [features, expected] : {std::pair{PoseFeatures::RotationMatrix, 2u},
                                      std::pair{PoseFeatures::RotationVector, 1u}}) {
        const int fpj = features_per_joint(features);
        const Eigen::MatrixXd raw = hinge_and_still(features, angles);
        const FeatureDirections dirs = principal_feature_directions(raw, rows, fpj, 0.03);
        ASSERT_EQ(dirs.offsets.size(), 3u);
        EXPECT_EQ(dirs.offsets[1], expected);
        EXPECT_EQ(dirs.offsets[2], expected);  // the still joint adds none
        ASSERT_EQ(dirs.basis.size(), std::size_t(expected) * fpj);
        // The hinge's features lie in the span of its directions: projected
        // and lifted back, they come back to float rounding.
        const Eigen::MatrixXd A = project_pose_matrix(raw, fpj, dirs);
        ASSERT_EQ(A.cols(), Eigen::Index(expected));
        for (Eigen::Index f = 0; f < raw.rows(); ++f)
            for (int a = 0; a < fpj; ++a) {
                double lifted = 0.0;
                for (Eigen::Index c = 0; c < A.cols(); ++c) lifted += A(f, c) * dirs.basis[std::size_t(c) * fpj + a];
                EXPECT_NEAR(lifted, raw(f, a), 1e-6) << "frame " << f << " feature " << a;
            }
    }
}

TEST(PoseFeatures, the_feature_tolerance_drops_a_joints_smaller_directions) {
    // Over small angles cos θ − 1 moves far less than sin θ: a tolerance
    // above their ratio keeps the sine's direction alone.
    const std::vector<double> angles = {-0.1, -0.05, 0.0, 0.05, 0.1, 0.02};
    const std::vector<std::size_t> rows = {0, 1, 2, 3, 4, 5};
    const Eigen::MatrixXd raw = hinge_and_still(PoseFeatures::RotationMatrix, angles);
    EXPECT_EQ(principal_feature_directions(raw, rows, 9, 0.0).offsets[1], 2u);
    EXPECT_EQ(principal_feature_directions(raw, rows, 9, 0.2).offsets[1], 1u);
}

}  // namespace
}  // namespace penumbra::visibility
