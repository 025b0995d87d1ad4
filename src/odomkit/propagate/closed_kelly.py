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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.noise import CompassNoise, GyroNoise, SpeedNoise
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
) -> NDArray[np.float64]:
    """Covariance at the end of a gyro-odometry segment, Kelly eq. (11), (13), (15).

    The integrand of eq. (11) is the same ``A Q Aᵀ`` as for per-wheel noise (see
    :mod:`odomkit.propagate.closed`), with the segment's noise over its duration
    ``q_ss = α_ss·|V|·T`` and ``q_θθ = σ_gg·T``, uncorrelated (Kelly Table 1,
    σ_vθ = 0). The incoming covariance goes through Kelly's IC_s transition.

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
    added = arc_added_cov_local(d, a, speed_noise.alpha_ss * abs(v) * t, 0.0,
                                gyro_noise.psd_gyro * t)
    return chain_cov(d, a, theta0, cov0, added)


def compass_arc_cov(
    segment: KellyArc,
    speed_noise: SpeedNoise,
    compass_noise: CompassNoise,
    theta0: float = 0.0,
    cov0: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Covariance at the end of a compass-odometry segment, Kelly eq. (10), (13), (14).

    The heading is measured, not integrated: the state is (x, y) and its transition
    matrix is the identity, so ``P = P(0) + ∫ B Q Bᵀ dt`` with
    ``B = [[cos θ, −V sin θ], [sin θ, V cos θ]]`` and Q = diag(α_ss·|V|, σ_θθ).

    The heading error at the end is the compass's own white noise at that instant, which
    a continuous-time spectral density cannot turn into a finite variance: the θ
    variance is returned as NaN and its covariances with x, y as 0 (a white error at one
    instant is independent of everything before). The θ part of ``cov0`` is ignored.

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
        Only the x, y block is used.

    Returns
    -------
    ndarray, shape (3, 3)

    Examples
    --------
    Straight, 2 m/s for 5 s (s = 10 m): σ_x² = α_ss·s, σ_y² = |V|·σ_θθ·s (Kelly eq. 13).

    >>> cov = compass_arc_cov(KellyArc(2.0, 0.0, 5.0), SpeedNoise(1e-4), CompassNoise(1e-3))
    >>> [round(float(v), 12) for v in (cov[0, 0], cov[1, 1])]
    [0.001, 0.02]
    """
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
