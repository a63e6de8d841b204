// The linear pose-space model of ZH visibility (paper §3.1, fig. 2c, and the
// run-time step 1 of §4.3) as stored and as the run time applies it: per
// vertex, lobe parameters = A · X, with A the pose vector of the active
// joints plus a bias (pose_features.hpp), X the weights fitted by
// pose_fit.hpp. Each vertex stores a bias and, per joint it keeps, the
// weights of that joint's leading feature directions, as binary16 blocks
// (weight_blocks.hpp); a vertex with no joint block is constant. The file
// form is model_file.hpp's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "visibility/pose_features.hpp"
#include "visibility/visibility_bake.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {

struct PoseModel {
    int order = 4;
    int lobes = 2;
    int rays = 0;
    BelowHorizon below_horizon = BelowHorizon::Occluded;
    PoseFeatures features = PoseFeatures::RotationMatrix;
    std::uint64_t vertex_count = 0;
    std::uint64_t topology_hash = 0;
    std::vector<std::string> armature_bones;  // every bone of the armature at bake time
    std::vector<std::string> joints;          // active joints, in pose-vector order
    // Joint j's features: the raw features (features_per_joint of them)
    // projected on rows [feature_offsets[j], feature_offsets[j + 1]) of
    // feature_basis (unit rows of features_per_joint floats); m_j of them.
    std::vector<std::uint32_t> feature_offsets;  // joints + 1
    std::vector<float> feature_basis;            // feature_offsets.back() × features_per_joint
    // Per vertex v: params = bias[v] + Σ_{e in [joint_offsets[v], joint_offsets[v+1])}
    //   (the first c_e = block_directions[e] features of joint_index[e]) ·
    //   weight_scales[e] · block e (c_e × d),
    // the blocks one after another from weights[weight_offsets[v]], stored
    // as binary16 with a power-of-two scale per block (weight_blocks.hpp;
    // set_weights packs floats and sets weight_offsets, weight_values
    // unpacks).
    std::vector<std::uint32_t> joint_offsets;  // vertex_count + 1
    std::vector<std::uint16_t> joint_index;
    std::vector<std::uint8_t> block_directions;  // per block: c_e, 1..m_j
    std::vector<float> bias;                   // vertex_count × d
    std::vector<std::uint64_t> weight_offsets; // vertex_count + 1
    std::vector<std::uint16_t> weights;        // Σ over blocks of c_e × d, binary16 bits
    std::vector<float> weight_scales;          // blocks
    // Summary of the bake, stored with the model (name, value).
    std::vector<std::pair<std::string, double>> summary;

    int params_per_vertex() const { return lobes * params_per_lobe(order); }
    // m_j: how many features joint j has.
    int joint_feature_count(std::size_t j) const { return int(feature_offsets[j + 1] - feature_offsets[j]); }
};

// Run time (§4.3 step 1): joint_rotations is joints × 9 (row-major, in
// model.joints order); writes vertex_count × d lobe parameters.
void synthesize_params(const PoseModel& model, const float* joint_rotations, float* params_out, int threads = 0);

// The steps of synthesize_params for callers that fuse them with their own
// per-vertex work: the pose's features (Σ m_j floats, joint after joint;
// ArgumentError for a non-finite rotation), then the parameters of vertices
// [begin, end), written from params_out[0] on.
std::vector<float> pose_features(const PoseModel& model, const float* joint_rotations);
void synthesize_params_range(const PoseModel& model, const float* features, std::size_t begin, std::size_t end,
                             float* params_out);
// The same as rows: parameter i of vertex v at params_out[i · stride + v −
// begin] (stride ≥ end − begin).
void synthesize_rows(const PoseModel& model, const float* features, std::size_t begin, std::size_t end,
                     float* params_out, std::size_t stride);

// synthesize_params and lobes_from_params in one parallel pass.
void synthesize_lobes(const PoseModel& model, const float* joint_rotations, float* params_out, float* axes_out,
                      float* bands_out, int threads = 0);

// Lobe parameters → axes in the local frame (V × lobes × 3, unit to float
// rounding) and zonal bands (V × lobes × order), ready for Eq. 1.
void lobes_from_params(int order, int lobes, std::size_t vertex_count, const float* params, float* axes_out,
                       float* bands_out);

// Throws ArgumentError when the model is inconsistent (sizes, indices).
void check_pose_model(const PoseModel& model);

// Every joint's features as they come (R − I or the rotation vector): an
// identity basis, as models before the joint feature directions had, every
// block keeping all of them (the joints and blocks set first).
void use_raw_joint_features(PoseModel& model);

// The model's weights from floats (block after block, c_e × d each, as the
// joint offsets, indices and block directions give them; those and the
// feature offsets set first), rounded to the stored form, with
// weight_offsets; and back to floats.
void set_weights(PoseModel& model, const std::vector<float>& weights);
std::vector<float> weight_values(const PoseModel& model);
// Sets weight_offsets from the joint offsets and block directions
// (ArgumentError when those are inconsistent): what a reader of the stored
// blocks needs.
void index_weight_blocks(PoseModel& model);

}  // namespace penumbra::visibility
