#include "sh/projection.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "sh/basis.hpp"
#include "sh/legendre.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

// Rows between two progress reports: a 16k-wide row at order 16 is about
// 1.5M multiply-adds, so 32 rows stay well under a tenth of a second.
constexpr int rows_per_report = 32;

}  // namespace

Eigen::MatrixXd project_samples(int order, const std::vector<Eigen::Vector3d>& directions,
                                const Eigen::MatrixXd& values, const std::vector<double>& weights) {
    check_order(order);
    const auto n = static_cast<Eigen::Index>(directions.size());
    if (values.rows() != n)
        throw ArgumentError("project_samples: " + std::to_string(n) + " directions but " +
                            std::to_string(values.rows()) + " value rows");
    if (!weights.empty() && static_cast<Eigen::Index>(weights.size()) != n)
        throw ArgumentError("project_samples: " + std::to_string(n) + " directions but " +
                            std::to_string(weights.size()) + " weights");
    if (n == 0) throw ArgumentError("project_samples needs at least one sample");

    const double equal_weight = 4.0 * pi / double(n);
    Eigen::MatrixXd coefficients = Eigen::MatrixXd::Zero(coefficient_count(order), values.cols());
    Eigen::VectorXd y(coefficient_count(order));
    for (Eigen::Index i = 0; i < n; ++i) {
        eval_unit(order, unit_direction(directions[i], "sample direction"), y.data());
        const double w = weights.empty() ? equal_weight : weights[i];
        coefficients.noalias() += (w * y) * values.row(i);
    }
    return coefficients;
}

Eigen::MatrixXd project_samples(int order, const PointSet& points, const Eigen::MatrixXd& values) {
    return project_samples(order, points.directions, values, points.weights);
}

Eigen::MatrixXd project_lights(int order, const std::vector<Eigen::Vector3d>& directions,
                               const Eigen::MatrixXd& rgb) {
    check_order(order);
    if (rgb.cols() != 3 || rgb.rows() != static_cast<Eigen::Index>(directions.size()))
        throw ArgumentError("project_lights needs one RGB row per light direction");
    Eigen::MatrixXd coefficients = Eigen::MatrixXd::Zero(coefficient_count(order), 3);
    Eigen::VectorXd y(coefficient_count(order));
    for (std::size_t i = 0; i < directions.size(); ++i) {
        // A delta light of irradiance E is E·δ(ω − d); ∫ E δ y = E y(d).
        eval_unit(order, unit_direction(directions[i], "light direction"), y.data());
        coefficients.noalias() += y * rgb.row(Eigen::Index(i));
    }
    return coefficients;
}

Eigen::Vector3d equirectangular_direction(int row, int column, int height, int width) {
    return latlong::pixel_direction(row, column, height, width);
}

double equirectangular_solid_angle(int row, int height, int width) {
    return latlong::pixel_solid_angle(row, height, width);
}

EnvironmentProjection project_equirectangular(int order, const float* pixels, int height, int width, int channels,
                                              const Progress& progress, int theta_nodes) {
    check_order(order);
    if (height < 1 || width < 1)
        throw ArgumentError("environment image must be at least 1x1, got " + std::to_string(height) + "x" +
                            std::to_string(width));
    if (channels != 3 && channels != 4)
        throw ArgumentError("environment image needs 3 (RGB) or 4 (RGBA) channels, got " + std::to_string(channels));
    if (theta_nodes < 1 || theta_nodes > 64)
        throw ArgumentError("theta_nodes must be between 1 and 64, got " + std::to_string(theta_nodes));
    if (pixels == nullptr) throw ArgumentError("environment image has no pixel data");

    // y_lm = p̄_l|m|(cosθ) sin^|m|θ · T_m(φ), T_0 = 1, T_m = √2 cos mφ,
    // T_−m = √2 sin mφ, so a pixel's integral ∫∫ y_lm sinθ dθ dφ splits into a
    // row factor (θ) times a column factor (φ).
    const int m_count = 2 * order - 1;  // m = −(order−1) .. order−1, stored at m + order − 1

    // Column factors ∫ T_m dφ over each column, in closed form. Written with
    // half-angle products so narrow columns lose no digits to cancellation.
    const double dphi = 2.0 * pi / width;
    std::vector<double> column_factor(std::size_t(width) * m_count);
    for (int c = 0; c < width; ++c) {
        const double phi = latlong::phi_of_x(c + 0.5, width);  // column centre
        double* f = &column_factor[std::size_t(c) * m_count];
        f[order - 1] = dphi;
        for (int m = 1; m < order; ++m) {
            const double chord = 2.0 * std::sin(0.5 * m * dphi) / m;
            f[order - 1 + m] = std::numbers::sqrt2 * std::cos(m * phi) * chord;  // ∫ √2 cos mφ
            f[order - 1 - m] = std::numbers::sqrt2 * std::sin(m * phi) * chord;  // ∫ √2 sin mφ
        }
    }

    // Rows of a low-resolution image span a large θ range over which the
    // integrand (degree up to `order` in θ) oscillates; add nodes in proportion
    // to that phase span so that even a 1-pixel-high image integrates exactly.
    const int nodes = theta_nodes + static_cast<int>(std::ceil(order * pi / height));
    std::vector<double> xi, xi_weight;
    gauss_legendre(nodes, xi, xi_weight);

    EnvironmentProjection result;
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(coefficient_count(order), 3);
    std::vector<double> row_factor(coefficient_count(order));
    std::vector<double> p(coefficient_count(order));
    std::vector<double> row_sum(std::size_t(m_count) * 3);

    for (int r = 0; r < height; ++r) {
        // Row factors ∫ p̄_l|m|(cosθ) sin^(|m|+1)θ dθ over [θ_top, θ_bottom],
        // Gauss–Legendre in θ (smooth there, unlike in cosθ near the poles).
        std::fill(row_factor.begin(), row_factor.end(), 0.0);
        const double theta_top = latlong::theta_of_y(r, height), half = 0.5 * pi / height;
        for (int k = 0; k < nodes; ++k) {
            const double theta = theta_top + half * (1.0 + xi[k]);
            const double s = std::sin(theta);
            legendre_scaled(order, std::cos(theta), p.data());
            double s_power = half * xi_weight[k] * s;  // weight · sin^(m+1)θ
            for (int m = 0; m < order; ++m) {
                for (int l = m; l < order; ++l) row_factor[sh_index(l, m)] += s_power * p[sh_index(l, m)];
                s_power *= s;
            }
        }

        // Σ_c L(r, c) · column factor, per m and channel.
        std::fill(row_sum.begin(), row_sum.end(), 0.0);
        const float* row = pixels + std::size_t(r) * width * channels;
        for (int c = 0; c < width; ++c) {
            const float* px = row + std::size_t(c) * channels;
            double radiance[3];
            bool non_finite = false, negative = false;
            for (int ch = 0; ch < 3; ++ch) {
                const double value = px[ch];
                if (!std::isfinite(value)) {
                    non_finite = true;
                    radiance[ch] = 0.0;
                } else {
                    negative |= value < 0.0;
                    radiance[ch] = value;
                }
            }
            result.non_finite_pixels += non_finite;
            result.negative_pixels += negative;
            const double* f = &column_factor[std::size_t(c) * m_count];
            for (int j = 0; j < m_count; ++j) {
                row_sum[3 * j + 0] += radiance[0] * f[j];
                row_sum[3 * j + 1] += radiance[1] * f[j];
                row_sum[3 * j + 2] += radiance[2] * f[j];
            }
        }

        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m) {
                const double a = row_factor[sh_index(l, std::abs(m))];
                const double* s = &row_sum[3 * std::size_t(m + order - 1)];
                for (int ch = 0; ch < 3; ++ch) sum(sh_index(l, m), ch) += a * s[ch];
            }

        if ((r + 1) % rows_per_report == 0 || r + 1 == height) progress.report(double(r + 1) / height);
    }
    result.coefficients = sum;
    return result;
}

}  // namespace penumbra::sh
