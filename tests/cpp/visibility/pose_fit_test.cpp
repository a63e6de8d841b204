// The pose model's fit (visibility/pose_fit.hpp) on synthetic training
// sets whose visibility is exactly linear in the pose features.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "visibility/pose_fit.hpp"
#include "visibility_test_util.hpp"

namespace penumbra::visibility {
namespace {

using testing::synthetic_set;

TEST(PoseFit, linear_data_is_reproduced_on_unseen_poses) {
    std::vector<double> angles;
    for (int f = 0; f < 16; ++f) angles.push_back(0.1 * f);
    const TrainingSet set = synthetic_set(angles, 50, 2);
    FitSettings s;
    s.lobes = 1;
    // Pruning drops a joint direction whose contribution stays under the
    // tolerance (RMS of lobe parameters): well under the 2e-3 asked here.
    s.prune_tolerance = 1e-4;
    FitReport report;
    const PoseModel model = fit_pose_model(set, {{true, false}, {true, false}, {true, false}}, s, {}, &report);
    ASSERT_EQ(model.joints, std::vector<std::string>{"arm"});
    // A rotation about one axis: its R − I spans two directions.
    EXPECT_EQ(report.joints[0].feature_directions, 2);
    EXPECT_EQ(model.joint_feature_count(0), 2);
    EXPECT_FALSE(report.joints[1].active);
    EXPECT_NE(report.joints[1].reason.find("rotates at most"), std::string::npos);
    EXPECT_EQ(report.holdout_frames, 4u);
    EXPECT_LT(report.model_holdout.sh_rms, 2e-3);
    EXPECT_LT(report.model_training.sh_rms, 2e-3);
    // Vertex 0 does not change with pose: stored as a constant.
    EXPECT_EQ(model.joint_offsets[1] - model.joint_offsets[0], 0u);
    EXPECT_GE(report.constant_vertices, 1u);
    EXPECT_LT(report.model_bytes, report.dense_bytes);
    const TrainingSet unseen = synthetic_set({0.05, 0.77, 1.33}, 50, 2);
    EXPECT_LT(evaluate_pose_model(model, unseen).sh_rms, 3e-3);
}

// The synthetic joint turns about one axis: two feature directions. Its
// lobes move with the pose in proportion to the vertex index, so vertices
// near 0 barely depend on it: pruning by measured contribution keeps the
// leading direction alone (or none) there, both further on, and every
// direction at tolerance 0.
TEST(PoseFit, pruning_keeps_each_vertex_the_leading_joint_directions_that_matter) {
    std::vector<double> angles;
    for (int f = 0; f < 16; ++f) angles.push_back(0.1 * f);
    const TrainingSet set = synthetic_set(angles, 50, 1);
    const std::vector<BoneInfluence> influence{{true, false}, {true, false}};
    FitSettings s;
    s.lobes = 1;
    s.constant_tolerance = 0.0;
    FitReport report;
    const PoseModel pruned = fit_pose_model(set, influence, s, {}, &report);
    ASSERT_EQ(pruned.joint_feature_count(0), 2);
    std::size_t one = 0, two = 0;
    for (std::uint8_t c : pruned.block_directions) (c == 1 ? one : two) += 1;
    EXPECT_GT(one, 0u);
    EXPECT_GT(two, 0u);
    EXPECT_EQ(report.stored_directions, one + 2 * two);
    EXPECT_LT(pruned.weights.size(), pruned.joint_index.size() * 2 * std::size_t(pruned.params_per_vertex()));
    // The blocks that keep both directions are the vertices that move most.
    std::size_t first_two = pruned.vertex_count;
    for (std::size_t v = 0; v < pruned.vertex_count && first_two == pruned.vertex_count; ++v)
        for (std::uint32_t e = pruned.joint_offsets[v]; e < pruned.joint_offsets[v + 1]; ++e)
            if (pruned.block_directions[e] == 2) first_two = v;
    for (std::size_t v = first_two; v < pruned.vertex_count; ++v) {
        ASSERT_EQ(pruned.joint_offsets[v + 1] - pruned.joint_offsets[v], 1u) << v;
        EXPECT_EQ(pruned.block_directions[pruned.joint_offsets[v]], 2) << v;
    }

    s.prune_tolerance = 0.0;
    FitReport full_report;
    const PoseModel full = fit_pose_model(set, influence, s, {}, &full_report);
    for (std::uint8_t c : full.block_directions) EXPECT_EQ(c, 2);
    EXPECT_GT(full.weights.size(), pruned.weights.size());
    // What pruning drops stays small next to what the pose explains.
    EXPECT_LT(report.model_holdout.sh_rms, full_report.model_holdout.sh_rms + 0.01);
}

TEST(PoseFit, held_out_error_is_that_of_the_pruned_model_as_stored) {
    std::vector<double> angles;
    for (int f = 0; f < 16; ++f) angles.push_back(0.1 * f);
    const TrainingSet set = synthetic_set(angles, 50, 1);
    const std::vector<BoneInfluence> influence{{true, false}, {true, false}};
    // Held out: every 4th frame (3, 7, 11, 15); the rest trains.
    TrainingSet train = set, holdout = set;
    train.frames.clear();
    holdout.frames.clear();
    for (std::size_t f = 0; f < set.frames.size(); ++f) (f % 4 == 3 ? holdout : train).frames.push_back(set.frames[f]);

    // Tolerances so large that every vertex is stored as a constant: the
    // stored model then ignores the pose (whatever λ), and its held-out error
    // is that of the per-vertex mean of the training frames, which a model
    // fitted on the training frames alone and evaluated on the held-out ones
    // measures independently. The unpruned ridge model follows the pose and
    // is far better: the report must not give its error for the stored model.
    FitSettings s;
    s.lobes = 1;
    s.constant_tolerance = 1e9;
    FitReport report;
    fit_pose_model(set, influence, s, {}, &report);
    FitSettings alone = s;
    alone.holdout_stride = 0;
    const PoseModel mean_model = fit_pose_model(train, influence, alone);
    const Errors expected = evaluate_pose_model(mean_model, holdout);
    EXPECT_NEAR(report.model_holdout.sh_rms, expected.sh_rms, 1e-5);
    EXPECT_NEAR(report.model_holdout.ao_mean_abs, expected.ao_mean_abs, 1e-5);
    EXPECT_EQ(report.model_holdout.samples, holdout.frames.size() * 50);
    EXPECT_GT(report.model_holdout.sh_rms, 5 * report.model_holdout_unpruned.sh_rms);

    // No pruning at all: the stored model is the ridge solution with its
    // weights rounded to binary16 blocks (weight_blocks.hpp), the same error
    // up to that rounding: each weight within 2^-12 of its block's largest
    // (here the error rises from 6e-7 to 6e-6, the model being near exact on
    // this synthetic set; reporting the unpruned error would hide it).
    s.constant_tolerance = 0.0;
    s.prune_tolerance = 0.0;
    fit_pose_model(set, influence, s, {}, &report);
    EXPECT_NEAR(report.model_holdout.sh_rms, report.model_holdout_unpruned.sh_rms,
                1e-4 * report.model_holdout_unpruned.sh_rms + 2e-5);
}

// The tail of pruning. The joint barely moves on the training frames of the
// held-out split and swings only on the held-out ones (every 4th frame):
// fitted without them, every vertex's motion is under the tolerances, so
// that fit's pruning drops the joint everywhere. The model refitted on every
// frame leans on it, and must then keep it: its worst unseen error stays
// near the unpruned model's (reusing the first fit's choices dropped the
// joint: 0.028 against 0.014 unpruned).
TEST(PoseFit, pruning_keeps_what_the_stored_weights_lean_on_so_the_worst_unseen_error_stays_near_unpruned) {
    std::vector<double> angles;
    for (int f = 0; f < 16; ++f) angles.push_back(f % 4 == 3 ? 0.3 * (f + 1) / 4 : 0.001 * f);
    const TrainingSet set = synthetic_set(angles, 50, 1);
    const std::vector<BoneInfluence> influence{{true, false}, {true, false}};
    FitSettings s;
    s.lobes = 1;
    const PoseModel pruned = fit_pose_model(set, influence, s);
    s.prune_tolerance = s.constant_tolerance = 0.0;
    const PoseModel unpruned = fit_pose_model(set, influence, s);
    const TrainingSet unseen = synthetic_set({0.45, 0.75, 1.05}, 50, 1);
    const double worst_unpruned = evaluate_pose_model(unpruned, unseen).ao_max_abs;
    EXPECT_LT(evaluate_pose_model(pruned, unseen).ao_max_abs, 1.2 * worst_unpruned + 1e-4);
    EXPECT_LT(worst_unpruned, 0.02);
}

TEST(PoseFit, stays_finite_with_more_columns_than_frames_repeated_frames_and_still_joints) {
    // 3 distinct poses, repeated: far fewer frames than the 9 feature columns,
    // plus two joints that never move.
    const TrainingSet set = synthetic_set({0.0, 0.5, 1.0, 0.0, 0.5, 1.0, 1.0, 1.0}, 20, 2);
    for (auto features : {PoseFeatures::RotationMatrix, PoseFeatures::RotationVector}) {
        FitSettings s;
        s.lobes = 2;
        s.features = features;
        FitReport report;
        const PoseModel model = fit_pose_model(set, {{true, false}, {true, false}, {true, false}}, s, {}, &report);
        for (float x : weight_values(model)) EXPECT_TRUE(std::isfinite(x));
        for (float x : model.bias) EXPECT_TRUE(std::isfinite(x));
        EXPECT_TRUE(std::isfinite(report.model_holdout.sh_rms));
        EXPECT_LT(report.model_training.sh_rms, 0.05);
    }
}

TEST(PoseFit, rigid_and_non_deforming_bones_are_dropped_with_their_reason) {
    const TrainingSet set = synthetic_set({0.0, 0.3, 0.6, 0.9}, 5, 1);
    const auto choices = choose_active_joints(set, {{true, true}, {false, false}}, 1.0);
    EXPECT_FALSE(choices[0].active);
    EXPECT_NE(choices[0].reason.find("rigidly"), std::string::npos);
    EXPECT_NEAR(choices[0].max_angle_degrees, 0.9 * 180 / std::numbers::pi, 1e-3);
    EXPECT_NE(choices[1].reason.find("deforms no vertex"), std::string::npos);
    EXPECT_THROW(choose_active_joints(set, {{true, false}}, 1.0), ArgumentError);
}

// Vertex v's lobe tilts from +z by an angle that grows with the bone's
// rotation (v spreads the rate): per-frame fits must move their axes.
TrainingSet tilting_set(const std::vector<double>& angles, int vertices) {
    TrainingSet set = synthetic_set(angles, vertices);
    for (std::size_t f = 0; f < angles.size(); ++f) {
        set.frames[f].visibility.clear();
        for (int v = 0; v < vertices; ++v) {
            const double tilt = 0.6 * angles[f] * (0.5 + double(v) / vertices);
            const Eigen::Vector3d axis(std::sin(tilt), 0.0, std::cos(tilt));
            for (double x : testing::lobe_sh({{axis, {1.5, 1.0, 0.3, 0.05}}})) set.frames[f].visibility.push_back(float(x));
        }
    }
    return set;
}

TEST(PoseFit, the_default_iterations_per_frame_fit_moving_lobes_about_as_well_as_eight) {
    std::vector<double> angles;
    for (int f = 0; f < 12; ++f) angles.push_back(0.1 * f);
    const TrainingSet set = tilting_set(angles, 20);
    const std::vector<BoneInfluence> influence{{true, false}};
    auto zh_error = [&](int iterations) {
        FitSettings s;
        s.lobes = 1;
        s.frame_zh_iterations = iterations;
        FitReport report;
        fit_pose_model(set, influence, s, {}, &report);
        return report.zh_fit.sh_rms;
    };
    const int chosen = FitSettings{}.frame_zh_iterations;  // 1 (measured 0.049 against 0.048 for 8)
    ASSERT_GE(chosen, 1);
    const double eight = zh_error(8), fitted = zh_error(chosen), none = zh_error(0);
    const double bound = 1.1 * eight + 1e-4;
    EXPECT_LT(fitted, bound);
    // Axes left at the reference fit's (no iteration) fail the same bound
    // (measured 0.066 against 0.048 for 8): it is one the frames' own fits
    // must earn.
    EXPECT_GT(none, bound);
}

TEST(PoseFit, a_vertex_whose_visibility_repeats_gets_the_fit_of_its_first_occurrence) {
    // Poses 0, 0.5, 1.0 repeated: the repeated frames' visibility is equal
    // bit for bit to the first ones' and their fits are reused. Perturbing
    // the repeats by 1e-6 (no longer equal, so fitted anew) must change the
    // model by no more than that: a fit copied from the wrong frame or
    // vertex would change it by the lobes' own variation.
    const std::vector<double> angles{0.0, 0.5, 1.0, 0.2, 0.0, 0.5, 1.0, 0.7};
    const TrainingSet repeated = tilting_set(angles, 30);
    TrainingSet perturbed = repeated;
    for (std::size_t f : {4u, 5u, 6u})
        for (float& x : perturbed.frames[f].visibility) x += 1e-6f;
    const std::vector<BoneInfluence> influence{{true, false}};
    FitSettings s;
    s.lobes = 1;
    s.holdout_stride = 0;
    s.constant_tolerance = s.prune_tolerance = 0.0;
    FitReport a_report, b_report;
    const PoseModel a = fit_pose_model(repeated, influence, s, {}, &a_report);
    const PoseModel b = fit_pose_model(perturbed, influence, s, {}, &b_report);
    const std::vector<float> a_weights = weight_values(a), b_weights = weight_values(b);
    ASSERT_EQ(a_weights.size(), b_weights.size());
    ASSERT_GT(a_weights.size(), 0u);
    for (std::size_t i = 0; i < a_weights.size(); ++i) EXPECT_NEAR(a_weights[i], b_weights[i], 1e-3) << i;
    for (std::size_t i = 0; i < a.bias.size(); ++i) EXPECT_NEAR(a.bias[i], b.bias[i], 1e-3) << i;
    EXPECT_NEAR(a_report.zh_fit.sh_rms, b_report.zh_fit.sh_rms, 1e-5);
}

TEST(PoseFit, bad_training_sets_are_argument_errors) {
    TrainingSet set = synthetic_set({0.0, 0.3}, 5);
    set.frames[1].visibility.pop_back();
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
    set = synthetic_set({0.0, 0.3}, 5);
    set.frames[0].bone_rotations[0] = NAN;
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
    set = synthetic_set({}, 5);
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
}

}  // namespace
}  // namespace penumbra::visibility
