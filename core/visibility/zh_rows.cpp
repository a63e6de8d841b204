#include "visibility/zh_rows.hpp"

namespace penumbra::visibility {

void fit_zh_lobes_rows(const ZhFitSettings& settings, std::size_t count, const double* sh, const double* reference,
                       double* params_out, double* residual_out) {
    const std::size_t n_sh = std::size_t(settings.order) * settings.order;
    const std::size_t d = std::size_t(settings.lobes) * params_per_lobe(settings.order);
    for (std::size_t i = 0; i < count; ++i)
        residual_out[i] = fit_zh_lobes(settings, sh + i * n_sh, reference ? reference + i * d : nullptr,
                                       params_out + i * d);
}

void lobes_to_sh_rows(int order, int lobes, std::size_t count, const double* params, double* sh_out) {
    const std::size_t n_sh = std::size_t(order) * order, d = std::size_t(lobes) * params_per_lobe(order);
    for (std::size_t i = 0; i < count; ++i) lobes_to_sh(order, lobes, params + i * d, sh_out + i * n_sh);
}

void ambient_occlusion_rows(int order, std::size_t count, const double* sh, double* ao_out) {
    const std::size_t n_sh = std::size_t(order) * order;
    for (std::size_t i = 0; i < count; ++i) ao_out[i] = ambient_occlusion(order, sh + i * n_sh);
}

}  // namespace penumbra::visibility
