// Which SIMD targets the Highway kernels (sh/pose_shading_kernel.cpp,
// visibility/vertex_kernels.cpp, lights/region_kernels.cpp) are compiled
// for, and so which ones simd_target.cpp lists and can force: every target
// at least as good as the build's baseline, plus EMU128, the one-lane scalar
// reference the SIMD targets are tested against. SSSE3 is below the
// x86-64-v2 baseline. Include before any Highway header.
#pragma once

#ifndef HWY_COMPILE_ALL_ATTAINABLE
#define HWY_COMPILE_ALL_ATTAINABLE
#endif
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS HWY_SSSE3
#endif
