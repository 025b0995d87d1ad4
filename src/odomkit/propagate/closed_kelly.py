"""Kelly's closed forms for gyro (integrated heading) and compass (direct heading)
odometry on straight and constant-curvature segments (Kelly eq. 10–15, Table 2).

A segment is :class:`odomkit.path.KellyArc`: constant speed V [m/s] and yaw rate ω
[rad/s] for T [s]; straight when ω = 0. Noise (Kelly Table 1): speed noise with spectral
density σ_vv = α_ss·|V| (so the distance has variance α_ss·|Δs|), and either gyro rate
noise of density σ_gg or compass heading noise of density σ_θθ, all white.

Misprints found while checking Kelly against quadrature of his eq. (10)/(11) (see the
tests):

* Table 2, M₂₂ entry (1,2): printed without the factor R that its mirror (2,1) carries;
  the correct entry is ``R·[θ·s2θ/2 + (3/2)·c2θ/2 − cθ + 1/4]`` (the known unit error).
* Eq. (14), compass term: printed ``|V|·σ_θθ·[...]``; integrating eq. (10) gives
  ``|V|·σ_θθ·(R/2)·[...]`` (R = V/ω). Only then are the units m² and the limit ω -> 0
  equal to eq. (13)'s ``|V|·σ_θθ·s``.

Compass odometry is predicted for a *sampled* compass (period T, each reading an
independent error of variance σ_θθ/T, exact arcs between readings), the model ``odomkit
track`` propagates for a compass log; Kelly's continuous eq. (10)/(14) is its limit
T -> 0 for the position (see :func:`compass_arc_cov`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.angles import sinc, sinc_derivative
from odomkit.errors import ModelError
from odomkit.noise import CompassNoise, GyroNoise, SpeedNoise, TurnNoise
from odomkit.noise.kelly import compass_sample_count
from odomkit.path import KellyArc
from odomkit.propagate.closed import (
    INTEGRALS,
    arc_added_cov_local,
    arc_integrals,
    chain_cov,
    rotate_cov,
)

__all__ = ["compass_arc_cov", "gyro_arc_cov"]


def gyro_arc_cov(
    segment: KellyArc,
    speed_noise: SpeedNoise,
    gyro_noise: GyroNoise,
    theta0: float = 0.0,
    cov0: ArrayLike | None = None,
    turn_noise: TurnNoise | None = None,
) -> NDArray[np.float64]:
    """Covariance at the end of a gyro-odometry segment, Kelly eq. (11), (13), (15).

    The integrand of eq. (11) is the same ``A Q Aᵀ`` as for per-wheel noise (see
    :mod:`odomkit.propagate.closed`), with the segment's noise over its duration
    ``q_ss = α_ss·|V|·T`` and ``q_θθ = σ_gg·T``, uncorrelated (Kelly Table 1,
    σ_vθ = 0). The incoming covariance goes through Kelly's IC_s transition.

    A :class:`~odomkit.noise.TurnNoise` adds ``α_turn_travel·|ωT|`` to q_ss and
    ``α_turn·|ωT|`` to q_θθ: on a constant-curvature segment its density per unit of the
    segment is constant too (a GyroNoise of density α_turn·|ω| and a SpeedNoise of
    α_ss = α_turn_travel·|ω/V|), so the same integral holds. On a spin in place (V = 0,
    D = 0) the travel error still moves the end point, along the turning heading:
    A's first column (cos φ, sin φ) does not vanish with D.

    Parameters
    ----------
    segment : KellyArc
    speed_noise : SpeedNoise
        α_ss [m].
    gyro_noise : GyroNoise
        σ_gg [rad²/s].
    theta0 : float
        Heading at the start [rad].
    cov0 : array_like, shape (3, 3), optional
    turn_noise : TurnNoise, optional
        α_turn [rad], α_turn_travel [m²/rad]; None: none.

    Returns
    -------
    ndarray, shape (3, 3)

    Examples
    --------
    Straight, 1 m/s for 3 s, gyro only: σ_y² = σ_gg·s²t/3 (Kelly eq. 13).

    >>> cov = gyro_arc_cov(KellyArc(1.0, 0.0, 3.0), SpeedNoise(0.0), GyroNoise(1e-4))
    >>> round(float(cov[1, 1]) / (1e-4 * 9 * 3 / 3), 12)
    1.0
    """
    v, w, t = segment.speed, segment.yaw_rate, segment.duration
    d, a = v * t, w * t
    q_ss, q_tt = speed_noise.alpha_ss * abs(v) * t, gyro_noise.psd_gyro * t
    if turn_noise is not None:
        q_ss += turn_noise.alpha_turn_travel * abs(a)
        q_tt += turn_noise.alpha_turn * abs(a)
    added = arc_added_cov_local(d, a, q_ss, 0.0, q_tt)
    return chain_cov(d, a, theta0, cov0, added)


def compass_arc_cov(
    segment: KellyArc,
    speed_noise: SpeedNoise,
    compass_noise: CompassNoise,
    theta0: float = 0.0,
    cov0: ArrayLike | None = None,
    period: float | None = None,
) -> NDArray[np.float64]:
    """Covariance at the end of a compass-odometry segment: a compass sampled every
    ``period`` [s] (Kelly eq. 10 discretised), or Kelly's continuous eq. (10), (13), (14).

    **Sampled compass** (``period`` = T given; what ``odomkit track`` propagates for a
    compass log). The segment lasts n = duration/T samples (a whole number). Each reading
    h_j = θ_j + e_j has an independent error of variance σ² = σ_θθ/T; step k is the exact
    arc from h_k to h_{k+1} with length d = V·T (+ an error of variance α_ss·|d|), so
    its end point moves by A δd + B e_k + C e_{k+1} with, for the step's heading change
    a = ωT, x = a/2 and φ_k the heading at its middle (``sinc`` = sin(x)/x)::

        A = sinc(x)·u(φ_k),   B, C = (d/2)·[sinc(x)·u⊥(φ_k) ∓ sinc′(x)·u(φ_k)]

    (u the unit heading vector, u⊥ it turned by +90°). An interior reading enters two steps,
    and the two terms add to exactly d·sinc²(x)·u⊥(θ_j) (the u parts cancel by
    sin/cos of a half angle), perpendicular to its own heading; the first reading weighs
    B₀, the last C_{n−1}. Summed over the segment::

        P_xy += α_ss|d|·sinc²(x)·Σ_k u uᵀ(φ_k) + σ²·[d²sinc⁴(x)·Σ_{j=1}^{n−1} u⊥u⊥ᵀ(θ_j)
                + B₀B₀ᵀ + CCᵀ] + B₀ rᵀ + r B₀ᵀ

    where r = ``cov0[:2, 2]`` is the covariance of the start position with the start
    reading's error (zero at a path's start; the previous segment's C·σ² when chained).
    The sums over equally spaced headings are closed (Dirichlet kernel):
    Σ_{k<N} R(β + 2ka) = sin(Na)/sin(a)·R(β + (N−1)a), R(ψ) = [[cos ψ, sin ψ],
    [sin ψ, −cos ψ]], with u uᵀ = (I + R(2φ))/2 and u⊥u⊥ᵀ = (I − R(2θ))/2. The end
    heading is the last reading: variance σ², covariance C·σ² with the position.

    As T -> 0 this tends to Kelly's continuous covariance: the interior sum is the
    trapezoid rule of eq. (10), and the end readings weigh a quarter of an interior one,
    so P(T) = P_Kelly − σ_θθ·V²·T/4·(n₀n₀ᵀ + n₁n₁ᵀ) + O(T²) (n₀, n₁ the unit normals at
    the ends; tested), while the heading variance σ_θθ/T grows without bound.

    **Continuous** (``period`` None, Kelly eq. 10): the state is (x, y), Φ = I, and
    ``P = P(0) + ∫ B Q Bᵀ dt`` with ``B = [[cos θ, −V sin θ], [sin θ, V cos θ]]`` and
    Q = diag(α_ss·|V|, σ_θθ). White heading noise has no finite variance at an instant:
    the θ variance is NaN and its covariances with x, y are 0.

    Parameters
    ----------
    segment : KellyArc
    speed_noise : SpeedNoise
        α_ss [m].
    compass_noise : CompassNoise
        σ_θθ [rad²·s].
    theta0 : float
        Heading at the start [rad].
    cov0 : array_like, shape (3, 3), optional
        Its x, y block and (sampled only) its x–θ, y–θ column, as above; the θ variance
        is ignored (the reading's own is used).
    period : float, optional
        Compass sample period T [s]; |ω|·T must be below π.

    Returns
    -------
    ndarray, shape (3, 3)

    Examples
    --------
    Straight, 2 m/s for 5 s (s = 10 m): σ_x² = α_ss·s, σ_y² = |V|·σ_θθ·s (Kelly eq. 13);
    sampled every 0.5 s, the two end readings lose a quarter each: σ_y² = V²σ_θθ(t − T/2).

    >>> cov = compass_arc_cov(KellyArc(2.0, 0.0, 5.0), SpeedNoise(1e-4), CompassNoise(1e-3))
    >>> [round(float(v), 12) for v in (cov[0, 0], cov[1, 1])]
    [0.001, 0.02]
    >>> cov = compass_arc_cov(KellyArc(2.0, 0.0, 5.0), SpeedNoise(1e-4), CompassNoise(1e-3),
    ...                       period=0.5)
    >>> [round(float(v), 12) for v in (cov[0, 0], cov[1, 1], cov[1, 2], cov[2, 2])]
    [0.001, 0.019, 0.001, 0.002]
    """
    if period is not None:
        return _sampled_compass_cov(segment, speed_noise, compass_noise, theta0, cov0, period)
    v, w, t = segment.speed, segment.yaw_rate, segment.duration
    i = dict(zip(INTEGRALS, arc_integrals(w * t), strict=True))
    var_speed = speed_noise.alpha_ss * abs(v) * t  # distance variance over the segment
    var_heading = compass_noise.psd_compass * t * v * v  # lateral, per Kelly eq. (10)
    local = np.zeros((3, 3))
    local[0, 0] = var_speed * i["cc"] + var_heading * i["ss"]
    local[1, 1] = var_speed * i["ss"] + var_heading * i["cc"]
    local[0, 1] = local[1, 0] = (var_speed - var_heading) * i["cs"]
    cov = rotate_cov(local, theta0)
    if cov0 is not None:
        cov[:2, :2] += np.asarray(cov0, dtype=float)[:2, :2]
    cov = 0.5 * (cov + cov.T)
    cov[2, 2] = np.nan
    return cov


def _unit(phi: float) -> NDArray[np.float64]:
    return np.array([math.cos(phi), math.sin(phi)])


def _heading_sum(n: int, a: float, beta: float) -> NDArray[np.float64]:
    """Σ_{k<n} R(β + 2ka), R(ψ) = [[cos ψ, sin ψ], [sin ψ, −cos ψ]]: the Dirichlet kernel
    sin(na)/sin(a) = n·sinc(na)/sinc(a) (|a| < π) times R at the middle angle."""
    if n <= 0:
        return np.zeros((2, 2))
    psi = beta + (n - 1) * a
    scale = n * float(sinc(n * a)) / float(sinc(a))
    return scale * np.array([[math.cos(psi), math.sin(psi)], [math.sin(psi), -math.cos(psi)]])


def _sampled_compass_cov(segment: KellyArc, speed_noise: SpeedNoise, compass_noise: CompassNoise,
                         theta0: float, cov0: ArrayLike | None, period: float
                         ) -> NDArray[np.float64]:
    """The sampled-compass covariance of :func:`compass_arc_cov` (see its derivation)."""
    var_h = compass_noise.sample_variance(period)
    n = compass_sample_count(segment.duration, period)
    a = segment.yaw_rate * period
    if not abs(a) < math.pi:
        raise ModelError(f"the heading turns by {abs(a):.3g} rad between compass samples "
                         f"(|yaw rate| × compass period); it must be below π")
    start = np.zeros((3, 3)) if cov0 is None else np.asarray(cov0, dtype=float).reshape(3, 3)
    cov = np.zeros((3, 3))
    cov[:2, :2] = start[:2, :2]
    cov[:2, 2] = cov[2, :2] = start[:2, 2]
    cov[2, 2] = var_h
    if n == 0:
        return 0.5 * (cov + cov.T)
    d = segment.speed * period
    x = 0.5 * a
    s0, s1 = float(sinc(x)), float(sinc_derivative(x))
    eye = np.eye(2)
    # distance errors along u(φ_k), φ_k = θ0 + a/2 + k·a
    along = 0.5 * (n * eye + _heading_sum(n, a, 2.0 * theta0 + a))
    # interior readings θ_j = θ0 + j·a, j = 1 … n−1, each ⊥ its heading
    across = 0.5 * ((n - 1) * eye - _heading_sum(n - 1, a, 2.0 * theta0 + 2.0 * a))
    phi0, phi1 = theta0 + x, theta0 + (n - 0.5) * a
    perp0, perp1 = _unit(phi0 + 0.5 * math.pi), _unit(phi1 + 0.5 * math.pi)
    first = 0.5 * d * (s0 * perp0 - s1 * _unit(phi0))  # B₀
    last = 0.5 * d * (s0 * perp1 + s1 * _unit(phi1))   # C_{n−1}
    r = start[:2, 2]
    added = (speed_noise.alpha_ss * abs(d) * s0 * s0 * along
             + var_h * (d * d * s0**4 * across + np.outer(first, first) + np.outer(last, last))
             + np.outer(first, r) + np.outer(r, first))
    cov[:2, :2] += added
    cov[:2, 2] = cov[2, :2] = var_h * last
    return 0.5 * (cov + cov.T)
