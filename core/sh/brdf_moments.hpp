// One entry of the normalized Phong operator, computed to (nearly) full double
// precision for every exponent α ≥ 0: the numerical core behind
// phong_operator (brdf_operator.hpp, which holds the derivation).
//
// The entry for bands l, l' and order |m| is
//   T[l'm, lm] = (α+1)/(2π) ∫_0^1 μ^α p̄_l'|m|(μ) p̄_l|m|(μ) dμ,
// with p̄_lm = sqrt((2l+1)/2 · (l−m)!/(l+m)!) P_l^m, orthonormal on [−1, 1].
#pragma once

namespace penumbra::sh::detail {

struct PhongEntry {
    double value = 0.0;
    // Σ|terms| / |Σ terms| of the sum that was used: the factor by which the
    // double-double rounding (≈ 1e-32) is amplified. Infinite for an entry
    // that is exactly zero at this α (e.g. l = 0, l' = 3 at α = 1).
    double condition = 0.0;
};

// 0 <= m <= l, l' <= 15 (unchecked); alpha finite and >= 0 (unchecked).
PhongEntry phong_entry(int l, int l_prime, int m, double alpha);

}  // namespace penumbra::sh::detail
