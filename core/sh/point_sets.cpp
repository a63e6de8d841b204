#include "sh/point_sets.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"

namespace penumbra::sh {

PointSet fibonacci_sphere(int n) {
    if (n < 1) throw ArgumentError("fibonacci_sphere needs at least 1 point, got " + std::to_string(n));
    // Golden angle 2π(1 − 1/ϕ) = π(3 − √5).
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    PointSet set;
    set.directions.reserve(n);
    set.weights.assign(n, 4.0 * std::numbers::pi / n);
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        // Reduce the angle before cos/sin so large i keep full precision.
        const double phi = std::fmod(golden_angle * i, 2.0 * std::numbers::pi);
        set.directions.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return set;
}

namespace {

// P_n(x) and P_n'(x) by the three-term recurrence (n >= 1).
void legendre_and_derivative(int n, double x, double& value, double& derivative) {
    double previous = 1.0, current = x;
    for (int j = 2; j <= n; ++j) {
        const double next = ((2.0 * j - 1.0) * x * current - (j - 1.0) * previous) / j;
        previous = current;
        current = next;
    }
    value = current;
    derivative = n * (x * current - previous) / (x * x - 1.0);
}

}  // namespace

void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
    if (n < 1) throw ArgumentError("gauss_legendre needs at least 1 node, got " + std::to_string(n));
    nodes.assign(n, 0.0);
    weights.assign(n, 2.0);  // n == 1: the midpoint rule
    if (n == 1) return;
    // Newton on P_n from Tricomi's initial guess; the roots are symmetric.
    for (int k = 0; k < n / 2; ++k) {
        double x = std::cos(std::numbers::pi * (k + 0.75) / (n + 0.5));
        double value = 0.0, derivative = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            legendre_and_derivative(n, x, value, derivative);
            const double step = value / derivative;
            x -= step;
            if (std::abs(step) < 1e-16) break;
        }
        legendre_and_derivative(n, x, value, derivative);
        nodes[k] = x;
        nodes[n - 1 - k] = -x;
        weights[k] = weights[n - 1 - k] = 2.0 / ((1.0 - x * x) * derivative * derivative);
    }
    if (n % 2 == 1) {
        double value = 0.0, derivative = 0.0;
        legendre_and_derivative(n, 0.0, value, derivative);
        weights[n / 2] = 2.0 / (derivative * derivative);
    }
}

PointSet gauss_product_sphere(int n_theta, int n_phi) {
    if (n_theta < 1 || n_phi < 1)
        throw ArgumentError("gauss_product_sphere needs n_theta, n_phi >= 1");
    std::vector<double> mu, w;
    gauss_legendre(n_theta, mu, w);
    PointSet set;
    set.directions.reserve(std::size_t(n_theta) * n_phi);
    set.weights.reserve(std::size_t(n_theta) * n_phi);
    const double dphi = 2.0 * std::numbers::pi / n_phi;
    for (int k = 0; k < n_theta; ++k) {
        const double r = std::sqrt(std::max(0.0, 1.0 - mu[k] * mu[k]));
        for (int j = 0; j < n_phi; ++j) {
            const double phi = (j + 0.5) * dphi;
            set.directions.emplace_back(r * std::cos(phi), r * std::sin(phi), mu[k]);
            set.weights.push_back(w[k] * dphi);
        }
    }
    return set;
}

PointSet exact_sphere_quadrature(int degree) {
    if (degree < 0) throw ArgumentError("quadrature degree must be >= 0");
    return gauss_product_sphere(degree / 2 + 1, degree + 1);
}

}  // namespace penumbra::sh
