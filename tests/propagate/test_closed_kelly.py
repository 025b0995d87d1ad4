"""Kelly's closed forms (gyro and compass odometry) against quadrature of his eq. (10)
and (11), and against the printed eq. (13), (14) and Table 2 (with the misprints fixed)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate as si

from odomkit.kinematics import step_displacement
from odomkit.noise import CompassNoise, GyroNoise, SpeedNoise
from odomkit.path import KellyArc
from odomkit.propagate.closed_kelly import compass_arc_cov, gyro_arc_cov


def rel_err(a, b) -> float:
    a, b = np.asarray(a), np.asarray(b)
    ok = np.isfinite(b)
    return float(np.max(np.abs(a[ok] - b[ok])) / np.max(np.abs(b[ok])))


def _eq11(seg, alpha, sgg, theta0, cov0):
    """Kelly eq. (11): IC_s + ∫₀ᵗ A(τ) diag(α_ss|V|, σ_gg) A(τ)ᵀ dτ, by quadrature; the
    trajectory from the exact-arc step map."""
    v, w, t = seg.speed, seg.yaw_rate, seg.duration
    x1, y1 = step_displacement(theta0, v * t, w * t, "exact")
    q = np.diag([alpha * abs(v), sgg])

    def f(tau):
        x, y = step_displacement(theta0, v * tau, w * tau, "exact")
        th = theta0 + w * tau
        A = np.array([[np.cos(th), -(y1 - y)], [np.sin(th), x1 - x], [0.0, 1.0]])
        return A @ q @ A.T

    ic = np.array([[1.0, 0.0, -y1], [0.0, 1.0, x1], [0.0, 0.0, 1.0]])
    return ic @ cov0 @ ic.T + si.quad_vec(f, 0.0, t, epsabs=1e-20, epsrel=1e-12)[0]


def _eq10(seg, alpha, stt, theta0, cov0):
    """Kelly eq. (10): P(0) + ∫ B diag(α_ss|V|, σ_θθ) Bᵀ dτ, B = [[cθ, −V sθ], [sθ, V cθ]]."""
    v, w, t = seg.speed, seg.yaw_rate, seg.duration
    q = np.diag([alpha * abs(v), stt])

    def f(tau):
        th = theta0 + w * tau
        B = np.array([[np.cos(th), -v * np.sin(th)], [np.sin(th), v * np.cos(th)]])
        return B @ q @ B.T

    return cov0[:2, :2] + si.quad_vec(f, 0.0, t, epsabs=1e-20, epsrel=1e-12)[0]


SEGMENTS = [KellyArc(1.0, 0.3, 5.0), KellyArc(2.0, -1.5, 4.0), KellyArc(-0.7, 0.2, 6.0),
            KellyArc(0.5, 0.0, 8.0), KellyArc(1.2, 1e-4, 3.0), KellyArc(0.0, 0.8, 2.0)]
COV0 = np.array([[1e-3, 2e-4, -1e-4], [2e-4, 2e-3, 3e-4], [-1e-4, 3e-4, 5e-4]])


@pytest.mark.parametrize("seg", SEGMENTS)
@pytest.mark.parametrize("theta0", [0.0, 2.1])
def test_gyro_matches_quadrature_of_eq11(seg, theta0):
    ours = gyro_arc_cov(seg, SpeedNoise(2e-3), GyroNoise(5e-4), theta0, COV0)
    assert rel_err(ours, _eq11(seg, 2e-3, 5e-4, theta0, COV0)) < 1e-11


@pytest.mark.parametrize("seg", SEGMENTS)
@pytest.mark.parametrize("theta0", [0.0, -0.8])
def test_compass_matches_quadrature_of_eq10(seg, theta0):
    ours = compass_arc_cov(seg, SpeedNoise(2e-3), CompassNoise(5e-4), theta0, COV0)
    ref = _eq10(seg, 2e-3, 5e-4, theta0, COV0)
    assert rel_err(ours[:2, :2], ref) < 1e-11
    assert np.isnan(ours[2, 2]) and ours[0, 2] == ours[1, 2] == 0.0


def test_straight_matches_eq13():
    v, t, alpha, sgg, stt = 1.5, 4.0, 1e-3, 2e-4, 3e-4
    s = v * t
    seg = KellyArc(v, 0.0, t)
    gyro = gyro_arc_cov(seg, SpeedNoise(alpha), GyroNoise(sgg))
    eq13_gyro = alpha * np.diag([s, 0, 0]) + sgg * np.array(
        [[0, 0, 0], [0, s**2 * t / 3, s * t / 2], [0, s * t / 2, t]])
    assert rel_err(gyro, eq13_gyro) < 1e-14
    compass = compass_arc_cov(seg, SpeedNoise(alpha), CompassNoise(stt))
    eq13_compass = alpha * np.diag([s, 0]) + abs(v) * stt * np.diag([0, s])
    assert rel_err(compass[:2, :2], eq13_compass) < 1e-14


def _eq14(v, w, t, alpha, stt, printed=False):
    """Kelly eq. (14), start at the origin heading 0, V, ω > 0. As printed, the compass
    term is |V|σ_θθ[...]; integrating eq. (10) gives |V|σ_θθ(R/2)[...]."""
    R, th = v / w, w * t
    s2, sq = np.sin(2 * th), np.sin(th) ** 2
    m_speed = np.array([[th + s2 / 2, sq], [sq, th - s2 / 2]])
    m_head = np.array([[th - s2 / 2, -sq], [-sq, th + s2 / 2]])
    factor = 1.0 if printed else R / 2
    return alpha * R / 2 * m_speed + abs(v) * stt * factor * m_head


def test_arc_matches_eq14_corrected_not_printed():
    v, w, t, alpha, stt = 1.0, 0.25, 7.0, 1e-3, 4e-4  # R = 4, so R/2 ≠ 1
    ours = compass_arc_cov(KellyArc(v, w, t), SpeedNoise(alpha), CompassNoise(stt))[:2, :2]
    assert rel_err(ours, _eq14(v, w, t, alpha, stt)) < 1e-13
    assert rel_err(ours, _eq14(v, w, t, alpha, stt, printed=True)) > 0.1


def _table2(R, th, printed=False):
    """Kelly Table 2: M11 and M22 (integrated heading, arc). Printed M22 (1,2) lacks the
    factor R of its mirror (2,1)."""
    s, c, s2, c2 = np.sin(th), np.cos(th), np.sin(2 * th), np.cos(2 * th)
    m11 = np.array([[th + s2 / 2, s**2, 0], [s**2, th - s2 / 2, 0], [0, 0, 0]])
    m22_12 = th * s2 / 2 + 1.5 * c2 / 2 - c + 0.25
    m22 = np.array([
        [R * (th * (1 + c2 / 2) - 1.5 * s2 / 2), (1 if printed else R) * m22_12, -(s - th * c)],
        [R * m22_12, R * (th * (1 - c2 / 2) + 1.5 * s2 / 2 - 2 * s), th * s + c - 1],
        [-(s - th * c), th * s + c - 1, th / R],
    ])
    return m11, m22


@pytest.mark.parametrize("v,w,t", [(1.0, 0.3, 5.0), (2.0, 0.1, 30.0), (0.5, 2.0, 1.3)])
def test_arc_matches_table2_eq15_corrected(v, w, t):
    alpha, sgg = 1e-3, 2e-4
    R, th = v / w, w * t
    m11, m22 = _table2(R, th)
    eq15 = alpha * R / 2 * m11 + sgg * R / w * m22
    ours = gyro_arc_cov(KellyArc(v, w, t), SpeedNoise(alpha), GyroNoise(sgg))
    assert rel_err(ours, eq15) < 1e-12
    _, m22_printed = _table2(R, th, printed=True)
    assert abs(m22_printed[0, 1] - m22[0, 1]) > 1e-3 * abs(m22[0, 1])  # R ≠ 1 here


def test_zero_noise_adds_nothing():
    seg = KellyArc(1.0, 0.3, 5.0)
    assert np.array_equal(gyro_arc_cov(seg, SpeedNoise(0), GyroNoise(0)), np.zeros((3, 3)))
    assert np.array_equal(compass_arc_cov(seg, SpeedNoise(0), CompassNoise(0))[:2, :2],
                          np.zeros((2, 2)))


def test_gyro_consistent_when_split():
    seg, half = KellyArc(1.3, -0.4, 6.0), KellyArc(1.3, -0.4, 3.0)
    noise = (SpeedNoise(1e-3), GyroNoise(3e-4))
    whole = gyro_arc_cov(seg, *noise, 0.5, COV0)
    first = gyro_arc_cov(half, *noise, 0.5, COV0)
    both = gyro_arc_cov(half, *noise, 0.5 - 0.4 * 3.0, first)
    assert rel_err(both, whole) < 1e-13


def _m12(R, th, printed=False):
    """Kelly Table 2, M12 (the σ_vω cross term, not used by eq. 15 since σ_vθ = 0).
    Printed (1,1) is −R(θ + s2θ/2); integrating eq. (11) gives −R(θ − s2θ/2)."""
    s, c, s2 = np.sin(th), np.cos(th), np.sin(2 * th)
    m11 = -R * (th + s2 / 2) if printed else -R * (th - s2 / 2)
    m12 = 0.5 * R * (s**2 - (c - 1) ** 2)
    return np.array([[m11, m12, s], [m12, R * (-th + 2 * s - s2 / 2), 1 - c], [s, 1 - c, 0]])


@pytest.mark.parametrize("v,w,t", [(1.0, 0.3, 5.0), (0.5, 2.0, 1.3)])
def test_cross_term_matches_table2_m12_corrected(v, w, t):
    # Only correlated speed/yaw-rate noise σ_vω: added covariance = (σ_vω/ω)·M12.
    from odomkit.propagate.closed import arc_added_cov_local

    svw = 1e-4
    ours = arc_added_cov_local(v * t, w * t, 0.0, svw * t, 0.0)
    R, th = v / w, w * t
    assert rel_err(ours, svw / w * _m12(R, th)) < 1e-12
    assert abs(ours[0, 0] - svw / w * _m12(R, th, printed=True)[0, 0]) > 1e-3 * abs(ours[0, 0])
