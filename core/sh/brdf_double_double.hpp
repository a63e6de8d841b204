// Double-double arithmetic (an unevaluated sum hi + lo of two doubles, about
// 32 significant digits) for the few sums in the BRDF operators that cancel:
// the Phong moments of the normalized Legendre products lose up to ten digits
// to cancellation (see brdf_moments.cpp), more than a double can spare when
// every entry must keep 1e-8 relative accuracy. Portable (no __float128 or
// 80-bit long double, which MSVC and arm64 lack); requires IEEE round-to-
// nearest and no -ffast-math.
//
// Algorithms: Dekker's and Knuth's error-free transformations, as in
// Hida, Li & Bailey, "Library for double-double and quad-double arithmetic"
// (2007): two_sum, two_prod (FMA), and the "accurate" add and divide.
#pragma once

#include <cmath>

namespace penumbra::sh::detail {

struct DoubleDouble {
    double hi = 0.0;
    double lo = 0.0;

    constexpr DoubleDouble() = default;
    constexpr DoubleDouble(double value) : hi(value), lo(0.0) {}  // NOLINT: implicit on purpose
    constexpr DoubleDouble(double high, double low) : hi(high), lo(low) {}

    explicit operator double() const { return hi + lo; }
};

namespace dd {

// s + e == a + b exactly, for any a, b (Knuth).
inline DoubleDouble two_sum(double a, double b) {
    const double s = a + b;
    const double v = s - a;
    const double e = (a - (s - v)) + (b - v);
    return {s, e};
}

// Same, but requires |a| >= |b| (Dekker).
inline DoubleDouble quick_two_sum(double a, double b) {
    const double s = a + b;
    return {s, b - (s - a)};
}

// p + e == a * b exactly (the FMA computes the rounding error of a * b).
inline DoubleDouble two_prod(double a, double b) {
    const double p = a * b;
    return {p, std::fma(a, b, -p)};
}

}  // namespace dd

inline DoubleDouble operator+(const DoubleDouble& a, const DoubleDouble& b) {
    DoubleDouble s = dd::two_sum(a.hi, b.hi);
    const DoubleDouble t = dd::two_sum(a.lo, b.lo);
    s.lo += t.hi;
    s = dd::quick_two_sum(s.hi, s.lo);
    s.lo += t.lo;
    return dd::quick_two_sum(s.hi, s.lo);
}

inline DoubleDouble operator-(const DoubleDouble& a) { return {-a.hi, -a.lo}; }

inline DoubleDouble operator-(const DoubleDouble& a, const DoubleDouble& b) { return a + (-b); }

inline DoubleDouble operator*(const DoubleDouble& a, const DoubleDouble& b) {
    DoubleDouble p = dd::two_prod(a.hi, b.hi);
    p.lo += a.hi * b.lo + a.lo * b.hi;
    return dd::quick_two_sum(p.hi, p.lo);
}

inline DoubleDouble operator/(const DoubleDouble& a, const DoubleDouble& b) {
    // Three rounds of long division, each correcting the remainder.
    const double q1 = a.hi / b.hi;
    DoubleDouble r = a - b * DoubleDouble(q1);
    const double q2 = r.hi / b.hi;
    r = r - b * DoubleDouble(q2);
    const double q3 = r.hi / b.hi;
    const DoubleDouble q = dd::quick_two_sum(q1, q2);
    return q + DoubleDouble(q3);
}

inline DoubleDouble& operator+=(DoubleDouble& a, const DoubleDouble& b) { return a = a + b; }

}  // namespace penumbra::sh::detail
