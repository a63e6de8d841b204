// The pose vector of the linear pose-space model (pose_model.hpp): what
// each joint's rotation contributes, and the few directions each joint
// actually moves along.
//
// Pose vector. Each active joint contributes its rotation relative to rest,
// in its parent's space (Blender: rest-relative local rotation, constraints
// and IK included), as the 9 entries of R − I (PoseFeatures::RotationMatrix,
// the default) or as its rotation vector (axis·angle, PoseFeatures::
// RotationVector). The matrix form is continuous everywhere (no double cover
// as with quaternions, no wrap at π as with the rotation vector or Euler
// angles), and linear-blend skinning moves every vertex linearly in exactly
// these entries, so the geometry the visibility comes from is linear in
// them; the rotation vector is 3 numbers instead of 9 and is continuous for
// rotations below π. A bias column (the constant 1) completes A.
//
// Joint features. A joint rarely moves along all its feature directions: a
// knee or an elbow is a hinge (its R − I spans 2 dimensions), a shoulder
// moves mostly along 3 or 4. Each joint's raw features are projected on the
// principal directions it moved along over the training frames (those whose
// singular value is at least feature_tolerance times the joint's largest),
// and the model is linear in those projections: every stored weight block is
// that many rows instead of 9. Ridge would have shrunk the dropped
// directions almost to nothing anyway; dropping them makes the model and
// the run time's read smaller.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "visibility/visibility_bake.hpp"

namespace penumbra::visibility {

enum class PoseFeatures : std::uint32_t { RotationMatrix = 0, RotationVector = 1 };

int features_per_joint(PoseFeatures features);

// One joint's features from its rotation (row-major 3×3): R − I, or the
// rotation vector.
void joint_features(PoseFeatures features, const float* rotation, double* out);

// Angle (radians) of the rotation between two row-major 3×3 rotations.
double rotation_angle_between(const float* a, const float* b);

// The raw features of the bones `bones` (indices into the set's bones) per
// frame: frames × bones·features_per_joint, bone after bone.
Eigen::MatrixXd raw_pose_matrix(const TrainingSet& set, const std::vector<std::size_t>& bones, PoseFeatures features);

// Each joint's principal feature directions: joint j's are the unit rows
// [offsets[j], offsets[j + 1]) of basis, features_per_joint floats each.
struct FeatureDirections {
    std::vector<std::uint32_t> offsets;  // joints + 1
    std::vector<float> basis;            // offsets.back() × features_per_joint
};

// The right singular vectors of each joint's raw features (fpj columns per
// joint of `raw`) over the frames `rows`, centred, whose singular value is
// at least `tolerance` times the joint's largest (and not zero to rounding).
FeatureDirections principal_feature_directions(const Eigen::MatrixXd& raw, const std::vector<std::size_t>& rows,
                                               int fpj, double tolerance);

// The pose matrix (frames × Σ directions, without its bias column): each
// joint's raw features projected on its directions (the basis in float, as
// the run time applies it).
Eigen::MatrixXd project_pose_matrix(const Eigen::MatrixXd& raw, int fpj, const FeatureDirections& directions);

}  // namespace penumbra::visibility
