#include "common/simd_target.hpp"

// The kernels' target list: hwy::SupportedAndGeneratedTargets() reads
// HWY_TARGETS of the file it is compiled in.
#include "common/simd_compiled_targets.hpp"

#include <cstdint>

#include <hwy/targets.h>

#include "common/error.hpp"

namespace penumbra {

std::vector<std::string> simd_targets() {
    std::vector<std::string> names;
    for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) names.push_back(hwy::TargetName(target));
    return names;
}

std::string simd_target() { return simd_targets().front(); }

void force_simd_target(const std::string& name) {
    hwy::SetSupportedTargetsForTest(0);  // the CPU's own list, and the dispatch chooses again
    if (name.empty()) return;
    for (const std::int64_t target : hwy::SupportedAndGeneratedTargets())
        if (name == hwy::TargetName(target)) {
            hwy::SetSupportedTargetsForTest(target);
            return;
        }
    std::string known;
    for (const std::string& n : simd_targets()) known += (known.empty() ? "" : ", ") + n;
    throw ArgumentError("SIMD target '" + name + "' is not compiled in or not supported by this CPU (have: " + known + ")");
}

}  // namespace penumbra
