// The real spherical-harmonic (SH) basis every other part of Penumbra speaks:
// visibility, lighting and BRDF operators are all vectors or matrices in it.
//
// Convention (the only place it is written down)
// ------------------------------------------------------------------------
// Order n: bands l < n, n² coefficients, index i = l(l+1)+m. Real orthonormal
// SH, no Condon–Shortley phase:
//   y_l0 = K_l0 P_l(cosθ);
//   y_lm = √2 K_lm cos(mφ) P_l^m(cosθ)      (m > 0);
//   y_lm = √2 K_l|m| sin(|m|φ) P_l^|m|(cosθ)  (m < 0),
//   K_lm = sqrt((2l+1)/(4π) · (l−|m|)!/(l+|m|)!), P_l^m ≥ 0 near θ = 0.
// So y_1^{-1} = +sqrt(3/4π) y, y_1^0 = +sqrt(3/4π) z, y_1^1 = +sqrt(3/4π) x.
// Directions, θ and φ are Blender world coordinates as common/latlong.hpp
// defines them (+z up, θ from +z, φ from +x towards +y).
//
// Evaluation never forms θ or φ: it uses cos(mφ)sin^mθ + i sin(mφ)sin^mθ =
// (x + iy)^m and the normalized Legendre recurrence in z of legendre.hpp, so
// it is a polynomial in (x, y, z) and stays exact at and near the poles.
#pragma once

#include <Eigen/Core>

namespace penumbra::sh {

// Highest supported order (bands 0..15). Orthonormality is tested to order 8.
constexpr int max_order = 16;

constexpr int coefficient_count(int order) { return order * order; }
constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }

// Writes the order² basis values y_i(direction) to out. The direction is
// normalized first; a zero-length or non-finite direction, or an order outside
// [1, max_order], throws penumbra::ArgumentError.
void eval(int order, const Eigen::Vector3d& direction, double* out);

// Hot path for callers that already hold a unit vector and a valid order:
// no checks, no normalization.
void eval_unit(int order, const Eigen::Vector3d& unit_direction, double* out);

// Throws penumbra::ArgumentError unless 1 <= order <= max_order.
void check_order(int order);

// Returns direction / |direction|, or throws penumbra::ArgumentError when the
// direction is zero-length or has a NaN/Inf component. `what` names it in the
// message.
Eigen::Vector3d unit_direction(const Eigen::Vector3d& direction, const char* what = "direction");

}  // namespace penumbra::sh
