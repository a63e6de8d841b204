// Rotation of SH coefficient vectors. Lighting is rotated into a vertex frame,
// and visibility into the reflection frame (paper, Sec. 4.2), so this sits on
// the hot path of relighting.
//
// Rotating a function f by R gives g(ω) = f(Rᵀω); its coefficients are D(R)·c.
// D(R) is block diagonal, one (2l+1)×(2l+1) block per band, built from the
// 3×3 matrix directly by the Ivanic–Ruedenberg recurrence (J. Phys. Chem. 1996,
// 100, 6342, with the 1998 erratum): band l from band l−1 and band 1, no Euler
// angles, so no gimbal singularity.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace penumbra::sh {

class ShRotation {
public:
    // R must be a proper rotation (RᵀR = I, det R = +1, to 1e-6);
    // otherwise, or for an order outside [1, max_order], ArgumentError.
    ShRotation(int order, const Eigen::Matrix3d& rotation);

    int order() const { return order_; }

    // out = D(R)·in for order² coefficients. in and out must not alias.
    void apply(const double* in, double* out) const;

    // The same for several channels at once: coefficients is (order², k),
    // e.g. k = 3 for RGB lighting. Returns (order², k).
    Eigen::MatrixXd apply(const Eigen::MatrixXd& coefficients) const;

    // D^l, the (2l+1)×(2l+1) block of band l, indexed [m+l][m'+l].
    const Eigen::MatrixXd& band(int l) const { return bands_[l]; }

    // The full order²×order² block-diagonal matrix D(R).
    Eigen::MatrixXd matrix() const;

private:
    int order_;
    std::vector<Eigen::MatrixXd> bands_;
};

}  // namespace penumbra::sh
