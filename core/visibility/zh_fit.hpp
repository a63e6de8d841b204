// Fitting a few zonal-harmonic lobes to an SH visibility vector (paper §3.1,
// fig. 2b). A lobe is six scalars at order 4: its axis as two numbers and one
// zonal coefficient per band; its SH expansion is paper Eq. 1.
//
// Axis parameterization (seam-free): the Lambert azimuthal equal-area map of
// the vertex's local frame, centred on the normal (+z):
//   (X, Y) = sqrt(2 / (1 + z)) · (x, y),   |(X, Y)| <= 2,
//   z = 1 − r²/2, (x, y) = sqrt(1 − r²/4) · (X, Y),   r = |(X, Y)|.
// It is smooth and one-to-one everywhere except at the single point −z
// (straight into the surface), which visibility lobes do not approach; there
// is no longitude seam, so a lobe whose axis wanders across φ = ±π, or over
// the normal, moves smoothly in (X, Y), and the linear pose model (which
// interpolates these numbers) never has to jump. Predicted values with r > 2
// are pulled back onto r = 2.
//
// Parameter layout per vertex: lobes × (2 + order) scalars,
// [X, Y, g_0, …, g_{order−1}] per lobe.
//
// Fit: for fixed axes the band coefficients are linear (one small least
// squares per band, a 1e-6 ridge splitting the constant band evenly between
// lobes that share it), so Levenberg–Marquardt runs over the 2·lobes axis
// numbers only. Deterministic initialization: lobe k starts at the best of a
// fixed set of 64 directions plus the residual's band-1 (bent-normal)
// direction, fitted greedily to what lobes 1..k−1 leave. Per-frame fits
// start from a reference fit (the vertex's mean visibility over all frames)
// and carry a prior towards its axes, weighted axis_prior·|sh|², so lobe k is
// the same lobe in every frame and lobes that barely matter do not wander.
// The weight trades fit error for smoothness across poses: on the test
// character, 1e-3 gives the lowest per-frame ZH error but a linear model
// twice as bad as with 1 (docs/visibility.md), hence the default 1.
#pragma once

#include <Eigen/Core>

namespace penumbra::visibility {

constexpr int max_lobes = 4;

struct ZhFitSettings {
    int order = 4;             // SH order of the data (1..max_sh_order, order_limit.hpp)
    int lobes = 2;             // c, 1..4
    int iterations = 8;        // Levenberg–Marquardt iterations
    double axis_prior = 1.0;   // weight of the pull towards the reference axes, relative to |sh|² (docs/visibility.md)
};

inline int params_per_lobe(int order) { return 2 + order; }

Eigen::Vector2d axis_to_lambert(const Eigen::Vector3d& unit_axis);
Eigen::Vector3d lambert_to_axis(double X, double Y);

// Fits settings.lobes lobes to sh (order² values). `reference` is null for a
// fresh (greedy) fit, or a previous fit's parameters whose axes start and
// anchor this one. Writes lobes × (2 + order) parameters; returns the squared
// L2 residual |sh − Eq.1(params)|² (without the prior).
double fit_zh_lobes(const ZhFitSettings& settings, const double* sh, const double* reference, double* params_out);

// Eq. 1 for all lobes of one vertex: writes order² values (overwrites).
void lobes_to_sh(int order, int lobes, const double* params, double* sh_out);

// The diffuse AO of an SH visibility vector: √(4π)·(T_diffuse v)_00, what
// the fit's and the model's errors are also measured in.
double ambient_occlusion(int order, const double* sh);

}  // namespace penumbra::visibility
