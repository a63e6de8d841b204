// Lane vectors for the kernels Highway compiles once per SIMD target
// (sh/pose_shading_kernel.cpp, visibility/vertex_kernels.cpp,
// lights/region_kernels.cpp). A lane vector is one register of the target
// being compiled, written as a GCC/Clang vector extension, which Highway's
// per-target `#pragma GCC target` turns into that target's instructions:
// every step is the same straight-line arithmetic on all lanes, and a choice
// is a lane mask instead of a branch.
//
// A kernel includes this after <hwy/highway.h>, so that foreach_target
// re-includes it once per target (Highway's -inl.h convention: the guard
// below flips with HWY_TARGET_TOGGLE), and takes the names with
// `using namespace simd::HWY_NAMESPACE;` inside its own HWY_NAMESPACE. What
// Highway needs in each kernel's translation unit (HWY_TARGET_INCLUDE,
// foreach_target.h, HWY_EXPORT, HWY_DYNAMIC_DISPATCH) stays there; the
// targets and the override are common/simd_compiled_targets.hpp and
// common/simd_target.hpp.

#if defined(PENUMBRA_COMMON_SIMD_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PENUMBRA_COMMON_SIMD_LANES_INL_H_
#undef PENUMBRA_COMMON_SIMD_LANES_INL_H_
#else
#define PENUMBRA_COMMON_SIMD_LANES_INL_H_
#endif

#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

#include <hwy/highway.h>

// Forced inline, so that a batch's steps stay one straight-line block in
// registers.
#ifndef PENUMBRA_LANES_INLINE
#define PENUMBRA_LANES_INLINE [[gnu::always_inline]] inline
#endif

HWY_BEFORE_NAMESPACE();
namespace penumbra::simd::HWY_NAMESPACE {

// One lane vector = one SIMD register of S for the target being compiled:
// wider vectors are split by the compiler into pieces that go through
// memory, which measured 1.6x slower (docs/sh-engine.md). EMU128 (no SIMD
// instructions) gets one lane: the scalar reference the SIMD targets are
// tested and benchmarked against.
#if HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR
inline constexpr int kDoubleLanes = 1, kFloatLanes = 1;
#else
inline constexpr int kDoubleLanes = HWY_LANES(double), kFloatLanes = HWY_LANES(float);
#endif

template <typename S>
struct Lanes;

template <>
struct Lanes<double> {
    static constexpr int count = kDoubleLanes;
    typedef double Vec __attribute__((vector_size(count * sizeof(double))));
    typedef long long Mask __attribute__((vector_size(count * sizeof(double))));
};

template <>
struct Lanes<float> {
    static constexpr int count = kFloatLanes;
    typedef float Vec __attribute__((vector_size(count * sizeof(float))));
    typedef std::int32_t Mask __attribute__((vector_size(count * sizeof(float))));
};

template <typename S>
using Vec = typename Lanes<S>::Vec;
template <typename S>
using Mask = typename Lanes<S>::Mask;
using VecD = Vec<double>;
using MaskD = Mask<double>;
using VecF = Vec<float>;
using MaskF = Mask<float>;

// The element type of lane vector V.
template <typename V>
using LaneOf = std::remove_cvref_t<decltype(std::declval<V&>()[0])>;

// Every lane = value. value − 0 is value exactly (−0 included) and compiles
// to one broadcast; a lane-by-lane fill compiled to one masked insert per
// lane.
template <typename S>
PENUMBRA_LANES_INLINE Vec<S> splat(S value) {
    return value - Vec<S>{};
}

// The square root of every lane: one vector instruction where the kernel is
// compiled with -fno-math-errno.
template <typename V>
PENUMBRA_LANES_INLINE V sqrt_lanes(const V& x) {
    V r{};
    for (int k = 0; k < int(sizeof(V) / sizeof(LaneOf<V>)); ++k) r[k] = std::sqrt(x[k]);
    return r;
}

// False in the lanes holding NaN or ±inf.
template <typename V>
PENUMBRA_LANES_INLINE Mask<LaneOf<V>> finite(const V& x) {
    return x - x == LaneOf<V>(0);
}

}  // namespace penumbra::simd::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // PENUMBRA_COMMON_SIMD_LANES_INL_H_ toggle
