// Colour maps correlated with a Gaussian microsurface (paper Sec. 5): the
// statistics a node group needs to filter a colour map of the microsurface's
// heights (Sec. 5.1) or slopes (Sec. 5.2), view- and light-dependently.
//
// Conventions: heights h ~ N(0, σ_h²); slopes s = (∂h/∂x, ∂h/∂y) ~ N(s̄, Σ),
// the microfacet normal is (−s_x, −s_y, 1)/‖·‖; directions are given by their
// polar angle θ from the macro normal and, for slopes, their azimuth φ.
// Everything is in double and stays finite at θ → 0, θ → 90° and σ_s → 0.
#pragma once

#include <array>

namespace penumbra::colormap {

// ---- Smith masking for Gaussian slopes (paper Eq. 3) -----------------------

// Λ(ω) = φ(a)/a − Q(a), a = cot θ / σ_s, Q the upper normal tail: the Smith
// masking term of a direction whose slope standard deviation (in the
// direction's azimuth) is σ_s. Λ = 0 at normal incidence or σ_s → 0; Λ → ∞
// at grazing (θ = 90° gives +inf). Uses the asymptotic series for large a,
// where the two terms cancel.
double smith_lambda(double theta, double sigma_slope);
// Λ as a function of a = cot θ / σ_s directly (a >= 0; a = 0 gives +inf).
double smith_lambda_of_a(double a);

// Average visibility towards the light of what the viewer sees, paper Eq. 13:
// V̄ = (1 + Λ(ω_o)) / (1 + Λ(ω_o) + Λ(ω_i)). Infinite Λs take their limits
// (Λ_i = ∞: 0 unless Λ_o is infinite too, then 1/2).
double average_visibility(double lambda_view, double lambda_light);

// ---- Height-correlated filtering (paper Sec. 5.1) ---------------------------

// The effective (visible and lit) height distribution D_h of Eq. 16,
// ∝ Φ(h/σ_h)^Λ φ(h/σ_h), Λ = Λ(ω_o) + Λ(ω_i), summarized as a Gaussian
// N(μ_d, σ_d²) with σ_h = 1 (scale both by σ_h).
struct HeightStatistics {
    double mean = 0.0;    // μ_d / σ_h
    double stddev = 1.0;  // σ_d / σ_h
};

// Exact moments by numerical integration in log space: the integrand
// exp(Λ log Φ(h) + log φ(h)) is integrated around its mode with a scale set
// by its curvature, so Λ up to 1e12 neither overflows nor loses the peak.
// For integer Λ = n − 1 the result is the mean and spread of the largest of
// n standard normals (tests use this). Λ must be >= 0 (ArgumentError).
HeightStatistics effective_height_exact(double lambda_sum);

// The paper's fit, Eqs. 17–18: μ_d = α_μ log(β_μ Λ + 1),
// σ_d = 1 / (1 + α_σ log(β_σ Λ + 1)), with α_μ = 0.39, β_μ = 4.75,
// α_σ = 0.26, β_σ = 1.13.
HeightStatistics effective_height_fit(double lambda_sum);

// ---- Slope-correlated filtering (paper Sec. 5.2) ----------------------------

// The view-dependent slope filtering distribution of Eqs. 19–20 for a view
// direction ω_o: the projected-area weighting of the microfacets,
//   D_s(s) ∝ p(s) · √(1+‖s‖²) · max(n(s)·ω_o, 0) = p(s) · max(cos θ_o − sin θ_o (s·d), 0),
// with d = (cos φ_o, sin φ_o). (√(1+‖s‖²) is the microfacet area per unit of
// macro area; it cancels the normalization of n.) D_s is a Gaussian times a
// clamped linear function of y = s·d, so its mean and covariance are exact
// in closed form: with μ_y = s̄·d, σ_y² = dᵀΣd and c = (cot θ_o − μ_y)/σ_y,
//   Z0 = cΦ(c) + φ(c),  E[z] = −Φ(c)/Z0,  E[z²] = (cΦ(c) + 2φ(c))/Z0,
// z = (y − μ_y)/σ_y, and the rest of s follows y by Gaussian conditioning:
//   mean = s̄ + Σd/σ_y · E[z],  Cov = Σ − Σd dᵀΣ/σ_y² · (1 − Var[z]).
// The approximation (our stand-in for the unavailable supplemental) is the
// Gaussian with these exact first two moments.
struct SlopeStatistics {
    std::array<double, 2> mean{0.0, 0.0};
    std::array<double, 3> covariance{1.0, 0.0, 1.0};  // xx, xy, yy
};

// Throws ArgumentError for a covariance that is not positive definite or
// non-finite input. θ_o is clamped to [0, 90°].
SlopeStatistics slope_filtering_gaussian(double theta_view, double phi_view,
                                         const std::array<double, 2>& slope_mean,
                                         const std::array<double, 3>& slope_covariance);

// The 1D factors for zero-mean slopes along the view azimuth, as a function
// of c = cot θ_o / σ_y (c >= 0): E[z] and sqrt(Var[z]). Node groups read
// these from a table. c = +inf gives (0, 1).
struct SlopeShift {
    double mean = 0.0;
    double stddev = 1.0;
};
SlopeShift slope_shift_of_c(double c);

// The same moments by brute force (a 2D grid over slopes, using the normal
// n(s) itself), for tests and the docs: independent of the algebra above.
SlopeStatistics slope_filtering_numerical(double theta_view, double phi_view,
                                          const std::array<double, 2>& slope_mean,
                                          const std::array<double, 3>& slope_covariance, int grid = 801);

}  // namespace penumbra::colormap
