// The visibility tool's highest SH order (bands 0..7): one constant that the
// bake's settings range, the ZH fit, the pose model and its file, the
// bindings (_penumbra.visibility.MAX_ORDER), the GPU preview and the
// add-on's SH Order setting (through _penumbra.settings_spec()) all use.
//
// It is not the SH engine's limit (sh::max_order = 16, _penumbra.sh.MAX_ORDER),
// which serves any SH caller. This tool stops at 8 because its run time
// shades through the engine's per-order unrolled path, which exists for
// orders 1–8 (sh/pose_shading_kernel.cpp), and because the GPU preview passes
// a vertex's lobes as vertex attributes: order 8 × 4 lobes is 11 vec4s, with
// position, normal and tangent 14 of the 16 OpenGL guarantees
// (docs/visibility.md, GPU Preview).
#pragma once

namespace penumbra::visibility {

constexpr int max_sh_order = 8;

}  // namespace penumbra::visibility
