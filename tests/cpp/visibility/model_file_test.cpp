// The baker's files (visibility/model_file.hpp): exact round trips, every
// truncation and corruption an IoError, atomic writes.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "common/binary_io.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "test_files.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_fit.hpp"
#include "visibility_test_util.hpp"

namespace penumbra::visibility {
namespace {

using testing::synthetic_set;

PoseModel small_model() {
    std::vector<double> angles;
    for (int f = 0; f < 12; ++f) angles.push_back(0.1 * f);
    return fit_pose_model(synthetic_set(angles, 30, 1), {{true, false}, {true, false}}, FitSettings{});
}

// A model file from before binary16 blocks and joint feature directions
// (format version 1: float32 weights of every raw joint feature), written
// byte by byte as that version did.
TEST(ModelFile, a_version_1_model_loads_with_its_weights_rounded_to_blocks) {
    penumbra::testing::ScratchDir dir;
    const std::vector<std::uint32_t> offsets{0, 1, 1, 3};
    const std::vector<std::uint16_t> joints{0, 0, 1};
    std::vector<float> bias, weights;
    for (int i = 0; i < 3 * 6; ++i) bias.push_back(0.1f * float(i % 7));
    for (int i = 0; i < 3 * 9 * 6; ++i) weights.push_back(0.01f * float(i % 5) - 0.02f + 1e-5f * float(i));
    BinaryWriter w;
    for (std::uint32_t x : {4u /* order */, 1u /* lobes */, 16u, 0u, 0u /* R − I */}) w.put(x);
    w.put(std::uint64_t(3));
    w.put(std::uint64_t(0x1234));
    w.put_strings({"root", "arm", "hand"});
    w.put_strings({"arm", "hand"});
    w.put(std::uint32_t(0));
    w.put_array(offsets);
    w.put(std::uint64_t(joints.size()));
    w.put_array(joints);
    w.put_array(bias);
    w.put_array(weights);
    const std::string payload = w.bytes();
    std::string header(32, '\0');
    const std::uint32_t version = 1;
    const std::uint64_t size = payload.size(), checksum = fnv1a64(payload.data(), payload.size());
    std::memcpy(header.data(), "PNMBRZHM", 8);
    std::memcpy(header.data() + 8, &version, 4);
    std::memcpy(header.data() + 16, &size, 8);
    std::memcpy(header.data() + 24, &checksum, 8);
    std::ofstream(dir.file("v1.pzh"), std::ios::binary) << header << payload;

    const PoseModel m = read_pose_model(dir.file("v1.pzh"));
    EXPECT_EQ(m.joint_feature_count(0), 9);
    EXPECT_EQ(m.joint_feature_count(1), 9);
    EXPECT_EQ(m.block_directions, (std::vector<std::uint8_t>{9, 9, 9}));
    EXPECT_EQ(m.bias, bias);
    const std::vector<float> back = weight_values(m);
    ASSERT_EQ(back.size(), weights.size());
    for (std::size_t i = 0; i < weights.size(); ++i) EXPECT_NEAR(back[i], weights[i], std::ldexp(0.05f, -11)) << i;
    // The identity basis: the pose's features are the raw R − I entries.
    std::vector<float> rotations(18, 0.0f);
    for (int j = 0; j < 2; ++j) rotations[9 * j] = rotations[9 * j + 4] = rotations[9 * j + 8] = 1.0f;
    rotations[1] = 0.25f;
    const std::vector<float> features = pose_features(m, rotations.data());
    ASSERT_EQ(features.size(), 18u);
    EXPECT_EQ(features[1], 0.25f);
    EXPECT_EQ(features[0], 0.0f);
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
    EXPECT_EQ(back.block_directions, model.block_directions);
    EXPECT_EQ(back.feature_offsets, model.feature_offsets);
    EXPECT_EQ(back.feature_basis, model.feature_basis);
    EXPECT_EQ(back.weight_offsets, model.weight_offsets);
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
