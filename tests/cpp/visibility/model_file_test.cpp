// The baker's files (visibility/model_file.hpp): exact round trips, every
// truncation and corruption an IoError, atomic writes.
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "test_files.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_model.hpp"
#include "visibility_test_util.hpp"

namespace penumbra::visibility {
namespace {

using testing::synthetic_set;

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
    EXPECT_EQ(back.weight_scales, model.weight_scales);
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
