#include "sh/rotation.hpp"

#include <cmath>
#include <string>

#include <Eigen/LU>

#include "common/error.hpp"
#include "sh/basis.hpp"

namespace penumbra::sh {
namespace {

// Ivanic–Ruedenberg's P function (their Table 2): an entry of band l from band
// 1 (r) and band l−1 (previous). i is in {−1, 0, 1}; a, b index band l−1 / l.
double p_term(int i, int a, int b, int l, const Eigen::MatrixXd& r, const Eigen::MatrixXd& previous) {
    const auto r_at = [&](int row, int column) { return r(row + 1, column + 1); };
    const auto d_at = [&](int row, int column) { return previous(row + l - 1, column + l - 1); };
    if (b == l) return r_at(i, 1) * d_at(a, l - 1) - r_at(i, -1) * d_at(a, -l + 1);
    if (b == -l) return r_at(i, 1) * d_at(a, -l + 1) + r_at(i, -1) * d_at(a, l - 1);
    return r_at(i, 0) * d_at(a, b);
}

}  // namespace

ShRotation::ShRotation(int order, const Eigen::Matrix3d& rotation) : order_(order) {
    check_order(order);
    if (!rotation.allFinite() ||
        !(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
        std::abs(rotation.determinant() - 1.0) > 1e-6)
        throw ArgumentError("SH rotation needs a proper 3x3 rotation matrix (orthonormal, determinant +1)");

    bands_.resize(order);
    bands_[0] = Eigen::MatrixXd::Ones(1, 1);
    if (order == 1) return;

    // Band 1: y_1 = sqrt(3/4π)·(y, z, x), so D^1 = P R Pᵀ with the permutation
    // (m = −1, 0, 1) -> (y, z, x).
    const int axis_of[3] = {1, 2, 0};
    Eigen::MatrixXd r(3, 3);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r(i, j) = rotation(axis_of[i], axis_of[j]);
    bands_[1] = r;

    // Bands l >= 2: D^l_mn = u U + v V + w W (Ivanic–Ruedenberg Eq. 8.1, Table 1–2).
    for (int l = 2; l < order; ++l) {
        const Eigen::MatrixXd& previous = bands_[l - 1];
        Eigen::MatrixXd& d = bands_[l];
        d.resize(2 * l + 1, 2 * l + 1);
        for (int m = -l; m <= l; ++m) {
            for (int n = -l; n <= l; ++n) {
                const int abs_m = std::abs(m);
                const double delta_m0 = (m == 0) ? 1.0 : 0.0;
                const double denominator = (std::abs(n) == l) ? 2.0 * l * (2.0 * l - 1.0) : double(l + n) * (l - n);
                const double u = std::sqrt(double(l + m) * (l - m) / denominator);
                const double v = 0.5 * std::sqrt((1.0 + delta_m0) * (l + abs_m - 1.0) * (l + abs_m) / denominator) *
                                 (1.0 - 2.0 * delta_m0);
                const double w = -0.5 * std::sqrt((l - abs_m - 1.0) * (l - abs_m) / denominator) * (1.0 - delta_m0);

                double value = 0.0;
                if (u != 0.0) value += u * p_term(0, m, n, l, r, previous);
                if (v != 0.0) {
                    double big_v;
                    if (m == 0)
                        big_v = p_term(1, 1, n, l, r, previous) + p_term(-1, -1, n, l, r, previous);
                    else if (m > 0)
                        big_v = p_term(1, m - 1, n, l, r, previous) * std::sqrt(m == 1 ? 2.0 : 1.0) -
                                (m == 1 ? 0.0 : p_term(-1, -m + 1, n, l, r, previous));
                    else
                        big_v = (m == -1 ? 0.0 : p_term(1, m + 1, n, l, r, previous)) +
                                p_term(-1, -m - 1, n, l, r, previous) * std::sqrt(m == -1 ? 2.0 : 1.0);
                    value += v * big_v;
                }
                if (w != 0.0) {
                    const double big_w = (m > 0)
                        ? p_term(1, m + 1, n, l, r, previous) + p_term(-1, -m - 1, n, l, r, previous)
                        : p_term(1, m - 1, n, l, r, previous) - p_term(-1, -m + 1, n, l, r, previous);
                    value += w * big_w;
                }
                d(m + l, n + l) = value;
            }
        }
    }
}

void ShRotation::apply(const double* in, double* out) const {
    for (int l = 0; l < order_; ++l) {
        const int offset = l * l;
        Eigen::Map<Eigen::VectorXd>(out + offset, 2 * l + 1).noalias() =
            bands_[l] * Eigen::Map<const Eigen::VectorXd>(in + offset, 2 * l + 1);
    }
}

Eigen::MatrixXd ShRotation::apply(const Eigen::MatrixXd& coefficients) const {
    if (coefficients.rows() != coefficient_count(order_))
        throw ArgumentError("SH rotation of order " + std::to_string(order_) + " needs " +
                            std::to_string(coefficient_count(order_)) + " coefficient rows, got " +
                            std::to_string(coefficients.rows()));
    Eigen::MatrixXd out(coefficients.rows(), coefficients.cols());
    for (int l = 0; l < order_; ++l)
        out.middleRows(l * l, 2 * l + 1).noalias() = bands_[l] * coefficients.middleRows(l * l, 2 * l + 1);
    return out;
}

Eigen::MatrixXd ShRotation::matrix() const {
    const int n = coefficient_count(order_);
    Eigen::MatrixXd full = Eigen::MatrixXd::Zero(n, n);
    for (int l = 0; l < order_; ++l) full.block(l * l, l * l, 2 * l + 1, 2 * l + 1) = bands_[l];
    return full;
}

}  // namespace penumbra::sh
