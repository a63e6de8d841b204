// The pose model's binary16 weight blocks (visibility/weight_blocks.hpp) and
// the run time's decoding of them on every SIMD target.
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "common/simd_target.hpp"
#include "visibility/pose_model.hpp"
#include "visibility/weight_blocks.hpp"

namespace penumbra::visibility {
namespace {

std::vector<float> random_block(std::size_t n, float magnitude, std::mt19937_64& rng) {
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> block(n);
    for (float& x : block) x = magnitude * uniform(rng);
    return block;
}

float largest_magnitude(const std::vector<float>& block) {
    float largest = 0.0f;
    for (float x : block) largest = std::max(largest, std::abs(x));
    return largest;
}

// Every weight within 2^-12 of its block's scale, which is under twice the
// block's largest magnitude, from 1e-29 to 1e38, with and without a weight
// at the top of its power of two.
TEST(WeightBlocks, round_trip_within_a_2048th_of_the_blocks_largest_at_any_magnitude) {
    std::mt19937_64 rng(5);
    for (const float magnitude : {1e-29f, 3e-12f, 6e-5f, 0.37f, 1.0f, 65504.0f, 7e9f, 1e30f, 1e38f}) {
        for (int trial = 0; trial < 20; ++trial) {
            std::vector<float> block = random_block(108, magnitude, rng);
            if (trial == 0) block[7] = magnitude;  // exactly at the top
            std::vector<std::uint16_t> halves(block.size());
            const float scale = pack_weight_block(block.data(), block.size(), halves.data());
            std::vector<float> back(block.size());
            unpack_weight_block(halves.data(), halves.size(), scale, back.data());
            const float largest = largest_magnitude(block);
            EXPECT_GE(scale, largest);
            EXPECT_LT(scale, 2.0f * largest);
            for (std::size_t i = 0; i < block.size(); ++i) {
                ASSERT_TRUE(finite_half(halves[i]));
                ASSERT_TRUE(std::isfinite(back[i]));
                EXPECT_LE(std::abs(back[i] - block[i]), std::ldexp(scale, -12)) << magnitude << " " << i;
            }
            // Relative precision of the block's largest weight: binary16's own.
            EXPECT_LE(std::abs(largest_magnitude(back) - largest), std::ldexp(largest, -11)) << magnitude;
            // Rounding is what packing then unpacking gives, and rounding twice changes nothing.
            std::vector<float> rounded = block;
            round_weight_block(rounded.data(), rounded.size());
            EXPECT_EQ(rounded, back);
            std::vector<float> twice = rounded;
            round_weight_block(twice.data(), twice.size());
            EXPECT_EQ(twice, rounded);
        }
    }
}

TEST(WeightBlocks, zero_and_negligible_blocks_pack_as_zeros) {
    for (const float magnitude : {0.0f, 1e-31f, 1e-40f /* a float subnormal */}) {
        std::vector<float> block(12, magnitude);
        block[3] = -magnitude;
        std::vector<std::uint16_t> halves(block.size(), 0xffff);
        EXPECT_EQ(pack_weight_block(block.data(), block.size(), halves.data()), 0.0f);
        for (std::uint16_t h : halves) EXPECT_EQ(h & 0x7fff, 0) << magnitude;
        round_weight_block(block.data(), block.size());
        for (float x : block) EXPECT_EQ(x, 0.0f);
    }
}

// Above 2^127 the scale stops at 2^127 (a float's largest power of two):
// the block still packs finite, within binary16's precision.
TEST(WeightBlocks, the_largest_floats_pack_finite) {
    std::vector<float> block{3.4e38f, -3.4e38f, 1e38f, 2.0f, 0.0f};
    std::vector<std::uint16_t> halves(block.size());
    const float scale = pack_weight_block(block.data(), block.size(), halves.data());
    EXPECT_EQ(scale, std::ldexp(1.0f, 127));
    std::vector<float> back(block.size());
    unpack_weight_block(halves.data(), halves.size(), scale, back.data());
    for (std::size_t i = 0; i < block.size(); ++i) {
        EXPECT_TRUE(finite_half(halves[i]));
        EXPECT_TRUE(std::isfinite(back[i]));
        EXPECT_LE(std::abs(back[i] - block[i]), std::ldexp(3.4e38f, -11)) << i;
    }
}

TEST(WeightBlocks, infinities_and_nans_are_recognised) {
    EXPECT_TRUE(finite_half(0x3c00));   // 1
    EXPECT_TRUE(finite_half(0x7bff));   // 65504
    EXPECT_TRUE(finite_half(0x8001));   // the smallest negative subnormal
    EXPECT_FALSE(finite_half(0x7c00));  // +inf
    EXPECT_FALSE(finite_half(0xfc00));  // −inf
    EXPECT_FALSE(finite_half(0x7e00));  // NaN
}

// A model whose blocks span six orders of magnitude, its parameters
// synthesized on every SIMD target against the same sum in double from the
// unpacked weights (Eigen's binary16 conversion, not the kernels' Highway
// one): a wrong scale, lane order or conversion on any target shows.
TEST(WeightBlocks, every_simd_target_synthesizes_the_stored_weights) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    for (const int lobes : {2, 3}) {  // d = 12 (the fixed-size kernel) and 18 (the general one)
        PoseModel m;
        m.order = 4;
        m.lobes = lobes;
        m.vertex_count = 300;
        const int joints = 4, d = m.params_per_vertex(), fpj = 9;
        for (int j = 0; j < joints; ++j) m.joints.push_back("bone" + std::to_string(j));
        m.joint_offsets.push_back(0);
        for (std::size_t v = 0; v < m.vertex_count; ++v) {
            for (int j = 0; j < int(v % (joints + 1)); ++j) m.joint_index.push_back(std::uint16_t((v + j) % joints));
            m.joint_offsets.push_back(std::uint32_t(m.joint_index.size()));
        }
        for (std::size_t i = 0; i < m.vertex_count * d; ++i) m.bias.push_back(float(uniform(rng)));
        std::vector<float> weights;
        for (std::size_t e = 0; e < m.joint_index.size(); ++e) {
            const std::vector<float> block = random_block(std::size_t(fpj) * d, float(std::pow(10.0, double(e % 7) - 3.0)), rng);
            weights.insert(weights.end(), block.begin(), block.end());
        }
        use_raw_joint_features(m);
        set_weights(m, weights);
        check_pose_model(m);
        const std::vector<float> stored = weight_values(m);

        std::vector<float> rotations;
        for (int j = 0; j < joints; ++j) {
            const Eigen::Matrix3d r =
                Eigen::AngleAxisd(uniform(rng), Eigen::Vector3d(uniform(rng), uniform(rng), 1.0).normalized())
                    .toRotationMatrix();
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) rotations.push_back(float(r(a, b)));
        }
        const std::vector<float> features = pose_features(m, rotations.data());
        std::vector<double> expected(m.vertex_count * d), size(m.vertex_count * d);
        for (std::size_t v = 0; v < m.vertex_count; ++v)
            for (int i = 0; i < d; ++i) {
                double sum = m.bias[v * d + i], magnitude = std::abs(sum);
                for (std::uint32_t e = m.joint_offsets[v]; e < m.joint_offsets[v + 1]; ++e)
                    for (int a = 0; a < fpj; ++a) {
                        const double term = double(features[m.joint_index[e] * fpj + a]) *
                                            double(stored[(std::size_t(e) * fpj + a) * d + i]);
                        sum += term;
                        magnitude += std::abs(term);
                    }
                expected[v * d + i] = sum;
                size[v * d + i] = magnitude;
            }
        for (const std::string& target : simd_targets()) {
            force_simd_target(target);
            std::vector<float> params(m.vertex_count * d, -7.0f);
            synthesize_params(m, rotations.data(), params.data(), 2);
            for (std::size_t k = 0; k < params.size(); ++k)
                ASSERT_NEAR(params[k], expected[k], 1e-5 * size[k] + 1e-30) << target << " d " << d << " value " << k;
        }
        force_simd_target("");
    }
}

}  // namespace
}  // namespace penumbra::visibility
