// The linear pose-space model of ZH visibility (paper §3.1, fig. 2c, and the
// run-time step 1 of §4.3): per vertex, lobe parameters = A · X, with A the
// pose vector of the active joints plus a bias.
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
//
// Active joints (the paper's j): bones that rotate by more than a tolerance
// over the training frames AND move part of this mesh relative to the rest
// of it (a bone that deforms no vertex, directly or through its children,
// or that carries the whole mesh rigidly, cannot change self-occlusion).
//
// Fit. Per frame and vertex, ZH lobes (zh_fit.hpp) make the rows of B. The
// columns of A are centred, and X solves the ridge problem
//   min |A_c X − B_c|² + λ |X|²
// through one SVD of A_c shared by every vertex; λ = ρ·s_max² is chosen from
// a fixed grid of ρ by the SH error on held-out frames (every k-th frame),
// linearized and in closed form from the SVD of the other frames
// (ridge_curve.hpp), then X is refitted on all frames. Rank deficiency (more
// columns than frames, repeated frames, joints that never move) only adds
// zero singular values, which ridge handles.
//
// Model only what the scene requires: a vertex whose lobe parameters vary by
// less than constant_tolerance (RMS) over the training frames stores a
// constant; for the others, joint directions whose contribution is small
// are dropped greedily (smallest first, a joint's last direction before its
// earlier ones, so that a vertex keeps of each joint its leading directions)
// while the dropped part stays under prune_tolerance (RMS over the training
// frames). Both are decided once, on
// the frames that are not held out (the model the held-out error measures),
// and the model refitted on every frame keeps those joints. The joint
// feature directions too are decided on those frames.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/setting.hpp"
#include "common/progress.hpp"
#include "visibility/visibility_bake.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {

enum class PoseFeatures : std::uint32_t { RotationMatrix = 0, RotationVector = 1 };

int features_per_joint(PoseFeatures features);

// One joint's features from its rotation (row-major 3×3): R − I, or the
// rotation vector.
void joint_features(PoseFeatures features, const float* rotation, double* out);

// Angle (radians) of the rotation between two row-major 3×3 rotations.
double rotation_angle_between(const float* a, const float* b);

// What the caller (Blender) knows about each bone of the armature, in the
// order of TrainingSet::bone_names.
struct BoneInfluence {
    bool deforms_mesh = true;          // the bone or a child carries weight on some vertex of this mesh
    bool rigid_for_whole_mesh = false; // every weighted vertex is fully carried by this bone's subtree
};

struct JointChoice {
    std::string name;
    bool active = false;
    double max_angle_degrees = 0.0;  // largest rotation away from the first training frame
    int feature_directions = 0;      // active joints: the feature directions kept (FitSettings::feature_tolerance)
    std::string reason;              // why kept or dropped
};

std::vector<JointChoice> choose_active_joints(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                                              double tolerance_degrees);

struct FitSettings {
    int lobes = 2;
    static constexpr Range<int> lobes_range{1, max_lobes};
    PoseFeatures features = PoseFeatures::RotationMatrix;
    double joint_tolerance_degrees = 1.0;
    int holdout_stride = 4;              // every k-th frame held out to choose λ; 0: none
    double constant_tolerance = 0.01;    // RMS lobe-parameter variation under which a vertex is constant
    double prune_tolerance = 0.01;       // RMS lobe-parameter change allowed by per-vertex pruning of joint directions
    // A joint's feature direction is kept when its singular value over the
    // training frames is at least this fraction of the joint's largest (0:
    // every direction with any movement).
    double feature_tolerance = 0.03;
    int zh_iterations = 8;       // Levenberg–Marquardt iterations of each vertex's reference fit
    // ... and of each (vertex, frame) fit, which starts from the reference
    // axes: on the humanoid (docs/visibility-humanoid-benchmark.md) 2 fit the
    // frames as well as 8 (ZH sh error +2 %), give a held-out model error no
    // worse, and take a quarter of the time of this, the fit's largest step;
    // 1 against 2: ZH sh error +2 % again, held-out model error lower on the
    // humanoid (AO 0.0149 vs 0.0152) and the test character (0.00308 vs
    // 0.00310), a third less time (docs/visibility.md).
    int frame_zh_iterations = 1;
    double axis_prior = 1.0;     // see zh_fit.hpp; 1 measured best for the linear model (docs/visibility.md)
    int threads = 0;
};

// Errors of SH visibility, each over (vertex, frame) pairs:
//   sh_rms: sqrt(mean |Δv|²/4π), the RMS difference of the visibility
//           function over the sphere (0: exact, 1: everything wrong);
//   ao_mean_abs: mean |Δ ambient occlusion| (the diffuse shade under a
//           uniform unit World, what the add-on writes under that light);
//   ao_max_abs: the largest.
struct Errors {
    double sh_rms = 0.0;
    double ao_mean_abs = 0.0;
    double ao_max_abs = 0.0;
    std::size_t samples = 0;
};

struct FitReport {
    std::vector<JointChoice> joints;
    std::size_t training_frames = 0, holdout_frames = 0;
    Errors zh_fit;            // ZH lobes vs baked SH, every frame
    Errors model_training;    // final (pruned) model vs baked SH, every frame
    // The model as stored (ridge, constant vertices, per-vertex joint
    // pruning), fitted without the held-out frames, against them (λ chosen
    // on them too). This is the held-out error of the saved model's recipe.
    Errors model_holdout;
    Errors model_holdout_unpruned;  // the same before pruning (the plain ridge solution)
    double ridge_relative = 0.0;                          // ρ: λ = ρ·s_max²
    // (ρ, held-out SH RMS error of the ridge solution's lobes, linearized:
    // ridge_curve.hpp; the ZH fit's own residual not included).
    std::vector<std::pair<double, double>> ridge_curve;
    std::size_t constant_vertices = 0;
    std::size_t stored_joint_blocks = 0;   // Σ over vertices of joints kept
    std::size_t stored_directions = 0;     // Σ over blocks of the joint directions kept
    std::size_t model_bytes = 0;           // stored payload
    std::size_t dense_bytes = 0;           // float32 d·(features·j + 1)·v, as the paper's O(djv)
    double seconds_zh_fit = 0.0, seconds_linear = 0.0;
};

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

PoseModel fit_pose_model(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                         const FitSettings& settings, const Progress& progress = {}, FitReport* report = nullptr);

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

// Errors of the model against baked frames (e.g. poses it never saw). The
// set's bones must include every model joint.
Errors evaluate_pose_model(const PoseModel& model, const TrainingSet& set, int threads = 0);

}  // namespace penumbra::visibility
