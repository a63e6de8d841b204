// The batch forms the bindings call (visibility/zh_rows.hpp): each row read
// and written where its vertex's data lies, computed as the one-vertex
// function computes it.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "visibility/zh_fit.hpp"
#include "visibility/zh_rows.hpp"

namespace penumbra::visibility {
namespace {

TEST(ZhRows, each_row_is_its_own_vertexs_fit_eq1_and_ao) {
    ZhFitSettings s;
    s.order = 3;
    s.lobes = 2;
    const std::size_t count = 4, n_sh = 9, d = 2 * params_per_lobe(3);
    std::mt19937 rng(5);
    std::normal_distribution<double> normal;
    std::vector<double> sh(count * n_sh), reference(count * d);
    for (double& x : sh) x = normal(rng);
    for (std::size_t i = 0; i < count; ++i) fit_zh_lobes(s, sh.data() + ((i + 1) % count) * n_sh, nullptr,
                                                         reference.data() + i * d);
    std::vector<double> params(count * d), residual(count), eq1(count * n_sh), ao(count);
    fit_zh_lobes_rows(s, count, sh.data(), reference.data(), params.data(), residual.data());
    lobes_to_sh_rows(3, 2, count, params.data(), eq1.data());
    ambient_occlusion_rows(3, count, sh.data(), ao.data());
    for (std::size_t i = 0; i < count; ++i) {
        std::vector<double> p(d), one(n_sh);
        EXPECT_EQ(fit_zh_lobes(s, sh.data() + i * n_sh, reference.data() + i * d, p.data()), residual[i]);
        EXPECT_EQ(std::vector<double>(params.begin() + long(i * d), params.begin() + long((i + 1) * d)), p);
        lobes_to_sh(3, 2, p.data(), one.data());
        EXPECT_EQ(std::vector<double>(eq1.begin() + long(i * n_sh), eq1.begin() + long((i + 1) * n_sh)), one);
        EXPECT_EQ(ao[i], ambient_occlusion(3, sh.data() + i * n_sh));
    }
}

}  // namespace
}  // namespace penumbra::visibility
