// ZH lobe fitting, the linear pose model and the model files.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/zonal.hpp"
#include "test_files.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_model.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {
namespace {

std::vector<double> lobe_sh(const std::vector<std::pair<Eigen::Vector3d, std::array<double, 4>>>& lobes) {
    std::vector<double> sh(16, 0.0);
    for (const auto& [axis, band] : lobes) sh::zh_to_sh_accumulate(4, axis, band.data(), sh.data());
    return sh;
}

TEST(ZhFit, lambert_map_round_trips_and_has_no_longitude_seam) {
    for (double z : {0.999999, 0.5, 0.0, -0.5, -0.99})
        for (double phi = -3.14159; phi < 3.15; phi += 0.3) {
            const double r = std::sqrt(1 - z * z);
            const Eigen::Vector3d a(r * std::cos(phi), r * std::sin(phi), z);
            const Eigen::Vector2d q = axis_to_lambert(a);
            EXPECT_LT((lambert_to_axis(q.x(), q.y()) - a).norm(), 1e-9);
        }
    // Crossing φ = ±π moves (X, Y) by as little as the axis moves.
    const double z = 0.3, r = std::sqrt(1 - z * z);
    const Eigen::Vector2d before = axis_to_lambert({r * std::cos(3.14), r * std::sin(3.14), z});
    const Eigen::Vector2d after = axis_to_lambert({r * std::cos(-3.14), r * std::sin(-3.14), z});
    EXPECT_LT((before - after).norm(), 0.01);
    // Beyond the disc: pulled back onto −z.
    EXPECT_LT((lambert_to_axis(5.0, 0.0) + Eigen::Vector3d::UnitZ()).norm(), 1e-9);
    EXPECT_TRUE(lambert_to_axis(NAN, 0.0).allFinite());
}

TEST(ZhFit, one_lobe_is_recovered_exactly) {
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.4, 0.8).normalized();
    const auto sh = lobe_sh({{axis, {1.2, 0.9, 0.3, -0.1}}});
    ZhFitSettings s;
    s.lobes = 1;
    s.iterations = 30;
    std::vector<double> params(6);
    const double residual = fit_zh_lobes(s, sh.data(), nullptr, params.data());
    EXPECT_LT(residual, 1e-10);  // the 1e-6 ridge on the bands biases them by ~1e-6
    EXPECT_LT((lambert_to_axis(params[0], params[1]) - axis).norm(), 1e-4);
    EXPECT_NEAR(params[2], 1.2, 1e-5);
    EXPECT_NEAR(params[5], -0.1, 1e-5);
}

TEST(ZhFit, two_separated_lobes_fit_much_better_than_one) {
    const auto sh = lobe_sh({{Eigen::Vector3d(0, 0, 1), {1.5, 1.2, 0.6, 0.1}},
                             {Eigen::Vector3d(0.9, 0.0, 0.3).normalized(), {-0.5, -0.6, -0.4, -0.2}}});
    ZhFitSettings s;
    s.iterations = 40;
    std::vector<double> p1(6), p2(12), p3(18), back(16);
    s.lobes = 1;
    const double r1 = fit_zh_lobes(s, sh.data(), nullptr, p1.data());
    s.lobes = 2;
    const double r2 = fit_zh_lobes(s, sh.data(), nullptr, p2.data());
    s.lobes = 3;
    const double r3 = fit_zh_lobes(s, sh.data(), nullptr, p3.data());
    EXPECT_LT(r2, 1e-2 * r1);
    EXPECT_LE(r3, r2 * 1.01 + 1e-12);
    // The residual returned is the true one: expand the parameters with Eq. 1.
    lobes_to_sh(4, 2, p2.data(), back.data());
    double check = 0;
    for (int i = 0; i < 16; ++i) check += (back[i] - sh[i]) * (back[i] - sh[i]);
    EXPECT_NEAR(check, r2, 1e-12 + 1e-9 * r2);
}

TEST(ZhFit, zero_visibility_and_reference_fits_stay_finite_and_deterministic) {
    ZhFitSettings s;
    std::vector<double> zero(16, 0.0), p(12), q(12);
    EXPECT_EQ(fit_zh_lobes(s, zero.data(), nullptr, p.data()), 0.0);
    for (double x : p) EXPECT_TRUE(std::isfinite(x));
    const auto sh = lobe_sh({{Eigen::Vector3d(0.2, 0.1, 1).normalized(), {1.0, 0.8, 0.2, 0.0}}});
    fit_zh_lobes(s, sh.data(), nullptr, p.data());
    fit_zh_lobes(s, sh.data(), nullptr, q.data());
    EXPECT_EQ(p, q);
    // Fitting from a reference keeps each lobe next to its reference axis.
    std::vector<double> r(12);
    fit_zh_lobes(s, sh.data(), p.data(), r.data());
    EXPECT_LT(std::hypot(r[0] - p[0], r[1] - p[1]), 0.05);
}

// A synthetic training set: vertex v's visibility is one lobe about +z whose
// band coefficients depend linearly on cos θ_v and sin θ_v of one bone's
// rotation about z (so exactly linear in the R − I features).
TrainingSet synthetic_set(const std::vector<double>& angles, int vertices, int extra_still_bones = 0) {
    TrainingSet set;
    set.vertex_count = vertices;
    set.topology_hash = 42;
    set.bone_names = {"arm"};
    for (int b = 0; b < extra_still_bones; ++b) set.bone_names.push_back("still" + std::to_string(b));
    set.settings.rays = 64;
    for (std::size_t f = 0; f < angles.size(); ++f) {
        TrainingFrame frame;
        frame.frame = double(f);
        const Eigen::Matrix3d r = Eigen::AngleAxisd(angles[f], Eigen::Vector3d::UnitZ()).toRotationMatrix();
        for (std::size_t b = 0; b < set.bone_names.size(); ++b)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) frame.bone_rotations.push_back(b == 0 ? float(r(i, j)) : (i == j ? 1.f : 0.f));
        for (int v = 0; v < vertices; ++v) {
            const double w = double(v) / vertices;
            const std::array<double, 4> band{1.5 + 0.4 * w * std::cos(angles[f]), 1.0 + 0.3 * std::sin(angles[f]) * w,
                                             0.3, 0.05 * w};
            const auto sh = lobe_sh({{Eigen::Vector3d::UnitZ(), band}});
            for (double x : sh) frame.visibility.push_back(float(x));
        }
        set.frames.push_back(std::move(frame));
    }
    return set;
}

TEST(PoseModel, linear_data_is_reproduced_on_unseen_poses) {
    std::vector<double> angles;
    for (int f = 0; f < 16; ++f) angles.push_back(0.1 * f);
    const TrainingSet set = synthetic_set(angles, 50, 2);
    FitSettings s;
    s.lobes = 1;
    FitReport report;
    const PoseModel model = fit_pose_model(set, {{true, false}, {true, false}, {true, false}}, s, {}, &report);
    ASSERT_EQ(model.joints, std::vector<std::string>{"arm"});
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

TEST(PoseModel, held_out_error_is_that_of_the_pruned_model_as_stored) {
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

    // No pruning at all: the stored model is the ridge solution, same error.
    s.constant_tolerance = 0.0;
    s.prune_tolerance = 0.0;
    fit_pose_model(set, influence, s, {}, &report);
    EXPECT_NEAR(report.model_holdout.sh_rms, report.model_holdout_unpruned.sh_rms,
                1e-4 * report.model_holdout_unpruned.sh_rms + 1e-7);
}

TEST(PoseModel, stays_finite_with_more_columns_than_frames_repeated_frames_and_still_joints) {
    // 3 distinct poses, repeated: far fewer frames than the 9 feature columns,
    // plus two joints that never move.
    const TrainingSet set = synthetic_set({0.0, 0.5, 1.0, 0.0, 0.5, 1.0, 1.0, 1.0}, 20, 2);
    for (auto features : {PoseFeatures::RotationMatrix, PoseFeatures::RotationVector}) {
        FitSettings s;
        s.lobes = 2;
        s.features = features;
        FitReport report;
        const PoseModel model = fit_pose_model(set, {{true, false}, {true, false}, {true, false}}, s, {}, &report);
        for (float x : model.weights) EXPECT_TRUE(std::isfinite(x));
        for (float x : model.bias) EXPECT_TRUE(std::isfinite(x));
        EXPECT_TRUE(std::isfinite(report.model_holdout.sh_rms));
        EXPECT_LT(report.model_training.sh_rms, 0.05);
    }
}

TEST(PoseModel, rigid_and_non_deforming_bones_are_dropped_with_their_reason) {
    const TrainingSet set = synthetic_set({0.0, 0.3, 0.6, 0.9}, 5, 1);
    const auto choices = choose_active_joints(set, {{true, true}, {false, false}}, 1.0);
    EXPECT_FALSE(choices[0].active);
    EXPECT_NE(choices[0].reason.find("rigidly"), std::string::npos);
    EXPECT_NEAR(choices[0].max_angle_degrees, 0.9 * 180 / std::numbers::pi, 1e-3);
    EXPECT_NE(choices[1].reason.find("deforms no vertex"), std::string::npos);
    EXPECT_THROW(choose_active_joints(set, {{true, false}}, 1.0), ArgumentError);
}

TEST(PoseModel, bad_training_sets_are_argument_errors) {
    TrainingSet set = synthetic_set({0.0, 0.3}, 5);
    set.frames[1].visibility.pop_back();
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
    set = synthetic_set({0.0, 0.3}, 5);
    set.frames[0].bone_rotations[0] = NAN;
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
    set = synthetic_set({}, 5);
    EXPECT_THROW(fit_pose_model(set, {{true, false}}, {}), ArgumentError);
}

TEST(PoseModel, merging_pieces_sorts_frames_and_rejects_foreign_pieces) {
    TrainingSet a = synthetic_set({0.0, 0.1}, 4), b = synthetic_set({0.2, 0.3}, 4);
    for (auto& f : a.frames) f.frame += 10;
    const TrainingSet merged = merge_training_sets({a, b});
    ASSERT_EQ(merged.frames.size(), 4u);
    EXPECT_EQ(merged.frames[0].frame, 0.0);
    EXPECT_EQ(merged.frames[3].frame, 11.0);
    TrainingSet other = b;
    other.topology_hash = 7;
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
    other = b;
    other.bone_names = {"leg"};
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
    other = b;
    other.settings.rays = 128;
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
}

PoseModel small_model() {
    std::vector<double> angles;
    for (int f = 0; f < 12; ++f) angles.push_back(0.1 * f);
    return fit_pose_model(synthetic_set(angles, 30, 1), {{true, false}, {true, false}}, FitSettings{});
}

TEST(ModelFile, round_trip_is_exact) {
    penumbra::testing::ScratchDir dir;
    const PoseModel model = small_model();
    write_pose_model(dir.file("m.pzh"), model);
    const PoseModel back = read_pose_model(dir.file("m.pzh"));
    EXPECT_EQ(back.joints, model.joints);
    EXPECT_EQ(back.armature_bones, model.armature_bones);
    EXPECT_EQ(back.weights, model.weights);
    EXPECT_EQ(back.bias, model.bias);
    EXPECT_EQ(back.joint_offsets, model.joint_offsets);
    EXPECT_EQ(back.topology_hash, model.topology_hash);
    EXPECT_EQ(back.summary.size(), model.summary.size());
    const TrainingSet set = synthetic_set({0.0, 0.4}, 6);
    write_training_set(dir.file("s.pvis"), set);
    const TrainingSet set_back = read_training_set(dir.file("s.pvis"));
    EXPECT_EQ(set_back.frames[1].visibility, set.frames[1].visibility);
    EXPECT_EQ(set_back.bone_names, set.bone_names);
}

TEST(ModelFile, every_truncation_and_corruption_is_an_io_error) {
    penumbra::testing::ScratchDir dir;
    write_pose_model(dir.file("m.pzh"), small_model());
    const std::string bytes = penumbra::testing::read_bytes(dir.file("m.pzh"));
    for (std::size_t length : {std::size_t(0), std::size_t(5), std::size_t(8), std::size_t(31), std::size_t(32),
                               bytes.size() / 2, bytes.size() - 1}) {
        penumbra::testing::write_bytes(dir.file("t.pzh"), bytes.substr(0, length));
        EXPECT_THROW(read_pose_model(dir.file("t.pzh")), IoError) << "length " << length;
    }
    std::mt19937 rng(1);
    for (int trial = 0; trial < 50; ++trial) {
        std::string broken = bytes;
        broken[rng() % broken.size()] ^= char(1 + rng() % 255);
        penumbra::testing::write_bytes(dir.file("c.pzh"), broken);
        EXPECT_THROW(read_pose_model(dir.file("c.pzh")), IoError) << "trial " << trial;
    }
    try {
        std::string broken = bytes;
        broken[bytes.size() - 3] ^= 0x10;
        penumbra::testing::write_bytes(dir.file("c.pzh"), broken);
        read_pose_model(dir.file("c.pzh"));
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
    EXPECT_THROW(read_pose_model(dir.file("missing.pzh")), IoError);
    write_training_set(dir.file("s.pvis"), synthetic_set({0.0}, 3));
    EXPECT_THROW(read_pose_model(dir.file("s.pvis")), IoError);
    EXPECT_THROW(read_training_set(dir.file("m.pzh")), IoError);
}

TEST(ModelFile, a_failed_write_leaves_the_earlier_file_untouched) {
    penumbra::testing::ScratchDir dir;
    const PoseModel model = small_model();
    write_pose_model(dir.file("m.pzh"), model);
    const std::string before = penumbra::testing::read_bytes(dir.file("m.pzh"));
    PoseModel broken = model;
    broken.bias.pop_back();  // inconsistent: refused before anything is written
    EXPECT_THROW(write_pose_model(dir.file("m.pzh"), broken), ArgumentError);
    EXPECT_EQ(penumbra::testing::read_bytes(dir.file("m.pzh")), before);
    EXPECT_THROW(write_pose_model(dir.file("no/such/folder/m.pzh"), model), IoError);
}

}  // namespace
}  // namespace penumbra::visibility
