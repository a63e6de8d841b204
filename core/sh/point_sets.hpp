// Deterministic direction sets with integration weights on the unit sphere:
// the quadratures that SH projection, its tests and the bakers integrate with.
// A PointSet approximates ∫_{S²} f(ω) dω by Σ_i weights[i] · f(directions[i]).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace penumbra::sh {

struct PointSet {
    std::vector<Eigen::Vector3d> directions;  // unit vectors, world axes (common/latlong.hpp)
    std::vector<double> weights;              // solid angle per point; sums to 4π
};

// n points of the spherical Fibonacci lattice (z_i = 1 − (2i+1)/n, φ advancing
// by the golden angle), each with weight 4π/n. Low discrepancy, but only
// approximately exact: use it for visibility-style sampling, not for tests
// that need machine precision. n >= 1, else penumbra::ArgumentError.
PointSet fibonacci_sphere(int n);

// Gauss–Legendre nodes μ_k and weights w_k on [−1, 1], exact for polynomials
// of degree <= 2n − 1. n >= 1, else penumbra::ArgumentError.
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights);

// Product rule: Gauss–Legendre in cosθ (n_theta nodes) × n_phi equally spaced
// φ. Integrates every spherical polynomial of degree <= min(2 n_theta − 1,
// n_phi − 1) exactly (up to rounding), so the products y_i y_j of order n
// (degree 2n − 2) need n_theta >= n and n_phi >= 2n − 1.
PointSet gauss_product_sphere(int n_theta, int n_phi);

// The smallest product rule that integrates spherical polynomials of the
// given degree exactly.
PointSet exact_sphere_quadrature(int degree);

}  // namespace penumbra::sh
