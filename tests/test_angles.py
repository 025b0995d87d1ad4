"""odomkit.angles against independent truth: exact rational arithmetic for wrapping and
for the series truncation bounds, mpmath at 50 digits for the sin(u)/u family."""

from __future__ import annotations

import math
import subprocess
import sys
from fractions import Fraction

import mpmath
import numpy as np
import pytest

from odomkit import angles
from odomkit.angles import (
    SERIES_BELOW,
    SHORT_BELOW,
    TWO_PI,
    sin_cos_sinc,
    sin_cos_sinc_series,
    sinc,
    sinc_derivative,
    sinc_derivative_scalar,
    sinc_half,
    sinc_half_derivative,
    sinc_half_pair,
    sinc_pair,
    unwrap_angle,
    wrap_angle,
)

mpmath.mp.dps = 50

EPS = np.finfo(float).eps
REL = 1e-15  # about 4.5 ulp


# ------------------------------------------------------------------------------ wrapping

def _exact_wrap(theta: float) -> float:
    """θ − 2π·⌊(θ + π)/2π⌋ in exact rational arithmetic, 2π = TWO_PI (the float)."""
    t, two_pi = Fraction(theta), Fraction(TWO_PI)
    k = math.floor((t + two_pi / 2) / two_pi)
    return float(t - k * two_pi)


SPECIAL = [0.0, -0.0, math.pi, -math.pi, 3 * math.pi, -3 * math.pi, 5 * math.pi, -5 * math.pi,
           TWO_PI, -TWO_PI, np.nextafter(math.pi, 0.0), np.nextafter(math.pi, 4.0),
           np.nextafter(-math.pi, 0.0), np.nextafter(-math.pi, -4.0), 1e-300, -1e-300, 7.0, -7.0,
           1e6 + 0.5, -1e6 - 0.5, 1e15, -1e15, 1e300, -1e300, 5e-324]


@pytest.mark.parametrize("theta", SPECIAL)
def test_wrap_angle_is_the_exact_floor_convention(theta):
    w = float(wrap_angle(theta))
    assert -math.pi <= w < math.pi
    # the wrapping is exact: not merely close to the rational result, equal to it
    assert w == _exact_wrap(theta)


def test_wrap_angle_endpoints_and_odd_multiples():
    odd = np.array([-5, -3, -1, 1, 3, 5]) * math.pi
    assert np.all(wrap_angle(odd) == -math.pi)  # [−π, π): +π and every odd multiple -> −π
    assert float(wrap_angle(-math.pi)) == -math.pi


def test_wrap_angle_arrays_keep_shape_and_match_exact_values():
    rng = np.random.default_rng(0)
    theta = np.concatenate([rng.uniform(-50, 50, 500), rng.standard_normal(200) * 1e8])
    w = wrap_angle(theta.reshape(35, 20))
    assert w.shape == (35, 20)
    w = w.ravel()
    assert np.all((w >= -math.pi) & (w < math.pi))
    assert all(wi == _exact_wrap(ti) for wi, ti in zip(w, theta, strict=True))


def test_wrap_angle_nan_and_inf_give_nan():
    with np.errstate(invalid="ignore"):
        assert np.all(np.isnan(wrap_angle([np.nan, np.inf, -np.inf])))


def test_unwrap_angle_round_trip():
    rng = np.random.default_rng(1)
    theta = 2.0 + np.cumsum(rng.uniform(-3.0, 3.0, 2000))  # steps below π: recoverable
    back = unwrap_angle(wrap_angle(theta))
    shift = back - theta
    k = np.round(shift / TWO_PI)
    assert np.all(k == k[0])  # one multiple of 2π for the whole track
    np.testing.assert_allclose(shift, k[0] * TWO_PI, rtol=0, atol=1e-10)
    steps = np.diff(back)
    assert np.all((steps >= -math.pi) & (steps < math.pi))
    np.testing.assert_allclose(back, np.unwrap(wrap_angle(theta)), rtol=0, atol=1e-12)


def test_unwrap_angle_along_an_axis_and_the_pi_convention():
    theta = np.array([[0.0, 3.0, -3.0, -2.0], [0.0, math.pi, 0.0, 0.5]])
    out = unwrap_angle(theta, axis=1)
    np.testing.assert_allclose(out[0], [0.0, 3.0, TWO_PI - 3.0, TWO_PI - 2.0], atol=1e-15)
    # a step of exactly +π becomes −π (the wrap_angle convention; np.unwrap keeps +π),
    # and one of exactly −π stays
    np.testing.assert_array_equal(out[1], [0.0, -math.pi, -TWO_PI, 0.5 - TWO_PI])
    np.testing.assert_array_equal(unwrap_angle(theta.T, axis=0), out.T)


# ------------------------------------------------------------- series truncation bounds

def _omitted(kind: str, n: int, u: Fraction) -> Fraction:
    """First omitted term of n terms, relative to the function's size at u (a bound for
    the alternating, decreasing tail); exact."""
    k = n  # first omitted index
    if kind == "sinc":
        return u ** (2 * k) / math.factorial(2 * k + 1) / Fraction(math.sin(float(u)) / float(u) * 0.999)
    if kind == "cos":
        return u ** (2 * k) / math.factorial(2 * k) / Fraction(math.cos(float(u)) * 0.999)
    # sinc′ starts at −u/3 and |sinc′(u)| >= 0.9·u/3 for |u| <= 1
    return 2 * (k + 1) * u ** (2 * k + 1) / math.factorial(2 * k + 3) / (Fraction(9, 10) * u / 3)


@pytest.mark.parametrize("kind", ["sinc", "cos", "dsinc"])
@pytest.mark.parametrize("limit,terms", [(SHORT_BELOW, angles.SHORT_TERMS),
                                         (SERIES_BELOW, angles.SERIES_TERMS)])
def test_series_truncation_is_far_below_rounding(kind, limit, terms):
    """The documented reason for the thresholds: the first omitted term, at the limit, is
    under ε/100 of the value (the sinc′ table holds k = 1 … n, so it omits k = n + 1)."""
    bound = _omitted(kind, terms, Fraction(limit))
    assert bound < Fraction(EPS) / 100


def test_coefficients_are_the_rounded_exact_rationals():
    for k in range(angles.SERIES_TERMS):
        a = Fraction((-1) ** k, math.factorial(2 * k + 1))
        assert angles.SINC_COEFFS[k] == float(a)
        assert angles.COS_COEFFS[k] == float(a * (2 * k + 1))
        assert angles.DSINC_COEFFS[k] == float(Fraction((-1) ** (k + 1) * (2 * k + 2),
                                                        math.factorial(2 * k + 3)))


# ---------------------------------------------------------------- sin(u)/u against mpmath

def _grid() -> np.ndarray:
    base = np.logspace(-12, 1, 600)
    edges = []
    for t in (SHORT_BELOW, SERIES_BELOW):
        edges += [np.nextafter(t, 0.0), t, np.nextafter(t, 2.0), t * (1 - 1e-9), t * (1 + 1e-9)]
    u = np.concatenate([base, edges, [math.pi, 3.0, 4.0, 5.0]])
    return np.concatenate([u, -u, [0.0]])


def _ref(u: float) -> tuple[float, float, float, float]:
    """sinc, sinc′, sin, cos at the float u, to 50 digits, then rounded."""
    if u == 0.0:
        return 1.0, 0.0, 0.0, 1.0
    x = mpmath.mpf(u)
    s, c = mpmath.sin(x), mpmath.cos(x)
    return float(s / x), float((x * c - s) / x**2), float(s), float(c)


U = _grid()
REF = np.array([_ref(float(u)) for u in U])


def _assert_rel(got: np.ndarray, want: np.ndarray, u: np.ndarray, what: str) -> None:
    """|got − want| <= REL·|want|; where the function crosses zero (sinc′ near
    |u| = 4.4934) relative accuracy is impossible in u and the bound is REL times the
    size of the terms that cancel, (|u cos u| + |sin u|)/u²."""
    scale = np.abs(want)
    if what == "dsinc":
        near_zero = (np.abs(u) > 4.2) & (np.abs(u) < 4.8)
        terms = (np.abs(u * np.cos(u)) + np.abs(np.sin(u))) / np.where(u == 0, 1.0, u * u)
        scale = np.where(near_zero, terms, scale)
    err = np.abs(got - want)
    bad = err > REL * scale
    assert not bad.any(), (what, u[bad][:5], (err / np.where(scale > 0, scale, 1))[bad][:5])


def test_sinc_and_derivative_against_mpmath():
    _assert_rel(sinc(U), REF[:, 0], U, "sinc")
    _assert_rel(sinc_derivative(U), REF[:, 1], U, "dsinc")
    f, df = sinc_pair(U)
    np.testing.assert_array_equal(f, sinc(U))
    np.testing.assert_array_equal(df, sinc_derivative(U))
    assert sinc(0.0) == 1.0 and sinc_derivative(0.0) == 0.0


def test_half_angle_forms_against_mpmath():
    dtheta = 2.0 * U  # exact: u = Δθ/2
    _assert_rel(sinc_half(dtheta), REF[:, 0], U, "sinc")
    _assert_rel(sinc_half_derivative(dtheta), 0.5 * REF[:, 1], U, "dsinc")
    f, df = sinc_half_pair(dtheta.reshape(-1, 1))
    assert f.shape == df.shape == (dtheta.size, 1)
    np.testing.assert_array_equal(f.ravel(), sinc_half(dtheta))
    np.testing.assert_array_equal(df.ravel(), sinc_half_derivative(dtheta))


def test_nan_propagates():
    f, df = sinc_pair(np.array([np.nan, 0.1]))
    assert np.isnan(f[0]) and np.isnan(df[0]) and f[1] == sinc(0.1)


# ------------------------------------------------------------------ scalar (numba) forms

def _scalar_table(fns) -> np.ndarray:
    sin_cos_sinc_fn, dsinc_fn = fns
    rows = []
    for u in U:
        s, c, f = sin_cos_sinc_fn(float(u))
        rows.append((f, dsinc_fn(float(u), s, c), s, c))
    return np.array(rows)


def test_scalar_versions_against_mpmath_and_the_array_versions():
    got = _scalar_table((sin_cos_sinc, sinc_derivative_scalar))
    _assert_rel(got[:, 0], REF[:, 0], U, "sinc")
    _assert_rel(got[:, 1], REF[:, 1], U, "dsinc")
    _assert_rel(got[:, 2], REF[:, 2], U, "sin")
    _assert_rel(got[:, 3], REF[:, 3], U, "cos")
    # same tables, threshold and operation order: the same bits as numpy in the series
    series = np.abs(U) < SERIES_BELOW
    np.testing.assert_array_equal(got[series, 0], sinc(U)[series])
    np.testing.assert_array_equal(got[series, 1], sinc_derivative(U)[series])
    # the branch-free full series agrees with the dispatcher to an ulp or so below the limit
    for u in U[series]:
        np.testing.assert_allclose(sin_cos_sinc_series(float(u)), sin_cos_sinc(float(u)),
                                   rtol=4 * EPS, atol=0)


def test_numba_scalar_versions_give_the_python_values():
    pytest.importorskip("numba")
    from odomkit import jit

    fns = (jit.njit(angles.sin_cos_sinc), jit.njit(angles.sinc_derivative_scalar))
    got = _scalar_table(fns)
    want = _scalar_table((sin_cos_sinc, sinc_derivative_scalar))
    series = np.abs(U) < SERIES_BELOW
    np.testing.assert_array_equal(got[series], want[series])  # no FMA contraction by default
    np.testing.assert_array_equal(got[series, 0], sinc(U)[series])  # and so numpy's bits
    np.testing.assert_array_equal(got[series, 1], sinc_derivative(U)[series])
    np.testing.assert_allclose(got, want, rtol=2 * EPS, atol=0)
    series_fn = jit.njit(angles.sin_cos_sinc_series)
    for u in U[series]:
        assert series_fn(float(u)) == sin_cos_sinc_series(float(u))


def test_branch_free_short_series_give_the_dispatchers_bits_below_short_below():
    """sin_cos_sinc_short / sinc_derivative_short are what the vectorised kernel lanes
    use where every angle is below SHORT_BELOW: there they must be the dispatchers' bits
    (which the tests above check against mpmath), in Python and compiled alike."""
    u = np.concatenate([np.random.default_rng(5).uniform(-SHORT_BELOW, SHORT_BELOW, 2000),
                        [0.0, -0.0, 1e-300, np.nextafter(SHORT_BELOW, 0.0)]])
    fns = [(angles.sin_cos_sinc_short, angles.sinc_derivative_short)]
    try:
        from odomkit import jit

        fns.append((jit.njit(angles.sin_cos_sinc_short), jit.njit(angles.sinc_derivative_short)))
    except ImportError:  # numba is optional
        pass
    for trio, deriv in fns:
        for x in u.tolist():
            assert trio(x) == sin_cos_sinc(x)
            assert deriv(x) == sinc_derivative_scalar(x, 0.0, 0.0)


def test_angles_does_not_import_numba():
    code = "import sys, odomkit.angles; assert 'numba' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)
