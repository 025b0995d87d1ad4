"""Chong–Kleeman closed forms: against quadrature, the printed special cases (eq. 25–28),
the step recursion, and properties (consistency, symmetry, PSD, zero noise)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate as si
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.kinematics import diff_body_jacobian, step_displacement, step_jacobians
from odomkit.noise import ClassicalNoise, WheelNoise
from odomkit.propagate import closed
from odomkit.propagate.closed import (
    INTEGRALS,
    SERIES_BELOW,
    arc_integrals,
    classical_step,
    wheel_arc_cov,
)


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    """Largest entry difference relative to the largest entry of b."""
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


# ---------------------------------------------------------------- the scalar integrals

def _integrand(tau: float, name: str, a: float) -> float:
    """The factors of arc_integrals, written in product form so that quad sees no
    cancellation: cos φ − cos a = 2 sin((a+φ)/2) sin((a−φ)/2), sin a − sin φ =
    2 cos((a+φ)/2) sin((a−φ)/2)."""
    ph = tau * a
    f = {
        "c": np.cos(ph),
        "s": np.sin(ph),
        "p": -2.0 * np.sin((a + ph) / 2) * np.sin((a - ph) / 2) / a,
        "q": 2.0 * np.cos((a + ph) / 2) * np.sin((a - ph) / 2) / a,
    }
    return f[name[0]] * (f[name[1]] if len(name) == 2 else 1.0)


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
@pytest.mark.parametrize("a", [1e-8, 1e-4, 0.05, -0.5, 0.999, 1.001, -2.5, 7.0])
def test_arc_integrals_match_quadrature(a):
    ours = arc_integrals(a)
    for name, value in zip(INTEGRALS, ours, strict=True):
        ref = si.quad(_integrand, 0.0, 1.0, args=(name, a), epsabs=0, epsrel=1e-13)[0]
        assert abs(value - ref) <= 1e-12 * abs(ref), (name, a, value, ref)


def _branch(a, series: bool):
    old = closed.SERIES_BELOW
    closed.SERIES_BELOW = np.inf if series else 0.0
    try:
        return arc_integrals(a)
    finally:
        closed.SERIES_BELOW = old


def test_series_and_closed_forms_agree_around_threshold():
    # Both branches at rounding level where they meet (the series is used just below the
    # threshold, the trigonometric forms just above): 4e-15 is 18 ulps; the closed forms'
    # cancellation error grows as ~20 ulps/a⁴ below, the series' as ~e^a ulps above.
    a = np.linspace(0.9 * SERIES_BELOW, 1.1 * SERIES_BELOW, 61)
    a = np.concatenate([a, -a])
    assert np.max(np.abs(_branch(a, True) / _branch(a, False) - 1.0)) < 4e-15


def test_continuous_across_threshold():
    below = arc_integrals(np.nextafter(SERIES_BELOW, 0.0))
    above = arc_integrals(SERIES_BELOW)
    assert np.max(np.abs(below / above - 1.0)) < 5e-15


def test_closed_forms_alone_would_fail_near_zero():
    # Guards the reason for the series branch: it must be used where cancellation bites.
    a = 1e-3
    assert abs(_branch(a, False)[INTEGRALS.index("pp")] / arc_integrals(a)[INTEGRALS.index("pp")]
               - 1) > 1e-6


# ---------------------------------------------------------------- whole covariance

def _quad_cov(left, right, b, kl, kr, theta0):
    """∫ A Q Aᵀ dτ by quadrature in the world frame; positions along the arc from the
    exact-arc step map (kinematics), not from the closed form."""
    d, a = 0.5 * (left + right), (right - left) / b
    jac = diff_body_jacobian(b)
    q = jac @ np.diag([kl**2 * abs(left), kr**2 * abs(right)]) @ jac.T
    x1, y1 = step_displacement(theta0, d, a, "exact")

    def f(tau):
        x, y = step_displacement(theta0, tau * d, tau * a, "exact")
        th = theta0 + tau * a
        A = np.array([[np.cos(th), -(y1 - y)], [np.sin(th), x1 - x], [0.0, 1.0]])
        return A @ q @ A.T

    return si.quad_vec(f, 0.0, 1.0, epsabs=1e-20, epsrel=1e-12)[0]


@pytest.mark.parametrize("left,right,b,kl,kr,theta0", [
    (3.0, 1.0, 0.4, 0.001, 0.002, 0.0),
    (15.0, 10.0, 0.4, 0.01, 0.02, 0.7),
    (-2.0, 1.0, 0.5, 0.01, 0.02, -2.0),   # one wheel backwards
    (-4.0, -4.2, 0.5, 0.03, 0.01, 1.0),   # reversing, slightly curved (series branch)
    (1.0, 1.0, 0.3, 0.02, 0.01, 0.4),     # straight
    (-0.5, 0.5, 0.3, 0.02, 0.01, 0.4),    # spin
])
def test_wheel_arc_matches_quadrature(left, right, b, kl, kr, theta0):
    ours = wheel_arc_cov(left, right, b, WheelNoise(kl, kr), theta0)
    assert rel_err(ours, _quad_cov(left, right, b, kl, kr, theta0)) < 1e-11


def _printed_eq25(L, R, B, kL, kR, t0):
    """Chong–Kleeman eq. (25) exactly as printed (r from eq. 15, θ_k from eq. 14)."""
    r = B / 2 * (L + R) / (L - R)
    tk = t0 + (R - L) / B
    m1 = kR**2 * abs(R) * L + kL**2 * R * abs(L)
    m0 = kR**2 * abs(R) + kL**2 * abs(L)
    m2 = kR**2 * L**2 * abs(R) + kL**2 * R**2 * abs(L)
    s0, sk, c0, ck = np.sin(t0), np.sin(tk), np.cos(t0), np.cos(tk)
    h = B / (4 * (L - R) ** 3)
    c11 = (-2 * r / (L - R) ** 2 * m1 * (s0 - sk) * ck + (r / B * ck) ** 2 * m0
           - h * (2 * (tk - t0) - np.sin(2 * t0) + np.sin(2 * tk)) * m2)
    c22 = (-2 * r / (L - R) ** 2 * m1 * (ck - c0) * sk + (r / B * sk) ** 2 * m0
           - h * (2 * (tk - t0) + np.sin(2 * t0) - np.sin(2 * tk)) * m2)
    c12 = (-r / (L - R) ** 2 * m1 * (np.cos(2 * tk) - np.cos(t0 + tk))
           + 0.5 * (r / B) ** 2 * np.sin(2 * tk) * m0
           - h * (np.cos(2 * t0) - np.cos(2 * tk)) * m2)
    c13 = m1 * (s0 - sk) / (L - R) ** 2 - r / B**2 * ck * m0
    c23 = m1 * (ck - c0) / (L - R) ** 2 - r / B**2 * sk * m0
    return np.array([[c11, c12, c13], [c12, c22, c23], [c13, c23, m0 / B**2]])


@pytest.mark.parametrize("args", [
    (3.0, 1.0, 0.4, 0.001, 0.002, 0.0), (1.0, 3.0, 0.4, 0.003, 0.001, -0.4),
    (15.0, 10.0, 0.4, 0.01, 0.02, 0.3), (-2.0, 1.0, 0.5, 0.01, 0.02, 0.3),
])
def test_general_arc_matches_printed_eq25(args):
    # Eq. (25) as extracted is right for general arcs (it only fails to evaluate at L = R).
    ours = wheel_arc_cov(*args[:3], WheelNoise(*args[3:5]), args[5])
    assert rel_err(ours, _printed_eq25(*args)) < 1e-9


def _eq26(D, B, kL, kR, t, corrected=True):
    """Chong–Kleeman eq. (26), straight line at heading θ. Printed Cov₂₂ has sin²θ in its
    last term; it must be cos²θ (at θ = 0 it must give eq. 27's D³/(3B²)(k_R² + k_L²))."""
    sp, sm = kR**2 + kL**2, kR**2 - kL**2
    s, c = np.sin(t), np.cos(t)
    last22 = c**2 if corrected else s**2
    c11 = abs(D) * (c**2 * sp / 4 - D / (2 * B) * s * c * sm + D**2 / (3 * B**2) * s**2 * sp)
    c22 = abs(D) * (s**2 * sp / 4 + D / (2 * B) * s * c * sm + D**2 / (3 * B**2) * last22 * sp)
    c12 = abs(D) * ((1 / 8 - D**2 / (6 * B**2)) * np.sin(2 * t) * sp
                    + D / (4 * B) * np.cos(2 * t) * sm)
    c13 = abs(D) * (c * sm / (2 * B) - D / (2 * B**2) * s * sp)
    c23 = abs(D) * (s * sm / (2 * B) + D / (2 * B**2) * c * sp)
    return np.array([[c11, c12, c13], [c12, c22, c23], [c13, c23, abs(D) / B**2 * sp]])


@pytest.mark.parametrize("D,theta", [(2.0, 0.0), (2.0, 0.9), (-3.0, -2.2), (0.7, np.pi / 2)])
def test_straight_limit_matches_eq26_corrected(D, theta):
    ours = wheel_arc_cov(D, D, 0.4, WheelNoise(0.01, 0.02), theta)
    assert rel_err(ours, _eq26(D, 0.4, 0.01, 0.02, theta)) < 1e-13


def test_eq26_as_printed_is_wrong():
    ours = wheel_arc_cov(2.0, 2.0, 0.4, WheelNoise(0.01, 0.02), 0.0)
    printed = _eq26(2.0, 0.4, 0.01, 0.02, 0.0, corrected=False)
    assert abs(printed[1, 1] / ours[1, 1]) < 0.1  # printed gives only the ¼ sin²θ term


def test_straight_at_zero_heading_matches_eq27():
    D, B, kL, kR = 2.5, 0.4, 0.003, 0.002
    sp, sm = kR**2 + kL**2, kR**2 - kL**2
    eq27 = np.array([
        [D / 4 * sp, D**2 / (4 * B) * sm, D / (2 * B) * sm],
        [D**2 / (4 * B) * sm, D**3 / (3 * B**2) * sp, D**2 / (2 * B**2) * sp],
        [D / (2 * B) * sm, D**2 / (2 * B**2) * sp, D / B**2 * sp],
    ])
    assert rel_err(wheel_arc_cov(D, D, B, WheelNoise(kL, kR)), eq27) < 1e-14
    # the paper's remark: corr(y, θ) = 0.866 = √3/2 on a straight line from rest
    cov = wheel_arc_cov(D, D, B, WheelNoise(kL, kR))
    assert cov[1, 2] / np.sqrt(cov[1, 1] * cov[2, 2]) == pytest.approx(np.sqrt(3) / 2, rel=1e-13)


def _eq28(t0, tk, B, kL, kR):
    sp, sm, sg = kR**2 + kL**2, kR**2 - kL**2, np.sign(tk - t0)
    c11 = B / 32 * (2 * (tk - t0) - np.sin(2 * t0) + np.sin(2 * tk)) * sp * sg
    c22 = B / 32 * (2 * (tk - t0) + np.sin(2 * t0) - np.sin(2 * tk)) * sp * sg
    c12 = B / 32 * (np.cos(2 * t0) - np.cos(2 * tk)) * sp * sg
    c13 = sm / 4 * (np.sin(tk) - np.sin(t0)) * sg
    c23 = sm / 4 * (np.cos(t0) - np.cos(tk)) * sg
    return np.array([[c11, c12, c13], [c12, c22, c23], [c13, c23, abs(tk - t0) / (2 * B) * sp]])


@pytest.mark.parametrize("t0,dth", [(0.0, 1.5708), (0.3, -2.0), (-1.0, 7.5), (2.0, 0.2)])
def test_spin_limit_matches_eq28(t0, dth):
    # Eq. (28)'s results hold with L = −(B/2)Δθ, R = +(B/2)Δθ (eq. 14: Δθ = (R − L)/B);
    # the text's substitution "L -> (B/2)(θk − θ0)" has L and R swapped.
    B, kL, kR = 0.4, 0.01, 0.03
    half = 0.5 * B * dth
    ours = wheel_arc_cov(-half, half, B, WheelNoise(kL, kR), t0)
    assert rel_err(ours, _eq28(t0, t0 + dth, B, kL, kR)) < 1e-13
    swapped = wheel_arc_cov(half, -half, B, WheelNoise(kL, kR), t0)  # the text's L, R
    assert rel_err(swapped, _eq28(t0, t0 + dth, B, kL, kR)) > 1e-3


# ---------------------------------------------------------------- against the recursion

def _reference_recursion(left, right, b, noise, theta0, cov0, n):
    """Plain step recursion P <- F P Fᵀ + G Q Gᵀ over n exact-arc steps (test-only)."""
    d, a = 0.5 * (left + right) / n, (right - left) / b / n
    jac = diff_body_jacobian(b)
    q = jac @ np.diag([noise.k_left**2 * abs(left), noise.k_right**2 * abs(right)]) @ jac.T / n
    P = np.array(cov0, dtype=float)
    theta = theta0 + a * np.arange(n)
    F, G = step_jacobians(theta, np.full(n, d), np.full(n, a), "exact")
    for k in range(n):
        P = F[k] @ P @ F[k].T + G[k] @ q @ G[k].T
    return P


@pytest.mark.parametrize("left,right,theta0", [(3.0, 1.0, 0.2), (-1.0, 2.0, -1.0),
                                               (2.0, 2.0, 0.5), (0.4, -0.4, 1.0)])
def test_closed_equals_limit_of_recursion(left, right, theta0):
    b, noise = 0.4, WheelNoise(0.002, 0.005)
    cov0 = np.array([[1e-4, 2e-5, -1e-5], [2e-5, 3e-4, 4e-5], [-1e-5, 4e-5, 2e-4]])
    ours = wheel_arc_cov(left, right, b, noise, theta0, cov0)
    p1 = _reference_recursion(left, right, b, noise, theta0, cov0, 400)
    p2 = _reference_recursion(left, right, b, noise, theta0, cov0, 800)
    # The exact-arc recursion is a midpoint-type rule: error O(1/n²); check the rate,
    # then the Richardson extrapolation.
    e1, e2 = rel_err(p1, ours), rel_err(p2, ours)
    assert e2 < 1e-5
    if e1 > 1e-12:
        assert 3.0 < e1 / e2 < 5.0
    assert rel_err((4 * p2 - p1) / 3, ours) < 1e-9


# ---------------------------------------------------------------- properties

finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=150, deadline=None)
@given(left=st.floats(-20, 20, **finite), right=st.floats(-20, 20, **finite),
       theta0=st.floats(-10, 10, **finite), kl=st.floats(0, 0.05, **finite),
       kr=st.floats(0, 0.05, **finite), b=st.floats(0.1, 2.0, **finite))
def test_added_covariance_is_symmetric_psd(left, right, theta0, kl, kr, b):
    cov = wheel_arc_cov(left, right, b, WheelNoise(kl, kr), theta0)
    assert np.array_equal(cov, cov.T)
    scale = max(float(np.max(np.abs(cov))), 1e-300)
    assert np.min(np.linalg.eigvalsh(cov)) >= -1e-12 * scale


@settings(max_examples=100, deadline=None)
@given(left=st.floats(-10, 10, **finite), right=st.floats(-10, 10, **finite),
       theta0=st.floats(-4, 4, **finite), frac=st.floats(0.05, 0.95, **finite))
def test_splitting_an_arc_changes_nothing(left, right, theta0, frac):
    # Chong–Kleeman section 5.1: the per-wheel model is consistent.
    b, noise = 0.4, WheelNoise(0.01, 0.02)
    cov0 = np.diag([1e-4, 2e-4, 3e-4])
    whole = wheel_arc_cov(left, right, b, noise, theta0, cov0)
    first = wheel_arc_cov(frac * left, frac * right, b, noise, theta0, cov0)
    theta_mid = theta0 + frac * (right - left) / b
    both = wheel_arc_cov((1 - frac) * left, (1 - frac) * right, b, noise, theta_mid, first)
    assert np.max(np.abs(both - whole)) <= 1e-12 * np.max(np.abs(whole))


def test_splitting_into_many_pieces():
    b, noise, theta = 0.4, WheelNoise(0.003, 0.002), 0.0
    whole = wheel_arc_cov(15.0, 10.0, b, noise)
    cov, n = np.zeros((3, 3)), 37
    for _ in range(n):
        cov = wheel_arc_cov(15.0 / n, 10.0 / n, b, noise, theta, cov)
        theta += (10.0 - 15.0) / n / b
    assert rel_err(cov, whole) < 1e-12


def test_zero_noise_and_zero_length_add_nothing():
    assert np.array_equal(wheel_arc_cov(3.0, 1.0, 0.4, WheelNoise(0.0, 0.0), 0.3), np.zeros((3, 3)))
    assert np.array_equal(wheel_arc_cov(0.0, 0.0, 0.4, WheelNoise(0.1, 0.1), 0.3), np.zeros((3, 3)))
    cov0 = np.diag([1.0, 2.0, 3.0])
    assert np.array_equal(wheel_arc_cov(0.0, 0.0, 0.4, WheelNoise(0.1, 0.1), 0.3, cov0), cov0)


def test_initial_covariance_goes_through_transition():
    # Zero wheel noise: only the initial heading error swings the end point about the
    # start, by (−Δy, Δx)·δθ; checked by finite differences of the exact arc.
    left, right, b, theta0 = 3.0, 1.0, 0.4, 0.4
    cov0 = np.array([[1e-4, 0, 0], [0, 2e-4, 0], [0, 0, 3e-4]])
    d, a = 0.5 * (left + right), (right - left) / b
    h = 1e-6
    plus = np.array(step_displacement(theta0 + h, d, a, "exact"))
    minus = np.array(step_displacement(theta0 - h, d, a, "exact"))
    J = np.eye(3)
    J[:2, 2] = (plus - minus) / (2 * h)
    expected = J @ cov0 @ J.T
    assert rel_err(wheel_arc_cov(left, right, b, WheelNoise(0, 0), theta0, cov0), expected) < 1e-8


# ---------------------------------------------------------------- classical model

def test_classical_model_reproduces_inconsistency_example():
    # Chong–Kleeman section 1: (i) u = [2D, 0] once; (ii) u = [D, 0] twice.
    D, sd, sa = 1.5, 0.2, 0.03
    _, case_i = classical_step((0, 0, 0), np.zeros((3, 3)), 2 * D, 0.0, ClassicalNoise(sd, sa))
    assert np.allclose(case_i, [[sd**2, 0, 0], [0, 4 * D**2 * sa**2, 2 * D * sa**2],
                                [0, 2 * D * sa**2, sa**2]], rtol=1e-15, atol=0)
    pose, cov = classical_step((0, 0, 0), np.zeros((3, 3)), D, 0.0, ClassicalNoise(sd, sa))
    _, case_ii = classical_step(pose, cov, D, 0.0, ClassicalNoise(sd, sa))
    assert np.allclose(case_ii, [[2 * sd**2, 0, 0], [0, 5 * D**2 * sa**2, 3 * D * sa**2],
                                 [0, 3 * D * sa**2, 2 * sa**2]], rtol=1e-15, atol=0)
    # Even with Cov(u0) = 2·Cov(u1) the answers differ (4D² · 2 = 8D² ≠ 5D²).
    s2 = np.sqrt(2)
    _, case_i2 = classical_step((0, 0, 0), np.zeros((3, 3)), 2 * D, 0.0,
                                ClassicalNoise(s2 * sd, s2 * sa))
    assert case_i2[1, 1] == pytest.approx(8 * D**2 * sa**2, rel=1e-14)
    assert not np.allclose(case_i2, case_ii)


def test_classical_step_jacobian_by_finite_differences():
    pose, dist, ang = np.array([0.3, -0.2, 0.8]), 1.3, 0.4
    noise = ClassicalNoise(0.0, 0.0)
    eps = 1e-6

    def f(v):
        return classical_step(v[:3], np.zeros((3, 3)), v[3], v[4], noise)[0]

    v0 = np.concatenate([pose, [dist, ang]])
    J = np.column_stack([(f(v0 + eps * e) - f(v0 - eps * e)) / (2 * eps) for e in np.eye(5)])
    cov0 = np.diag([0.1, 0.2, 0.3])
    sd, sa = 0.05, 0.02
    expected = J[:, :3] @ cov0 @ J[:, :3].T + J[:, 3:] @ np.diag([sd**2, sa**2]) @ J[:, 3:].T
    _, got = classical_step(pose, cov0, dist, ang, ClassicalNoise(sd, sa))
    assert rel_err(got, expected) < 1e-8


def test_eq17_misprints_and_eq22_by_finite_differences():
    # ∂(x, y)/∂(L, R) of eq. (14). Eq. (22) (with r/B) is right; eq. (17) prints r_k
    # instead of r_k/B in all four position entries and −BL instead of +BL in ∂y/∂R.
    L, R, B, t0 = 3.0, 1.0, 0.4, 0.3
    r, tk = B / 2 * (L + R) / (L - R), t0 + (R - L) / B

    def pos(lr):
        x, y = step_displacement(t0, 0.5 * (lr[0] + lr[1]), (lr[1] - lr[0]) / B, "exact")
        return np.array([x, y])

    h = 1e-6
    fd = np.column_stack([(pos(np.array([L, R]) + h * e) - pos(np.array([L, R]) - h * e))
                          / (2 * h) for e in np.eye(2)])
    ds, dc = np.sin(t0) - np.sin(tk), np.cos(tk) - np.cos(t0)
    gr, gl = -B * R / (L - R) ** 2, B * L / (L - R) ** 2
    ck, sk = np.cos(tk), np.sin(tk)
    eq22 = np.array([[gr * ds + r / B * ck, gl * ds - r / B * ck],
                     [gr * dc + r / B * sk, gl * dc - r / B * sk]])
    eq17 = np.array([[gr * ds + r * ck, gl * ds - r * ck],
                     [gr * dc + r * sk, -gl * dc - r * sk]])
    assert np.allclose(eq22, fd, rtol=0, atol=1e-8)
    assert not np.allclose(eq17, fd, rtol=0, atol=1e-2)
