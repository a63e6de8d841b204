// Fitting the linear pose model (pose_model.hpp) to baked frames
// (visibility_bake.hpp): which joints make the pose vector, the ridge
// solution, its ridge chosen on held-out frames, and per-vertex pruning.
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
// frames). Both are decided on the frames a model is fitted on, with its
// own weights: the held-out error measures that recipe fitted without the
// held-out frames, and the stored model applies it again to its refit on
// every frame (reusing the first decisions with the refitted weights let
// the unseen worst case grow 4× over the unpruned model's). The joint
// feature directions are decided on the frames that are not held out.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "common/progress.hpp"
#include "common/setting.hpp"
#include "visibility/pose_model.hpp"

namespace penumbra::visibility {

// What the caller (Blender) knows about each bone of the armature, in the
// order of TrainingSet::bone_names.
struct BoneInfluence {
    bool deforms_mesh = true;          // the bone or a child carries weight on some vertex of this mesh
    bool rigid_for_whole_mesh = false; // every weighted vertex is fully carried by this bone's subtree
};

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

struct JointChoice {
    std::string name;
    bool active = false;
    double max_angle_degrees = 0.0;  // largest rotation away from the first training frame
    int feature_directions = 0;      // active joints: the feature directions kept (FitSettings::feature_tolerance)
    std::string reason;              // why kept or dropped
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

// The model of the set's frames (the whole fit above); `report`, when
// given, receives the joints chosen, the errors and the sizes.
PoseModel fit_pose_model(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                         const FitSettings& settings, const Progress& progress = {}, FitReport* report = nullptr);

// Errors of the model against baked frames (e.g. poses it never saw). The
// set's bones must include every model joint.
Errors evaluate_pose_model(const PoseModel& model, const TrainingSet& set, int threads = 0);

// The joints of the pose vector, one choice per bone of the set, with the
// reason it is kept or dropped (see above).
std::vector<JointChoice> choose_active_joints(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                                              double tolerance_degrees);

}  // namespace penumbra::visibility
