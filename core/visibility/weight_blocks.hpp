// The pose model's joint weight blocks as stored: IEEE binary16 values
// times one power-of-two scale per block.
//
// Why: the run time reads every stored block once per frame, and at
// 100k vertices that read, not the arithmetic, is most of the pose → lobes
// step (docs/visibility-benchmark.md). Half the bytes is half the read, and
// half the model on disk. Why a scale per block: binary16 alone overflows at
// 65504 and loses relative precision below 6e-5; scaled so that the block's
// largest magnitude lies in (1/2, 1], every weight is within 2^-12 of the
// scale (under 2^-11 of the block's largest magnitude), at any magnitude a
// fit produces. A power of two makes the scaling itself exact.
#pragma once

#include <cstddef>
#include <cstdint>

namespace penumbra::visibility {

// Packs count finite floats into binary16 bits (round to nearest even) and
// returns the block's scale: value ≈ scale · half. A block whose largest
// magnitude is below 1e-30 packs as zeros with scale 0.
float pack_weight_block(const float* values, std::size_t count, std::uint16_t* halves_out);

// The floats a packed block stands for.
void unpack_weight_block(const std::uint16_t* halves, std::size_t count, float scale, float* values_out);

// Replaces the block by what packing then unpacking gives (the stored value).
void round_weight_block(float* values, std::size_t count);

// True for the bits of a finite binary16 (not an infinity or NaN).
bool finite_half(std::uint16_t bits);

}  // namespace penumbra::visibility
