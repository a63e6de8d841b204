// Internal to the pose shader (sh/pose_shading.hpp): the per-call constants
// every vertex shares, and the per-target kernel that shades a range of
// vertices (sh/pose_shading_kernel.cpp, compiled once per SIMD target and
// chosen at run time).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sh/legendre.hpp"
#include "sh/pose_shading.hpp"

namespace penumbra::sh::detail {

// Everything a call shares between vertices.
struct PoseShadingSetup {
    int order = 0;
    int lobes = 1;
    ShadingModel model = ShadingModel::diffuse;
    Eigen::Vector3d camera = Eigen::Vector3d::Zero();
    bool want_visibility = false;
    // T per |m|: block a is (order−a)², row-major, at block_offset[a].
    std::array<int, max_order> block_offset{};
    std::vector<double> blocks;
    // X = D(Rx(90°)) and Xᵀ, non-zero entries by row.
    std::vector<int> x_rows, x_columns, xt_rows, xt_columns;
    std::vector<double> x_values, xt_values;
    // lighting[i][c], and for translucency the back lobe folded into it:
    // back[i][c] = transmission_c (−1)^l sqrt(4π/(2l+1)) h_l lighting[i][c].
    std::vector<std::array<double, 3>> lighting;
    std::vector<std::array<double, 3>> back;
    std::array<double, max_order> zh_scale{};        // sqrt(4π/(2l+1)), Eq. 1
    std::array<double, max_order> ao_weight{};       // √(4π) T_d[00, l0]
    // The normalized Legendre recurrence (sh/legendre.hpp), copied in beside
    // the other per-call constants.
    LegendreRecurrence legendre;
};

// Shades vertices [begin, end) of `buffers`, adding the invalid ones to
// invalid_count.
template <typename Real>
using RangeFunction = void (*)(const PoseShadingSetup&, const PoseBuffers<Real>&, std::size_t, std::size_t,
                               std::size_t&);

// The kernel for `order` of the SIMD target chosen for this CPU (Highway's
// dynamic dispatch: the best target the CPU supports among those compiled).
RangeFunction<float> range_function_float(int order);
RangeFunction<double> range_function_double(int order);

// How many vertices one batch holds on the chosen target.
int simd_lanes();

}  // namespace penumbra::sh::detail
