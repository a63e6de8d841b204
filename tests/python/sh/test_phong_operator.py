"""_penumbra.sh.phong_operator against an exact reference built here.

The reference shares nothing with the C++ closed form: the Legendre
polynomials come from Rodrigues' formula in exact rational arithmetic, the
exponent is taken as the exact rational value of the double, and
(α+1)∫_0^1 μ^α Q(μ) dμ = Σ_k c_k (α+1)/(α+k+1) is summed exactly, so no
cancellation can hide in the reference; only the final square roots and π are
evaluated, with mpmath at 50 digits. The reference itself is checked against
mpmath.quad of associated Legendre functions from their recurrence.
"""

import functools
import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest

import _penumbra

mpmath.mp.dps = 50
ORDER = 8


def poly_mul(a, b):
    out = [Fraction(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return out


def poly_derivative(a, times):
    for _ in range(times):
        a = [k * c for k, c in enumerate(a)][1:] or [Fraction(0)]
    return a


@functools.lru_cache(maxsize=None)
def legendre_derivative(l, m):
    """d^m/dμ^m P_l(μ), P_l = 1/(2^l l!) d^l/dμ^l (μ²−1)^l (Rodrigues)."""
    base = [Fraction(1)]
    for _ in range(l):
        base = poly_mul(base, [Fraction(-1), Fraction(0), Fraction(1)])
    scale = Fraction(1, 2**l * math.factorial(l))
    return tuple(scale * c for c in poly_derivative(base, l + m))


def reference_entry(l, lp, m, alpha):
    """T[l'm, lm] = (α+1)/(2π) N N' ∫_0^1 μ^α (1−μ²)^m P_l^(m) P_l'^(m) dμ."""
    sine_power = [Fraction(1)]
    for _ in range(m):
        sine_power = poly_mul(sine_power, [Fraction(1), Fraction(0), Fraction(-1)])
    q = poly_mul(poly_mul(legendre_derivative(l, m), legendre_derivative(lp, m)), sine_power)
    a = Fraction(alpha)  # exact value of the double
    moment = sum(c * (a + 1) / (a + k + 1) for k, c in enumerate(q))
    norm2 = Fraction((2 * l + 1) * (2 * lp + 1), 4) * Fraction(
        math.factorial(l - m) * math.factorial(lp - m), math.factorial(l + m) * math.factorial(lp + m))
    to_mpf = lambda f: mpmath.mpf(f.numerator) / f.denominator
    return to_mpf(moment) * mpmath.sqrt(to_mpf(norm2)) / (2 * mpmath.pi)


def index(l, m):
    return l * (l + 1) + m


def worst_relative_error(order, alpha):
    t = _penumbra.sh.phong_operator(order, alpha)
    worst = 0.0
    for m in range(order):
        for l in range(m, order):
            for lp in range(l, order):
                ref = reference_entry(l, lp, m, alpha)
                assert ref != 0, (l, lp, m)
                for sm in {m, -m}:
                    for i, j in ((index(l, sm), index(lp, sm)), (index(lp, sm), index(l, sm))):
                        worst = max(worst, float(abs((mpmath.mpf(t[i, j]) - ref) / ref)))
    return worst


def associated_legendre_by_recurrence(l, m, mu):
    """P_l^m(μ) without Condon–Shortley phase, by the three-term recurrence
    (l−m) P_l^m = (2l−1) μ P_{l−1}^m − (l+m−1) P_{l−2}^m in mpmath."""
    previous, current = mpmath.mpf(0), mpmath.fac2(2 * m - 1) * (1 - mu * mu) ** (mpmath.mpf(m) / 2)
    for n in range(m + 1, l + 1):
        previous, current = current, ((2 * n - 1) * mu * current - (n + m - 1) * previous) / (n - m)
    return current


def test_reference_agrees_with_mpmath_quadrature():
    alpha = 2.5
    for m, l, lp in [(0, 0, 0), (0, 2, 5), (1, 1, 4), (2, 3, 3), (3, 3, 7), (7, 7, 7)]:
        n2 = mpmath.mpf((2 * l + 1) * (2 * lp + 1)) / 4 * mpmath.factorial(l - m) * mpmath.factorial(lp - m) / (
            mpmath.factorial(l + m) * mpmath.factorial(lp + m))
        integral = mpmath.quad(lambda mu: mu**alpha * associated_legendre_by_recurrence(l, m, mu)
                               * associated_legendre_by_recurrence(lp, m, mu), [0, 1])
        quad = (alpha + 1) / (2 * mpmath.pi) * mpmath.sqrt(n2) * integral
        assert abs(quad - reference_entry(l, lp, m, alpha)) < mpmath.mpf(10) ** -30 * abs(quad)


@pytest.mark.parametrize("alpha", [1e6, 2.5, 1e-12, 12345.678])
def test_phong_operator_keeps_relative_accuracy_of_every_nonzero_entry(alpha):
    assert worst_relative_error(ORDER, alpha) < 1e-8


@pytest.mark.parametrize("alpha", [0.0, 1.0, 2.0, 8.0])
def test_entries_that_vanish_at_integer_alpha_are_exactly_zero(alpha):
    # E.g. ∫_0^1 μ^α P_l dμ = 0 for l = α+2, α+4, …; at α = 1 (diffuse) 252 of
    # the 816 distinct order-16 entries vanish. Rounding noise would show.
    t = _penumbra.sh.phong_operator(16, alpha)
    vanishing = 0
    for m in range(16):
        for l in range(m, 16):
            for lp in range(l, 16):
                if reference_entry(l, lp, m, alpha) == 0:
                    vanishing += 1
                    assert t[index(l, m), index(lp, m)] == 0.0, (l, lp, m)
                else:
                    assert t[index(l, m), index(lp, m)] != 0.0, (l, lp, m)
    assert vanishing > 0


@pytest.mark.parametrize("alpha", [0.0, 1e-12, 2.5, 1e6])
def test_phong_operator_is_exactly_zero_between_different_m(alpha):
    t = _penumbra.sh.phong_operator(ORDER, alpha)
    assert t.shape == (ORDER**2, ORDER**2) and t.dtype == np.float64
    for l in range(ORDER):
        for m in range(-l, l + 1):
            for lp in range(ORDER):
                for mp in range(-lp, lp + 1):
                    if mp != m:
                        assert t[index(l, m), index(lp, mp)] == 0.0


def test_phong_operator_approaches_yz_yz_transposed_as_alpha_grows():
    # y_l0(z) = sqrt((2l+1)/(4π)), y_lm(z) = 0 for m ≠ 0.
    yz = np.zeros(ORDER**2)
    for l in range(ORDER):
        yz[index(l, 0)] = math.sqrt((2 * l + 1) / (4 * math.pi))
    limit = np.outer(yz, yz)
    error_1e6 = np.abs(_penumbra.sh.phong_operator(ORDER, 1e6) - limit).max()
    error_1e9 = np.abs(_penumbra.sh.phong_operator(ORDER, 1e9) - limit).max()
    assert error_1e6 < 1e-4
    assert error_1e9 * 1e9 == pytest.approx(error_1e6 * 1e6, rel=1e-2)  # O(1/α)
    np.testing.assert_allclose(_penumbra.sh.phong_operator(ORDER, math.inf), limit, rtol=1e-15, atol=0)


def test_diffuse_operator_is_phong_at_alpha_1_and_shades_unit_radiance_to_one():
    t = _penumbra.sh.diffuse_operator(ORDER)
    np.testing.assert_array_equal(t, _penumbra.sh.phong_operator(ORDER, 1.0))
    unit = np.zeros(ORDER**2)
    unit[0] = math.sqrt(4 * math.pi)
    assert unit @ t @ unit == pytest.approx(1.0, rel=1e-15)


def test_kernel_operator_reproduces_the_linear_diffuse_kernel():
    t = _penumbra.sh.kernel_operator(ORDER, np.array([0.0, 1.0 / math.pi]))
    np.testing.assert_allclose(t, _penumbra.sh.diffuse_operator(ORDER), rtol=0, atol=1e-14)
    dense = _penumbra.sh.kernel_operator(ORDER, [(8 + 1) / (2 * math.pi) * x**8 for x in np.linspace(0, 1, 2001)])
    np.testing.assert_allclose(dense, _penumbra.sh.phong_operator(ORDER, 8.0), rtol=0, atol=1e-5)


@pytest.mark.parametrize("call", [
    lambda: _penumbra.sh.phong_operator(0, 1.0),
    lambda: _penumbra.sh.phong_operator(17, 1.0),
    lambda: _penumbra.sh.phong_operator(4, -0.5),
    lambda: _penumbra.sh.phong_operator(4, math.nan),
    lambda: _penumbra.sh.diffuse_operator(0),
    lambda: _penumbra.sh.kernel_operator(4, [1.0]),
    lambda: _penumbra.sh.kernel_operator(4, [1.0, math.inf]),
    lambda: _penumbra.sh.kernel_operator(4, np.ones((2, 2))),
])
def test_invalid_arguments_raise_value_error(call):
    with pytest.raises(ValueError):
        call()
