// The held-out error of the pose model's ridge solution (pose_model.hpp) as
// a function of λ, from one SVD, without predicting the held-out frames
// again for every λ.
//
// With A_c = U S Vᵀ the SVD of the training frames' centred pose features and
// C = Uᵀ B_c their centred lobe parameters projected on U, the ridge
// prediction of held-out frames is P · diag(w) · C, P = (A_h − mean) V and
// w_i = s_i / (s_i² + λ). Its squared error against the held-out frames'
// centred lobe parameters R = B_h − mean is, in closed form,
//   |R|² − 2 Σ_i w_i g_i + Σ_ij w_i w_j (PᵀP)_ij (C Cᵀ)_ij,   g_i = (Pᵀ R Cᵀ)_ii:
// a quadratic in w whose r × r coefficients are computed once; each λ then
// costs O(r²), r the rank (at most the training frames).
//
// The error is measured in SH, linearized: a vertex's lobe-parameter error
// Δp counts as |J Δp|² / 4π, J the Jacobian of Eq. 1 (lobes → SH) at the
// vertex's mean training lobes, i.e. the squared RMS error of its visibility
// over the sphere that the lobes' error alone makes (the ZH fit's own
// residual does not depend on λ).
#pragma once

#include <cstddef>

#include <Eigen/Core>

namespace penumbra::visibility {

struct RidgeCurve {
    double residual_squared = 0.0;  // |R|²
    Eigen::VectorXd g;              // r
    Eigen::MatrixXd q;              // (PᵀP) ∘ (C Cᵀ), r × r
    std::size_t samples = 0;        // (vertex, held-out frame) pairs

    // Linearized RMS SH error of the ridge prediction with weights w
    // (s/(s² + λ) per singular value): sqrt(|R − P diag(w) C|² / samples).
    double rms(const Eigen::VectorXd& w) const;
};

// order, lobes: of the lobes (d = lobes·(2 + order) parameters per vertex);
// mean_params: V·d, each vertex's mean training lobes (where J is taken);
// P: H × r; C: r × V·d; R: H × V·d. Parallel over vertices; the result does
// not depend on the thread count.
RidgeCurve ridge_curve(int order, int lobes, const Eigen::RowVectorXf& mean_params, const Eigen::MatrixXd& P,
                       const Eigen::MatrixXf& C, const Eigen::MatrixXf& R, int threads = 0);

}  // namespace penumbra::visibility
