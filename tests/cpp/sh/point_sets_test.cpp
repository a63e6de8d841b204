// Quadratures of sh/point_sets.hpp: Gauss–Legendre nodes against the exact
// moments of [−1, 1], the Fibonacci sphere's unit points and weights.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

TEST(PointSets, gauss_legendre_integrates_polynomials_up_to_degree_2n_minus_1) {
    for (int n : {1, 2, 5, 16, 33}) {
        std::vector<double> x, w;
        gauss_legendre(n, x, w);
        for (int k = 0; k <= 2 * n - 1; ++k) {
            double sum = 0.0;
            for (int i = 0; i < n; ++i) sum += w[i] * std::pow(x[i], k);
            EXPECT_NEAR(sum, (k % 2) ? 0.0 : 2.0 / (k + 1.0), 1e-14) << "n=" << n << " k=" << k;
        }
    }
}

TEST(PointSets, fibonacci_points_are_unit_with_weights_summing_to_4pi) {
    const PointSet set = fibonacci_sphere(1001);
    double total = 0.0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < set.directions.size(); ++i) {
        EXPECT_NEAR(set.directions[i].norm(), 1.0, 1e-15);
        total += set.weights[i];
        mean += set.directions[i];
    }
    EXPECT_NEAR(total, 4.0 * pi, 1e-12);
    EXPECT_LT(mean.norm() / 1001.0, 1e-3);  // evenly spread: no net direction
    EXPECT_THROW(fibonacci_sphere(0), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
