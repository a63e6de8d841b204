// Convolution operators of 1D BRDFs (paper §4.2, Eq. 2): a kernel k(cosθ)
// symmetric about the local z axis (the normal, or the reflection vector for
// Phong), integrated over the upper hemisphere only, acting on an SH vector v
// in that local frame: t = T v. Shading is then t · l (lighting l in the same
// frame). SH convention: sh/basis.hpp.
//
// Derivation (from Eq. 2; the paper's Appendix A matrix is not usable)
// ---------------------------------------------------------------------
// T[l'm', lm] = ∫_{H²} k(cosθ) y_l'm'(s) y_lm(s) ds, ds = dμ dφ, μ = cosθ ∈ [0, 1].
// Write y_lm = c_m K_l|m| P_l^|m|(μ) Φ_m(φ), Φ_m = 1, cos(mφ), sin(|m|φ) for
// m = 0, > 0, < 0 and c_0 = 1, c_m = √2. The kernel does not depend on φ, so
//   ∫_0^{2π} Φ_m' Φ_m dφ = δ_{m'm} · (2π if m = 0, else π):
// every entry with m' ≠ m vanishes (cos and sin parts never mix, nor do
// different |m|), and c_m² times that integral is 2π for every m, hence
//   T[l'm, lm] = ∫_0^1 k(μ) p̄_l'|m|(μ) p̄_l|m|(μ) dμ,
//   p̄_lm = sqrt(2π) K_lm P_l^m = sqrt((2l+1)/2 · (l−m)!/(l+m)!) P_l^m,
// which depends on |m| only (entries for m and −m are equal) and is symmetric
// in l, l'. Unlike the full-sphere case (Funk–Hecke: diagonal), the half-range
// integral does not kill l + l' odd, nor l ≠ l' of equal parity for α > 0:
// every l, l' ≥ |m| pair survives. T is block diagonal over m, one dense
// symmetric (n−|m|)×(n−|m|) block per m, at order n:
//   non-zero  Σ_{m=−(n−1)}^{n−1} (n−|m|)² = n(2n²+1)/3       (44 of 256 at n = 4, 17.2%),
//   distinct  Σ_{j=1}^{n} j(j+1)/2        = n(n+1)(n+2)/6   (20 of 256 at n = 4, 7.8%).
// The paper's "17.1 % non-zero" is this 44/256; its "5.9 % unique" (15/256)
// does not hold: no two of the 20 distinct entries are in constant ratio
// (checked at four exponents), see docs/phong-operator.md.
//
// Normalized Phong, k(μ) = (α+1)/(2π) μ^α (Eq. 2):
//   T[l'm, lm] = (α+1)/(2π) ∫_0^1 μ^α p̄_l'|m| p̄_l|m| dμ.
// Its closed form (brdf_moments.cpp) expands the polynomial p̄ p̄ exactly, in
// powers of μ or of 1−μ, and integrates term by term:
//   (α+1)∫_0^1 μ^α μ^k dμ = (α+1)/(α+k+1),
//   (α+1)∫_0^1 μ^α (1−μ)^j dμ = j!/∏_{i=2}^{j+1}(α+i),
// so it is a rational function of α. Limits: α = 0 gives (1/2π)∫_H y yᵀ
// (diagonal 1/(4π), zero between distinct bands of equal parity); α → ∞ gives
// y(z) y(z)ᵀ, with (α+1)∫μ^α f = f(1) − f'(1)/(α+2) + …, i.e. error O(1/α).
// T[00, 00] = 1/(4π) for every α: under unit radiance l = v = √(4π) e_0, a
// fully visible vertex shades to lᵀ T v = 1 (energy-normalized Phong).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace penumbra::sh {

// T in per-|m| blocks, for hot loops (the dense form is mostly zeros).
struct ZonalOperator {
    int order = 0;
    // blocks[|m|](l − |m|, l' − |m|) = T[l'm, lm] for l, l' in [|m|, order),
    // shared by +m and −m; each block is symmetric.
    std::vector<Eigen::MatrixXd> blocks;

    // t = T v, both of length order². t may alias v.
    void apply(const double* v, double* t) const;
    // The dense order² × order² matrix.
    Eigen::MatrixXd dense() const;
};

// Normalized Phong, T = (α+1)/(2π) M^α (Eq. 2), for 1 <= order <= max_order
// and any α >= 0, including +infinity (the limit y(z) y(z)ᵀ). Every entry
// carries close to full double relative accuracy, for tiny, integer,
// non-integer and huge α alike; an entry is exactly 0 where it vanishes
// (m' ≠ m, l ≠ l' of equal parity at α = 0, and the exponents where an entry
// crosses zero, e.g. l = 0, l' ∈ {3, 5, …} at α = 1). Throws
// penumbra::ArgumentError for an order out of range or α < 0 or NaN.
ZonalOperator phong_zonal_operator(int order, double alpha);
Eigen::MatrixXd phong_operator(int order, double alpha);

// The clamped cosine: phong with α = 1, T = (1/π) ∫_H cosθ y yᵀ.
ZonalOperator diffuse_zonal_operator(int order);
Eigen::MatrixXd diffuse_operator(int order);

// Any 1D kernel, tabulated: k_of_mu[i] = k(μ_i), μ_i = i/(n−1), n >= 2, linear
// between samples; T = ∫_{H²} k(cosθ) y yᵀ ds (no 1/(2π) or other factor: put
// the normalization in k). Integrated exactly (16-point Gauss–Legendre per
// segment: linear × degree-30 polynomial), so the only error is the caller's
// piecewise-linear approximation of k; cost O(n · order³). Throws
// penumbra::ArgumentError for an order out of range, fewer than 2 samples or a
// non-finite sample.
ZonalOperator kernel_zonal_operator(int order, const std::vector<double>& k_of_mu);
Eigen::MatrixXd kernel_operator(int order, const std::vector<double>& k_of_mu);

}  // namespace penumbra::sh
