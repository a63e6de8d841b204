// Internal to the pose shader (sh/pose_shading.hpp): the per-call constants
// every vertex shares, and the per-target kernel that shades a range of
// vertices (sh/pose_shading_kernel.cpp, compiled once per SIMD target and
// chosen at run time).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "sh/legendre.hpp"
#include "sh/pose_shading.hpp"

namespace penumbra::sh::detail {

// Everything a call shares between vertices, its numbers in S, the
// precision the kernel computes in (that of the buffers).
template <typename S>
struct PoseShadingSetup {
    int order = 0;
    int lobes = 1;
    ShadingModel model = ShadingModel::diffuse;
    std::array<S, 3> camera{};
    bool want_visibility = false;
    // T per |m|: block a is (order−a)², row-major, at block_offset[a].
    std::array<int, max_order> block_offset{};
    std::vector<S> blocks;
    // X = D(Rx(90°)) and Xᵀ row by row, quarter_turn_width(l) entries for
    // each row of band l (the non-zeros, then zeros).
    std::vector<int> x_columns, xt_columns;
    std::vector<S> x_values, xt_values;
    // lighting[i][c], and for translucency the back lobe folded into it:
    // back[i][c] = transmission_c (−1)^l sqrt(4π/(2l+1)) h_l lighting[i][c].
    std::vector<std::array<S, 3>> lighting;
    std::vector<std::array<S, 3>> back;
    std::array<S, max_order> zh_scale{};        // sqrt(4π/(2l+1)), Eq. 1
    std::array<S, max_order> ao_weight{};       // √(4π) T_d[00, l0]
    // The normalized Legendre recurrence (sh/legendre.hpp), copied in beside
    // the other per-call constants.
    std::array<S, max_order> legendre_diagonal{}, legendre_first{};
    std::array<S, max_order * max_order> legendre_a{}, legendre_b{};
};

// The same constants rounded to float, for float buffers.
PoseShadingSetup<float> to_float(const PoseShadingSetup<double>& setup);

// Entries stored per row of band l of X = D(Rx(90°)) and of Xᵀ: a row has
// at most l/2 + 1 non-zeros (checked when the shader is built).
constexpr int quarter_turn_width(int l) { return l / 2 + 1; }

// Shades vertices [begin, end) of `buffers` in the buffers' precision,
// adding the invalid ones to invalid_count.
template <typename Real>
using RangeFunction = void (*)(const PoseShadingSetup<Real>&, const PoseBuffers<Real>&, std::size_t, std::size_t,
                               std::size_t&);

// Shades a block in structure-of-arrays layout (PoseBlock), adding the
// invalid vertices to invalid_count.
using BlockFunction = void (*)(const PoseShadingSetup<float>&, const PoseBlock&, std::size_t&);

// The kernel for `order` of the SIMD target chosen for this CPU (Highway's
// dynamic dispatch: the best target the CPU supports among those compiled).
RangeFunction<float> range_function_float(int order);
RangeFunction<double> range_function_double(int order);
BlockFunction block_function(int order);

// How many vertices one batch holds on the chosen target.
int simd_lanes();

}  // namespace penumbra::sh::detail
