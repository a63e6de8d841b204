// The ZH fit, paper Eq. 1 and the diffuse AO (zh_fit.hpp)
// over many vertices at once: `count` rows one after another, as numpy
// passes them to _penumbra.visibility.fit_zh_lobes, zh_params_to_sh and
// ambient_occlusion. Each row is computed exactly as the one-vertex
// function computes it.
#pragma once

#include <cstddef>

#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {

// fit_zh_lobes of each of `count` SH rows (order² values each). `reference`
// is null or count rows of lobes × (2 + order) parameters. Writes
// params_out (count × lobes × (2 + order)) and residual_out (count).
void fit_zh_lobes_rows(const ZhFitSettings& settings, std::size_t count, const double* sh, const double* reference,
                       double* params_out, double* residual_out);

// lobes_to_sh of each of `count` rows of lobes × (2 + order) parameters:
// writes count × order² values.
void lobes_to_sh_rows(int order, int lobes, std::size_t count, const double* params, double* sh_out);

// ambient_occlusion of each of `count` SH rows (order² values each).
void ambient_occlusion_rows(int order, std::size_t count, const double* sh, double* ao_out);

}  // namespace penumbra::visibility
