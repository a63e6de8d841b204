#include "visibility/weight_blocks.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace penumbra::visibility {

namespace {

// Below this a block is stored as zero: its inverse scale would overflow
// a float, and a weight of 1e-30 changes no lobe.
constexpr float kSmallest = 1e-30f;

// The smallest power of two ≥ the block's largest magnitude (at most 2^127,
// the largest a float holds: above 2^127 the scaled values reach 2, still
// exact in binary16); 0 for a zero block.
float block_scale(const float* values, std::size_t count) {
    float largest = 0.0f;
    for (std::size_t i = 0; i < count; ++i) largest = std::max(largest, std::abs(values[i]));
    if (largest < kSmallest) return 0.0f;
    int exponent = 0;
    const float mantissa = std::frexp(largest, &exponent);  // mantissa in [1/2, 1)
    return std::ldexp(1.0f, std::min(mantissa == 0.5f ? exponent - 1 : exponent, 127));
}

std::uint16_t to_half(float x) { return Eigen::numext::bit_cast<std::uint16_t>(Eigen::half(x)); }
float from_half(std::uint16_t bits) { return float(Eigen::numext::bit_cast<Eigen::half>(bits)); }

}  // namespace

float pack_weight_block(const float* values, std::size_t count, std::uint16_t* halves_out) {
    const float scale = block_scale(values, count);
    const float inverse = scale > 0.0f ? 1.0f / scale : 0.0f;  // exact: a power of two
    for (std::size_t i = 0; i < count; ++i) halves_out[i] = to_half(values[i] * inverse);
    return scale;
}

void unpack_weight_block(const std::uint16_t* halves, std::size_t count, float scale, float* values_out) {
    for (std::size_t i = 0; i < count; ++i) values_out[i] = scale * from_half(halves[i]);
}

void round_weight_block(float* values, std::size_t count) {
    const float scale = block_scale(values, count);
    if (scale == 0.0f) {
        std::fill(values, values + count, 0.0f);
        return;
    }
    const float inverse = 1.0f / scale;
    for (std::size_t i = 0; i < count; ++i) values[i] = scale * from_half(to_half(values[i] * inverse));
}

bool finite_half(std::uint16_t bits) { return (bits & 0x7c00u) != 0x7c00u; }

}  // namespace penumbra::visibility
