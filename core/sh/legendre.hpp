// The normalized associated Legendre factors the real SH basis (basis.hpp) is
// built from, and the recurrence that computes them: the one copy every SH
// evaluation uses (basis.cpp, the SIMD lanes of pose_shading.cpp, the row
// integrals of projection.cpp, zonal projection, tabulated BRDF kernels).
// Tests: tests/cpp/sh/legendre_test.cpp.
//
//   p̄_lm(z) = K_lm P_l^m(z) / sin^mθ,   z = cosθ,   0 <= m <= l,
//   K_lm = sqrt((2l+1)/(4π) · (l−m)!/(l+m)!)   (basis.hpp),
// a polynomial in z (so exact at the poles), with y_l0 = p̄_l0(z) and, for
// m > 0, y_l±m = √2 p̄_lm(z) · (the real or imaginary part of (x + iy)^m).
// Recurrence in l at fixed m, normalized at every step so each term stays
// O(1) (the textbook form multiplies (2m−1)!! by a tiny K_lm):
//   p̄_mm      = sqrt((2m+1)/4π) · Π_{k=1..m} sqrt((2k−1)/(2k))
//   p̄_(m+1)m  = sqrt(2m+3) · z · p̄_mm
//   p̄_lm      = a_lm (z p̄_(l−1)m − b_lm p̄_(l−2)m),
//   a_lm = sqrt((4l²−1)/(l²−m²)),  b_lm = sqrt(((l−1)²−m²)/(4(l−1)²−1)).
// a_lm and b_lm depend on l and m only, so other normalizations of the same
// functions (brdf_kernel.cpp's orthonormal-on-[−1, 1] p̄_lm sin^mθ) share them.
#pragma once

#include <array>

#include "sh/basis.hpp"

namespace penumbra::sh {

// The recurrence's coefficients up to max_order, computed once.
struct LegendreRecurrence {
    std::array<double, max_order> diagonal{};           // p̄_mm
    std::array<double, max_order> first{};              // sqrt(2m+3): p̄_(m+1)m = first[m] z p̄_mm
    std::array<double, max_order * max_order> a{}, b{};  // a_lm, b_lm at sh_index(l, m), l >= m + 2
};

const LegendreRecurrence& legendre_recurrence();

// p̄_lm(z) for 0 <= m <= l < order, stored at sh_index(l, m) (the m >= 0
// slots of an order² array; the others are left alone). No checks: order in
// [1, max_order].
void legendre_scaled(int order, double z, double* out);

}  // namespace penumbra::sh
