"""Noise models -> covariance of each step's body input (Δd, Δθ).

Every engine in :mod:`odomkit.propagate` consumes, per step k, the 2×2 covariance Q_k of
(Δd_k, Δθ_k) [m², m·rad, rad²]. The functions here map each noise model of
:mod:`odomkit.noise` onto Q_k through the Jacobian of the model's raw inputs, or give the
Jacobian the engines need where the step map itself differs:

==========================  =========================================================
noise model                 mapping
==========================  =========================================================
WheelNoise                  :func:`wheel_input_cov` (Chong–Kleeman eq. 4)
ClassicalNoise              :func:`classical_input_cov` with the rotate-then-translate
                            step map :func:`classical_step_jacobians` (method
                            ``"classical"`` in the engines; Chong–Kleeman eq. 1–3)
SpeedNoise, GyroNoise       :func:`speed_gyro_input_cov` (Kelly Table 1)
TricycleNoise               :func:`tricycle_input_cov` via :func:`tricycle_input_jacobian`
CompassNoise                :func:`direct_heading_variances`; heading is measured, not
                            integrated, so it has its own engine
                            (:func:`odomkit.propagate.transition.propagate_direct_heading`)
ParameterUncertainty        :func:`diff_parameter_jacobian`,
                            :func:`tricycle_parameter_jacobian`, :func:`scale_parameter_jacobian`;
                            ``white``: :func:`white_parameter_cov`; ``bias``: a sensitivity
                            (:func:`odomkit.propagate.transition.parameter_sensitivity`)
==========================  =========================================================

Which of these a whole log needs, for its robot and a noise model or tuple of models, is
decided by :func:`odomkit.propagate.plan.plan_noise`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.kinematics import diff_body_jacobian, step_displacement, step_jacobians
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)

ENGINE_METHODS = ("exact", "midpoint", "euler", "classical")


def _f(a: ArrayLike) -> NDArray[np.float64]:
    return np.asarray(a, dtype=float)


def _sym2(q00: ArrayLike, q01: ArrayLike, q11: ArrayLike) -> NDArray[np.float64]:
    q00, q01, q11 = np.broadcast_arrays(_f(q00), _f(q01), _f(q11))
    # One stack instead of four strided writes: about 5x faster on cache-sized chunks.
    return np.stack([q00, q01, q01, q11], axis=-1).reshape(q00.shape + (2, 2))


def wheel_cov_coefficients(wheel_base: float, noise: WheelNoise) -> NDArray[np.float64]:
    """(k_L², k_R², J00², J01·J11, J11²), J = ∂(Δd, Δθ)/∂(d_L, d_R): the constants of
    :func:`wheel_input_cov`, shared with the numba kernel so both give the same bits.

    >>> wheel_cov_coefficients(0.5, WheelNoise(0.1, 0.2)).round(6).tolist()
    [0.01, 0.04, 0.25, 1.0, 4.0]
    """
    jac = diff_body_jacobian(wheel_base)
    return np.array([noise.k_left**2, noise.k_right**2, jac[0, 0] ** 2,
                     jac[0, 1] * jac[1, 1], jac[1, 1] ** 2])


def wheel_input_cov(
    d_left: ArrayLike, d_right: ArrayLike, wheel_base: float, noise: WheelNoise
) -> NDArray[np.float64]:
    """Per-wheel white noise -> Cov(Δd, Δθ) of each step.

    Cov(d_L, d_R) = diag(k_L²|d_L|, k_R²|d_R|) (Chong–Kleeman eq. 4), mapped by the
    constant Jacobian J = ∂(Δd, Δθ)/∂(d_L, d_R) = [[½, ½], [−1/b, 1/b]]
    (Borenstein–Feng eq. 2.2–2.4): Q = J diag J^T.

    Parameters
    ----------
    d_left, d_right : array_like, shape (M,)
        Wheel travel of each step [m].
    wheel_base : float
        Effective wheel base b [m].
    noise : WheelNoise
        k_left, k_right [m^½].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)
        [m², m·rad; m·rad, rad²].

    Examples
    --------
    >>> q = wheel_input_cov([1.0], [1.0], 0.5, WheelNoise(0.1, 0.1))
    >>> np.allclose(q[0], [[0.005, 0.0], [0.0, 0.08]])
    True
    """
    k_l2, k_r2, j00_sq, j01_j11, j11_sq = wheel_cov_coefficients(wheel_base, noise)
    var_l = np.abs(_f(d_left))
    var_l *= k_l2
    var_r = np.abs(_f(d_right))
    var_r *= k_r2
    # The Sun–Gao exercise prints Σ_ΔdΔθ = diag((σr²+σl²)/4, (σr²−σl²)/L²): wrong. The
    # θθ entry is (σr²+σl²)/b² (variances add), and the off-diagonal is (σr²−σl²)/(2b),
    # not 0. Its J_x also swaps sin and cos in the θ column; the engines use
    # [−Δy, Δx] (kinematics.step_jacobians), checked by finite differences.
    # J diag(var_l, var_r) J^T written out with J = [[½, ½], [−1/b, 1/b]]: no (M, 2, 2)
    # temporaries, few passes. The numba kernel (_numba.py, QMODE_WHEEL) repeats these
    # operations in this order; keep the two in step.
    var_sum = var_l + var_r
    var_diff = var_r
    var_diff -= var_l
    return _sym2(j00_sq * var_sum, j01_j11 * var_diff, j11_sq * var_sum)


def classical_input_cov(m: int, noise: ClassicalNoise) -> NDArray[np.float64]:
    """The classical model's Cov(D_k, α_k) = diag(σ_D², σ_α²), the same for every step.

    Chong–Kleeman eq. (3). It must be propagated with the classical step map, rotation
    α then translation D (eq. 1), i.e. ``method="classical"`` in the engines, whose
    Jacobians are :func:`classical_step_jacobians`. Its covariance depends on how a path
    is cut into steps (Chong–Kleeman section 1: one step of 2D and two of D differ);
    odomkit keeps it only to show that.

    Returns
    -------
    cov_input : ndarray, shape (m, 2, 2)
        [m², m·rad; m·rad, rad²].

    Examples
    --------
    >>> classical_input_cov(2, ClassicalNoise(0.1, 0.01))[1].tolist()
    [[0.010000000000000002, 0.0], [0.0, 0.0001]]
    """
    return _sym2(np.full(m, noise.sigma_distance**2), np.zeros(m),
                 np.full(m, noise.sigma_angle**2))


def classical_step_displacement(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(Δx, Δy) of the classical step: rotate by α = Δθ, then translate D = Δd along
    the new heading (Chong–Kleeman eq. 1)."""
    heading = _f(theta) + _f(dtheta)
    return _f(dd) * np.cos(heading), _f(dd) * np.sin(heading)


def classical_step_jacobians(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """F = ∂f/∂(x, y, θ) (M, 3, 3) and G = ∂f/∂(D, α) (M, 3, 2) of Chong–Kleeman eq. (1).

    ``G = [[cos(θ+α), −D sin(θ+α)], [sin(θ+α), D cos(θ+α)], [0, 1]]`` (eq. 3). Unlike
    the arc, the whole rotation acts before the translation, so ∂x/∂α equals ∂x/∂θ.

    >>> F, G = classical_step_jacobians([0.0], [1.0], [0.0])
    >>> G[0].tolist()
    [[1.0, -0.0], [0.0, 1.0], [0.0, 1.0]]
    """
    theta, dd, dtheta = np.broadcast_arrays(_f(theta), _f(dd), _f(dtheta))
    dx, dy = classical_step_displacement(theta, dd, dtheta)
    F = np.zeros(theta.shape + (3, 3))
    F[..., 0, 0] = F[..., 1, 1] = F[..., 2, 2] = 1.0
    F[..., 0, 2], F[..., 1, 2] = -dy, dx
    G = np.zeros(theta.shape + (3, 2))
    heading = theta + dtheta
    G[..., 0, 0], G[..., 1, 0] = np.cos(heading), np.sin(heading)
    G[..., 0, 1], G[..., 1, 1] = -dy, dx
    G[..., 2, 1] = 1.0
    return F, G


def any_step_displacement(theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: str):
    """:func:`odomkit.kinematics.step_displacement`, plus ``method="classical"``."""
    if method == "classical":
        return classical_step_displacement(theta, dd, dtheta)
    return step_displacement(theta, dd, dtheta, method)  # type: ignore[arg-type]


def any_step_jacobians(theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: str):
    """:func:`odomkit.kinematics.step_jacobians`, plus ``method="classical"``."""
    if method == "classical":
        return classical_step_jacobians(theta, dd, dtheta)
    return step_jacobians(theta, dd, dtheta, method)  # type: ignore[arg-type]


# Below |u| = |Δθ/2| = 0.1 the Taylor series of sinc(u) = sin(u)/u and of its derivative
# are exact to < 3e-17 relative (first omitted terms u^10/11!, 10·u^9/11!); the direct
# formulas, with their sines, cosines and cancellation in (u·cos u − sin u)/u², are then
# needed only for the few large turns (same scheme as the numba kernel in _numba.py).
_SERIES_BELOW = 0.1


def sinc_half_pair(dtheta: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """sinc(Δθ/2) and d/dΔθ sinc(Δθ/2), vectorised: the values of
    :func:`odomkit.kinematics.sinc_half` and :func:`~odomkit.kinematics.sinc_half_derivative`
    at about a fifth of the cost on typical logs (small Δθ per step)."""
    u = 0.5 * dtheta
    v = u * u
    f = 1.0 - v * (1.0 / 6.0) * (1.0 - v * (1.0 / 20.0) * (
        1.0 - v * (1.0 / 42.0) * (1.0 - v * (1.0 / 72.0))))
    # d/du sinc = −u/3 + u³/30 − u⁵/840 + u⁷/45360 − u⁹/3991680; d/dΔθ = ½ d/du
    df = (-0.5 / 3.0) * u * (1.0 - v * (1.0 / 10.0) * (1.0 - v * (1.0 / 28.0) * (
        1.0 - v * (1.0 / 54.0) * (1.0 - v * (1.0 / 88.0)))))
    big = np.flatnonzero(np.abs(u) >= _SERIES_BELOW)
    if big.size:
        ub = u[big]
        sb = np.sin(ub)
        f[big] = sb / ub
        df[big] = 0.5 * (ub * np.cos(ub) - sb) / (ub * ub)
    return f, df


def step_terms(
    theta: NDArray[np.float64], dd: NDArray[np.float64], dtheta: NDArray[np.float64],
    method: str,
) -> tuple[NDArray[np.float64], ...]:
    """(Δx, Δy, g00, g01, g10, g11) of each step as 1-D arrays (n,).

    The same numbers as :func:`any_step_jacobians` (F = I + (−Δy, Δx, 0) e_θ^T and
    G = [[g00, g01], [g10, g11], [0, 1]]) without building (n, 3, 3) arrays: the
    prefix-sum engines need only these six per step.
    """
    if method == "euler":
        c, s = np.cos(theta), np.sin(theta)
        return dd * c, dd * s, c, np.zeros_like(c), s, np.zeros_like(c)
    if method == "classical":
        heading = theta + dtheta
        c, s = np.cos(heading), np.sin(heading)
        dx, dy = dd * c, dd * s
        return dx, dy, c, -dy, s, dx
    heading = theta + 0.5 * dtheta
    c, s = np.cos(heading), np.sin(heading)
    if method == "midpoint":
        dx, dy = dd * c, dd * s
        return dx, dy, c, -0.5 * dy, s, 0.5 * dx
    if method != "exact":
        raise ModelError(f"unknown method {method!r}; expected one of {', '.join(ENGINE_METHODS)}")
    f, df = sinc_half_pair(dtheta)
    fc, fs = f * c, f * s
    dx, dy = dd * fc, dd * fs
    ddf = dd * df
    # kinematics.step_jacobians: ∂/∂Δθ [Δd·f·cos(θ+Δθ/2)] = Δd·(f'·cos − f·sin/2)
    return dx, dy, fc, ddf * c - 0.5 * dy, fs, ddf * s + 0.5 * dx


def speed_gyro_input_cov(
    dd: ArrayLike, dt: ArrayLike, speed: SpeedNoise | None = None, gyro: GyroNoise | None = None
) -> NDArray[np.float64]:
    """Integrated-heading odometry (Kelly Table 1): encoder and gyro noise per step.

    ``var Δd = α_ss·|Δd|`` (σ_vv = α_ss|V| integrated over the step) and
    ``var Δθ = σ_gg·Δt`` (white yaw-rate noise of density σ_gg integrated over Δt);
    independent (σ_vω = 0). Either model may be None (zero).

    Parameters
    ----------
    dd : array_like, shape (M,)
        Distance of each step [m].
    dt : array_like, shape (M,)
        Duration of each step [s].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)

    Examples
    --------
    >>> speed_gyro_input_cov([0.5], [0.1], SpeedNoise(0.01), GyroNoise(1e-4))[0].tolist()
    [[0.005, 0.0], [0.0, 1e-05]]
    """
    dd, dt = _f(dd), _f(dt)
    var_dd = (speed.alpha_ss if speed else 0.0) * np.abs(dd)
    var_dtheta = (gyro.psd_gyro if gyro else 0.0) * np.abs(dt)
    return _sym2(var_dd, np.zeros_like(var_dd), var_dtheta)


def tricycle_input_jacobian(
    travel: ArrayLike, steer: ArrayLike, dt: ArrayLike, wheel_to_axle: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(v, α, T) of the tricycle step, shape (M, 2, 3).

    With v = s/T the front-wheel speed, Δd = vT·cos α, Δθ = vT·sin α / L (Sun–Gao,
    Snowhite model):

    ``[[T cos α, −vT sin α, v cos α], [T sin α / L, vT cos α / L, v sin α / L]]``.

    Derived again rather than copied: the exercise does not print this J, and its
    printed heading update (vT sin α/(2L) in section 2.2, vT sin α/2 in 3.2) has a
    spurious ½ and a missing L; the heading change is vT sin α / L. Checked against
    finite differences in the tests.
    For a zero-length step (T = 0) the speed is taken as 0.
    """
    s, a, t = np.broadcast_arrays(_f(travel), _f(steer), _f(dt))
    v = np.divide(s, t, out=np.zeros_like(s), where=t != 0)
    jac = np.empty(s.shape + (2, 3))
    ca, sa = np.cos(a), np.sin(a)
    jac[..., 0, 0] = t * ca
    jac[..., 0, 1] = -s * sa
    jac[..., 0, 2] = v * ca
    jac[..., 1, 0] = t * sa / wheel_to_axle
    jac[..., 1, 1] = s * ca / wheel_to_axle
    jac[..., 1, 2] = v * sa / wheel_to_axle
    return jac


def tricycle_input_cov(
    travel: ArrayLike, steer: ArrayLike, dt: ArrayLike, wheel_to_axle: float, noise: TricycleNoise
) -> NDArray[np.float64]:
    """Tricycle speed, steering and sample-period noise -> Cov(Δd, Δθ) per step.

    Q = J diag(σ_v², σ_α², σ_T²) J^T with J from :func:`tricycle_input_jacobian`
    (Sun–Gao, Snowhite part, Σ_vαT; independent white noise on each sample).

    Parameters
    ----------
    travel : array_like, shape (M,)
        Front-wheel travel s = v·T [m].
    steer : array_like, shape (M,)
        Steering angle [rad].
    dt : array_like, shape (M,)
        Sample period T [s].
    wheel_to_axle : float
        L [m].
    noise : TricycleNoise
        sigma_speed [m/s], sigma_steer [rad], sigma_dt [s].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)

    Examples
    --------
    >>> q = tricycle_input_cov([0.1], [0.0], [0.1], 1.0, TricycleNoise(0.01, 0.02))
    >>> np.allclose(q[0], [[1e-6, 0.0], [0.0, 4e-6]])
    True
    """
    jac = tricycle_input_jacobian(travel, steer, dt, wheel_to_axle)
    var = np.array([noise.sigma_speed**2, noise.sigma_steer**2, noise.sigma_dt**2])
    return np.einsum("...ik,k,...jk->...ij", jac, var, jac)


def direct_heading_variances(dt: ArrayLike, noise: CompassNoise) -> NDArray[np.float64]:
    """Variance of each measured heading sample [rad²], shape (M + 1,).

    A compass with white heading noise of density ``psd_compass`` [rad²·s], sampled
    (averaged) over Δt, has ``var = psd_compass / Δt`` (noise.CompassNoise). Row k uses
    the spacing around it: the mean of the two adjacent step durations (one at the
    ends). With this, the position variance on a straight line at speed V grows as
    |V|·psd·s, Kelly eq. (13).
    """
    dt = _f(dt)
    if dt.size == 0:
        return np.zeros(1)
    if np.any(dt <= 0):
        raise ModelError("direct-heading noise needs strictly increasing time stamps (dt > 0)")
    spacing = np.empty(dt.size + 1)
    spacing[0], spacing[-1] = dt[0], dt[-1]
    spacing[1:-1] = 0.5 * (dt[:-1] + dt[1:])
    return noise.psd_compass / spacing


def diff_parameter_jacobian(
    d_left: ArrayLike, d_right: ArrayLike, wheel_base: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(b, ε_L, ε_R), shape (M, 2, 3), differential drive.

    b is the wheel base [m]; ε_L, ε_R are relative wheel-scale errors (a wheel travels
    d·(1 + ε)). From Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b (Borenstein–Feng 2.2–2.4):
    ``[[0, d_L/2, d_R/2], [−Δθ/b, −d_L/b, d_R/b]]``.
    """
    d_l, d_r = np.broadcast_arrays(_f(d_left), _f(d_right))
    jac = np.zeros(d_l.shape + (2, 3))
    jac[..., 0, 1] = 0.5 * d_l
    jac[..., 0, 2] = 0.5 * d_r
    jac[..., 1, 0] = -(d_r - d_l) / wheel_base**2
    jac[..., 1, 1] = -d_l / wheel_base
    jac[..., 1, 2] = d_r / wheel_base
    return jac


def tricycle_parameter_jacobian(
    travel: ArrayLike, steer: ArrayLike, wheel_to_axle: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(L, ε), shape (M, 2, 2): L [m] and the traction-wheel scale ε.

    Δd = s(1+ε)cos α, Δθ = s(1+ε) sin α / L: ``[[0, Δd], [−Δθ/L, Δθ]]``.
    """
    s, a = np.broadcast_arrays(_f(travel), _f(steer))
    dd = s * np.cos(a)
    dtheta = s * np.sin(a) / wheel_to_axle
    jac = np.zeros(s.shape + (2, 2))
    jac[..., 0, 1] = dd
    jac[..., 1, 0] = -dtheta / wheel_to_axle
    jac[..., 1, 1] = dtheta
    return jac


def scale_parameter_jacobian(dd: ArrayLike) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂ε, shape (M, 2, 1), for a single distance scale ε (gyro/compass)."""
    dd = _f(dd)
    jac = np.zeros(dd.shape + (2, 1))
    jac[..., 0, 0] = dd
    return jac


def white_parameter_cov(jac: ArrayLike, var_params: ArrayLike) -> NDArray[np.float64]:
    """Parameter uncertainty treated as fresh white noise at every step (the Sun–Gao
    exercise's treatment): Q = K diag(var) K^T, shape (M, 2, 2).

    This understates long runs: a wrong wheel base is the same error at every step.
    Use the bias mode (:func:`odomkit.propagate.transition.parameter_sensitivity`)
    for a physical prediction.
    """
    jac = _f(jac)
    return np.einsum("...ik,k,...jk->...ij", jac, _f(var_params), jac)
