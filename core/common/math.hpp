// Small numeric helpers shared by the tools.
#pragma once

#include <cmath>

namespace penumbra {

// √(x² + y²) for arguments of ordinary size (directions, pixel offsets).
// Not std::hypot: glibc 2.35 gave hypot a new symbol version, and calling it
// alone would raise the package's oldest glibc from 2.34 (RHEL 9) to 2.35
// (docs/packaging.md); hypot's overflow guard buys nothing at these sizes.
inline double length_2d(double x, double y) { return std::sqrt(x * x + y * y); }

}  // namespace penumbra
