// Which SIMD target the Highway kernels run on (sh/pose_shading_kernel.cpp,
// visibility/vertex_kernels.cpp, lights/region_kernels.cpp). Each is
// compiled for several targets (common/simd_compiled_targets.hpp) and runs
// the best one the CPU supports, chosen at run time. Highway's names: "AVX3"
// = AVX-512, "AVX2", "SSE4", and "EMU128", the one-lane scalar reference.
// The choice is one for the whole process, shared by all three kernels.
#pragma once

#include <string>
#include <vector>

namespace penumbra {

// The target the kernels run on now.
std::string simd_target();
// Every target compiled in that this CPU supports, best first.
std::vector<std::string> simd_targets();
// Tests and benchmarks: run on `name` (one of simd_targets()) from now on;
// "" returns to the CPU's best. Not thread-safe against concurrent kernels.
// ArgumentError for a name not in simd_targets().
void force_simd_target(const std::string& name);

}  // namespace penumbra
