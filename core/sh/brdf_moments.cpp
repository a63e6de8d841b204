// Phong operator entries without cancellation trouble (see brdf_operator.hpp
// for the derivation of the structure and the closed form).
//
// The entry is (α+1)/(2π) N N' ∫_0^1 μ^α Q(μ) dμ with the polynomial
//   Q(μ) = (1−μ²)^m P_l^(m)(μ) P_l'^(m)(μ)        (degree l + l' ≤ 30),
// P_l^(m) the m-th derivative of the Legendre polynomial, and
// N = sqrt((2l+1)/2 · (l−m)!/(l+m)!). Two exact expansions of Q give two sums:
//
//  * powers of μ:      (α+1)∫μ^α μ^k dμ       = (α+1)/(α+k+1);
//  * powers of u=1−μ:  (α+1)∫μ^α (1−μ)^j dμ   = (α+1) B(α+1, j+1)
//                                              = j! / ∏_{i=2}^{j+1} (α+i).
//
// Both expansions have sign-regular coefficients (every factor is a polynomial
// in −μ² resp. −u with positive coefficients), so the coefficients themselves
// are computed without cancellation; the sums then alternate. Their condition
// Σ|terms|/|Σ terms| was measured (all order-16 entries, exact rationals) as
//   powers of u: ≈ 1 + O(l²/α) for large α (1.0005 at α = 1e6, 98 at α = 100)
//                but up to 5e15 near α = 0;
//   powers of μ: ≤ 1e10 near α = 0, but growing like α^m for m > 0: useless
//                for large α.
// The better of the two never exceeded 2e10 (l = l' = 15, α ≈ 2.5 … 20). So
// the u-sum is used whenever it is well conditioned, else the better of the
// two; both are accumulated in double-double, which leaves ≲ 1e-20 relative
// error at that condition (a double would leave 1e-6).
//
// Tiny α needs one more step: for l ≠ l' with l + l' even,
// Σ c_k/(k+1) = ½∫_{−1}^1 Q dμ = 0 (orthogonality), so the entry is O(α) and
// is computed as
//   (α+1) Σ c_k [1/(α+k+1) − 1/(k+1)] = −α(α+1) Σ c_k / ((k+1)(α+k+1)),
// which keeps its relative accuracy however small α is (tested at 1e-25;
// the unfactored sum would cancel to nothing) and is exactly 0 at α = 0.
#include "sh/brdf_moments.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "sh/brdf_double_double.hpp"

namespace penumbra::sh::detail {
namespace {

using Polynomial = std::vector<DoubleDouble>;  // coefficient k multiplies x^k

// Exact for the arguments used here (results < 2^53).
double binomial(int n, int k) {
    double result = 1.0;
    for (int i = 1; i <= k; ++i)
        result = result * (n - k + i) / i;
    return std::round(result);
}

double falling_factorial(int n, int k) {  // n! / (n−k)!
    double result = 1.0;
    for (int i = 0; i < k; ++i)
        result *= n - i;
    return result;
}

// sign · a · b · 2^exponent, exact: a, b are integers below 2^53, so their
// product fits the 106-bit significand of a double-double.
DoubleDouble exact_term(int sign, double a, double b, int exponent) {
    const DoubleDouble p = dd::two_prod(a, b);
    return {sign * std::ldexp(p.hi, exponent), sign * std::ldexp(p.lo, exponent)};
}

Polynomial multiply(const Polynomial& a, const Polynomial& b) {
    Polynomial product(a.size() + b.size() - 1);
    for (std::size_t i = 0; i < a.size(); ++i)
        for (std::size_t j = 0; j < b.size(); ++j)
            product[i + j] += a[i] * b[j];
    return product;
}

// P_l^(m)(μ) in powers of μ, from P_l(μ) = 2^−l Σ_k (−1)^k C(l,k) C(2l−2k,l) μ^(l−2k).
Polynomial legendre_derivative_in_mu(int l, int m) {
    Polynomial p(l - m + 1);
    for (int k = 0; 2 * k <= l - m; ++k) {
        const int power = l - 2 * k;
        p[power - m] = exact_term(k % 2 ? -1 : 1, binomial(l, k) * binomial(2 * l - 2 * k, l),
                                  falling_factorial(power, m), -l);
    }
    return p;
}

// P_l^(m)(1−u) in powers of u, from P_l(1−u) = Σ_k (−1)^k C(l,k) C(l+k,k) (u/2)^k
// and d/dμ = −d/du.
Polynomial legendre_derivative_in_u(int l, int m) {
    Polynomial p(l - m + 1);
    for (int k = m; k <= l; ++k)
        p[k - m] = exact_term((m + k) % 2 ? -1 : 1, binomial(l, k) * binomial(l + k, k),
                              falling_factorial(k, m), -k);
    return p;
}

// (1−μ²)^m in powers of μ.
Polynomial sine_power_in_mu(int m) {
    Polynomial p(2 * m + 1);
    for (int i = 0; i <= m; ++i)
        p[2 * i] = DoubleDouble(i % 2 ? -binomial(m, i) : binomial(m, i));
    return p;
}

// (1−μ²)^m = u^m (2−u)^m in powers of u.
Polynomial sine_power_in_u(int m) {
    Polynomial p(2 * m + 1);
    for (int i = 0; i <= m; ++i)
        p[m + i] = DoubleDouble(std::ldexp(i % 2 ? -binomial(m, i) : binomial(m, i), m - i));
    return p;
}

struct Sum {
    DoubleDouble total;
    double magnitude = 0.0;  // Σ|terms|
    double factor = 1.0;     // the entry is factor · total

    void add(const DoubleDouble& term) {
        total += term;
        magnitude += std::abs(term.hi);
    }
    double condition() const {
        return total.hi == 0.0 ? std::numeric_limits<double>::infinity()
                               : magnitude / std::abs(total.hi);
    }
};

// Σ_j q_j (α+1) B(α+1, j+1), the running product never overflows (each
// factor j/(α+j+1) < 1) and decays fast for large α.
Sum sum_in_u(const Polynomial& q, double alpha) {
    Sum sum;
    DoubleDouble beta(1.0);
    for (std::size_t j = 0; j < q.size(); ++j) {
        if (j > 0)
            beta = beta * DoubleDouble(double(j)) / dd::two_sum(alpha, double(j) + 1.0);
        sum.add(q[j] * beta);
    }
    return sum;
}

// Σ_k c_k (α+1)/(α+k+1), or, when Σ c_k/(k+1) vanishes by orthogonality,
// the α-factored form α · (−Σ_k c_k (α+1)/((k+1)(α+k+1))); α multiplies the
// rounded sum at the end, so even α = 1e−300 loses nothing to subnormals.
Sum sum_in_mu(const Polynomial& c, double alpha, bool vanishes_at_zero) {
    Sum sum;
    if (vanishes_at_zero)
        sum.factor = alpha;
    const DoubleDouble alpha_plus_one = dd::two_sum(alpha, 1.0);
    for (std::size_t k = 0; k < c.size(); ++k) {
        if (c[k].hi == 0.0)
            continue;
        const DoubleDouble denominator = dd::two_sum(alpha, double(k) + 1.0);
        DoubleDouble weight = alpha_plus_one / denominator;
        if (vanishes_at_zero)
            weight = -weight / DoubleDouble(double(k) + 1.0);
        sum.add(c[k] * weight);
    }
    return sum;
}

// The u-sum is accepted outright below this condition (error ≲ 1e3 · 1e-31).
constexpr double well_conditioned = 1e3;
// An entry below this fraction of Σ|terms| is indistinguishable from zero in
// double-double (≈ 31 terms × a few roundings of 2^−104 each): it is returned
// as exactly 0. This is what happens at the exponents where an entry crosses
// zero, e.g. l = 0 with odd l' ≥ 3 at α = 1 (the diffuse operator).
constexpr double rounding_floor = 1e-28;

}  // namespace

PhongEntry phong_entry(int l, int l_prime, int m, double alpha) {
    const Polynomial q = multiply(multiply(legendre_derivative_in_u(l, m), legendre_derivative_in_u(l_prime, m)),
                                  sine_power_in_u(m));
    Sum best = sum_in_u(q, alpha);
    if (best.condition() > well_conditioned) {
        const Polynomial c = multiply(
            multiply(legendre_derivative_in_mu(l, m), legendre_derivative_in_mu(l_prime, m)), sine_power_in_mu(m));
        const bool vanishes_at_zero = l != l_prime && (l + l_prime) % 2 == 0;
        const Sum in_mu = sum_in_mu(c, alpha, vanishes_at_zero);
        if (in_mu.condition() < best.condition())
            best = in_mu;
    }
    if (best.factor == 0.0 || std::abs(best.total.hi) <= rounding_floor * best.magnitude)
        return {0.0, std::numeric_limits<double>::infinity()};

    // N N' / (2π), N² = (2l+1)/2 · (l−m)!/(l+m)!
    double factorial_ratio = 1.0;
    for (int i = l - m + 1; i <= l + m; ++i)
        factorial_ratio /= i;
    for (int i = l_prime - m + 1; i <= l_prime + m; ++i)
        factorial_ratio /= i;
    const double normalization = std::sqrt((2 * l + 1) * (2 * l_prime + 1) / 4.0 * factorial_ratio);
    return {best.factor * double(best.total) * normalization / (2.0 * std::numbers::pi), best.condition()};
}

}  // namespace penumbra::sh::detail
