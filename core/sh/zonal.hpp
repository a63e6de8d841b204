// Zonal harmonics (ZH): functions symmetric about an axis, stored as one
// coefficient per band. The visibility baker fits visibility as a sum of ZH
// lobes (paper, Sec. 3.1) because a lobe rotates by moving its axis, and
// expands back to SH with Eq. 1.
#pragma once

#include <array>
#include <functional>

#include <Eigen/Core>

#include "sh/basis.hpp"

namespace penumbra::sh {

// f(ω) = Σ_l band[l] · y_l0 in the frame whose +z is `axis`; band[l] is the
// paper's v_l^x (zonal coefficient of band l), for l < the order in use.
struct ZhLobe {
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    std::array<double, max_order> band{};
};

// Paper Eq. 1 for one lobe: sh[l,m] += sqrt(4π/(2l+1)) g_l y_lm(axis),
// for l < order. The axis is normalized (zero/non-finite: ArgumentError).
void zh_to_sh_accumulate(int order, const Eigen::Vector3d& axis, const double* band, double* sh);
void zh_to_sh_accumulate(int order, const ZhLobe& lobe, double* sh);

// The same lobe turned by the rotation R: its axis becomes R·axis, its band
// coefficients are unchanged. Matches ShRotation(R) applied to the SH
// expansion (g(ω) = f(Rᵀω)).
ZhLobe rotate_lobe(const ZhLobe& lobe, const Eigen::Matrix3d& rotation);

// Zonal coefficients g_l = ∫_{S²} f(cosθ) y_l0(ω) dω = 2π ∫_{-1}^{1} f(μ) y_l0(μ) dμ
// of a function of cosθ about +z, for l < order, by Gauss–Legendre with
// `quadrature_nodes` nodes in μ (exact when f is a polynomial of degree
// <= 2·quadrature_nodes − order). Entries l >= order are zero.
std::array<double, max_order> project_zonal(int order, const std::function<double(double)>& f_of_cos_theta,
                                            int quadrature_nodes = 64);

}  // namespace penumbra::sh
