"""Sensor increments -> body motion (Δd, Δθ) per step, and the step's Jacobians.

A *step* k goes from log row k to row k+1. Body motion is the travelled arc length Δd
[m] of the reference point (differential drive: axle centre; tricycle and car: rear axle
centre) and the heading change Δθ [rad].

The exact-arc step map (constant curvature over the step; Wang's compensation as used in
the Sun–Gao exercise, eq. for x_n, y_n) is::

    x' = x + Δd · sinc(Δθ/2) · cos(θ + Δθ/2)
    y' = y + Δd · sinc(Δθ/2) · sin(θ + Δθ/2)          sinc(u) = sin(u)/u, sinc(0) = 1
    θ' = θ + Δθ

which equals Chong–Kleeman eq. (14) rewritten without the radius, so it stays finite on
straight lines (r -> ∞). The factor sinc(Δθ/2) and its derivative come from
:mod:`odomkit.angles`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.angles import sinc_half, sinc_half_derivative, unwrap_angle
from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog, wheel_channels
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Robot, Tricycle, Unicycle

__all__ = [
    "METHODS", "body_steps", "BodySteps", "car_body_jacobian", "car_body_steps", "car_measured_steer",
    "car_road_wheel_angle", "car_speed_factor",
    "diff_body_jacobian", "diff_body_steps", "Method", "steering_body_jacobian", "steering_body_steps",
    "moving_speed", "step_displacement", "step_jacobians", "too_fast", "tricycle_body_jacobian",
    "tricycle_body_steps", "unicycle_moving"
]

Method = Literal["euler", "midpoint", "exact"]
METHODS: tuple[Method, ...] = ("euler", "midpoint", "exact")


def diff_body_steps(
    d_left: ArrayLike, d_right: ArrayLike, wheel_base: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Wheel travels -> (Δd, Δθ), Borenstein–Feng eq. (2.2)–(2.4).

    Parameters
    ----------
    d_left, d_right : array_like, shape (M,)
        Signed distance each wheel travelled over each step [m].
    wheel_base : float
        Effective wheel base b [m].

    Returns
    -------
    dd, dtheta : ndarray, shape (M,)
        ``(d_right + d_left)/2`` [m] and ``(d_right − d_left)/b`` [rad].
    """
    d_left = np.asarray(d_left, dtype=float)
    d_right = np.asarray(d_right, dtype=float)
    return 0.5 * (d_right + d_left), (d_right - d_left) / wheel_base


def diff_body_jacobian(wheel_base: float) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(d_left, d_right), shape (2, 2); constant for a differential drive."""
    return np.array([[0.5, 0.5], [-1.0 / wheel_base, 1.0 / wheel_base]])


def tricycle_body_steps(
    travel: ArrayLike, steer: ArrayLike, wheel_to_axle: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Front-wheel travel and steering angle -> (Δd, Δθ) of the rear-axle centre.

    ``Δd = s·cos α``, ``Δθ = s·sin α / L`` (Sun–Gao, Snowhite model; OptiOdom tricycle).

    Parameters
    ----------
    travel : array_like, shape (M,)
        Distance s the steering/driving front wheel rolled over each step [m].
    steer : array_like, shape (M,)
        Steering angle α [rad], positive to the left, offset already applied.
    wheel_to_axle : float
        L [m].
    """
    travel = np.asarray(travel, dtype=float)
    steer = np.asarray(steer, dtype=float)
    return travel * np.cos(steer), travel * np.sin(steer) / wheel_to_axle


def tricycle_body_jacobian(
    travel: ArrayLike, steer: ArrayLike, wheel_to_axle: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(s, α, L), shape (M, 2, 3)."""
    s = np.asarray(travel, dtype=float)
    a = np.asarray(steer, dtype=float)
    jac = np.zeros(s.shape + (2, 3))
    jac[..., 0, 0] = np.cos(a)
    jac[..., 0, 1] = -s * np.sin(a)
    jac[..., 1, 0] = np.sin(a) / wheel_to_axle
    jac[..., 1, 1] = s * np.cos(a) / wheel_to_axle
    jac[..., 1, 2] = -s * np.sin(a) / wheel_to_axle**2
    return jac


def _car_denominator(steer: NDArray[np.float64], wheel_base: float, encoder_offset: float,
                     encoder_at: str) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                               NDArray[np.float64], NDArray[np.float64]]:
    """cos α, sin α, D and r = cos α − sin α·H/L of :func:`car_body_steps` (D = r for a rear
    wheel, √(r² + sin² α) for a front wheel); a ModelError where a rear measuring wheel is at
    or beyond the centre of the turn (r ≤ 0: its speed says nothing about the car's), or
    the steering angle is at or past ±90°."""
    if np.any(np.abs(steer) >= np.pi / 2):
        raise ModelError(f"a steering angle of {float(np.max(np.abs(steer))):.3g} rad is at or past ±90°: "
                         "no car's road wheel steers so (a steering-wheel angle needs the robot file's "
                         "steering_ratio; degrees need steer_deg)")
    c, sn = np.cos(steer), np.sin(steer)
    r = c - sn * (encoder_offset / wheel_base)
    if encoder_at == "front":
        return c, sn, np.sqrt(r * r + sn * sn), r
    if encoder_at != "rear":
        raise ModelError(f"encoder_at must be 'rear' or 'front', got {encoder_at!r}")
    if np.any(r <= 0):
        raise ModelError(f"a steering angle of {float(np.max(np.abs(steer))):.3g} rad puts the rear "
                         f"measuring wheel (offset {encoder_offset:g} m) at or beyond the centre of "
                         "the turn (tan α·H/L >= 1): its speed cannot give the car's")
    return c, sn, r, r


def car_speed_factor(steer: ArrayLike, wheel_base: float, encoder_offset: float = 0.0,
                     encoder_at: str = "rear") -> NDArray[np.float64]:
    """Rear-axle speed per unit speed of the measuring wheel, v / v_e (:class:`~odomkit.robot.Car`).

    Rear wheel at lateral offset H: v_e = v − ωH with ω = v·tan α/L, so
    v/v_e = 1/(1 − tan α·H/L) (docs/reference/robot-files.md). Front wheel at (L, H): its contact point moves
    at (v − ωH, ωL) and an Ackermann wheel rolls along that direction, so
    v/v_e = 1/√((1 − tan α·H/L)² + tan² α) = cos α/√((cos α − sin α·H/L)² + sin² α)
    (H = 0: cos α, the tricycle). Derived here; checked against a closed circle.

    Examples
    --------
    >>> float(car_speed_factor(0.0, 2.7, 0.8))
    1.0
    >>> round(float(car_speed_factor(0.3, 2.0, 0.0, "front")), 12) == round(float(np.cos(0.3)), 12)
    True
    >>> round(float(car_speed_factor(0.3, 2.0, 0.5)), 12)   # 1/(1 − tan(0.3)·0.5/2)
    1.083815885307
    """
    c, sn, d, _ = _car_denominator(np.asarray(steer, dtype=float), wheel_base, encoder_offset,
                                   encoder_at)
    return np.asarray(c / d)


def car_body_steps(
    travel: ArrayLike, steer: ArrayLike, wheel_base: float, encoder_offset: float = 0.0,
    encoder_at: str = "rear",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Measuring-wheel travel and front steering angle -> (Δd, Δθ) of the rear-axle centre.

    ``Δd = s·cos α / D``, ``Δθ = Δd·tan α / L = s·sin α / (L·D)`` with r = cos α − sin α·H/L
    and D = r (rear wheel) or √(r² + sin² α) (front wheel): :func:`car_speed_factor`
    written without tan, so it stays finite at α = ±π/2.

    Parameters
    ----------
    travel : array_like, shape (M,)
        Distance s the measuring wheel rolled over each step [m].
    steer : array_like, shape (M,)
        Bicycle steering angle α [rad], positive to the left, offset already applied.
    wheel_base : float
        L [m].
    encoder_offset : float
        H, lateral offset of the measuring wheel [m], + left.
    encoder_at : {"rear", "front"}
    """
    s = np.asarray(travel, dtype=float)
    c, sn, d, _ = _car_denominator(np.asarray(steer, dtype=float), wheel_base, encoder_offset,
                                   encoder_at)
    return s * c / d, s * sn / (wheel_base * d)


def car_body_jacobian(
    travel: ArrayLike, steer: ArrayLike, wheel_base: float, encoder_offset: float = 0.0,
    encoder_at: str = "rear",
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(s, α, L) of :func:`car_body_steps`, shape (M, 2, 3).

    With h = H/L, r = cos α − sin α·h: rear D = r, ∂D/∂α = −sin α − cos α·h,
    ∂D/∂L = sin α·h/L; front D = √(r² + sin² α), ∂D/∂α = (r·(−sin α − cos α·h) +
    sin α cos α)/D, ∂D/∂L = r·sin α·h/(L·D). Then Δd = s cos α/D and Δθ = s sin α/(L D)
    differentiate by the quotient rule. Checked against finite differences.
    """
    s = np.asarray(travel, dtype=float)
    a = np.asarray(steer, dtype=float)
    s, a = np.broadcast_arrays(s, a)
    length = wheel_base
    c, sn, d, r = _car_denominator(a, length, encoder_offset, encoder_at)
    h = encoder_offset / length
    dr_da = -sn - c * h
    dr_dl = sn * h / length
    if encoder_at == "front":
        dd_da = (r * dr_da + sn * c) / d
        dd_dl = r * dr_dl / d
    else:
        dd_da, dd_dl = dr_da, dr_dl
    jac = np.zeros(s.shape + (2, 3))
    jac[..., 0, 0] = c / d
    jac[..., 0, 1] = s * (-sn / d - c * dd_da / d**2)
    jac[..., 0, 2] = -s * c * dd_dl / d**2
    jac[..., 1, 0] = sn / (length * d)
    jac[..., 1, 1] = s * (c / (length * d) - sn * dd_da / (length * d**2))
    jac[..., 1, 2] = -s * sn / (length**2 * d) - s * sn * dd_dl / (length * d**2)
    return jac


def steering_body_steps(robot: Tricycle | Car, travel: ArrayLike, steer: ArrayLike
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(Δd, Δθ) of a steered vehicle (tricycle or car) from the travel of its measuring
    wheel and its steering angle (offset applied): :func:`tricycle_body_steps` or
    :func:`car_body_steps` with the robot's geometry."""
    if isinstance(robot, Tricycle):
        return tricycle_body_steps(travel, steer, robot.wheel_to_axle)
    if isinstance(robot, Car):
        return car_body_steps(travel, steer, robot.wheel_base, robot.encoder_offset, robot.encoder_at)
    raise ModelError(f"not a steered vehicle (tricycle or car): {type(robot).__name__}")


def steering_body_jacobian(robot: Tricycle | Car, travel: ArrayLike, steer: ArrayLike
                           ) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(s, α, L) of :func:`steering_body_steps`, shape (M, 2, 3) (L is the
    tricycle's ``wheel_to_axle`` or the car's ``wheel_base``)."""
    if isinstance(robot, Tricycle):
        return tricycle_body_jacobian(travel, steer, robot.wheel_to_axle)
    if isinstance(robot, Car):
        return car_body_jacobian(travel, steer, robot.wheel_base, robot.encoder_offset,
                                 robot.encoder_at)
    raise ModelError(f"not a steered vehicle (tricycle or car): {type(robot).__name__}")


def step_displacement(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: Method = "exact"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """World-frame displacement (Δx, Δy) of each step, starting at heading ``theta``.

    ``euler`` uses the heading at the start of the step, ``midpoint`` (RK2) the heading
    at its middle, ``exact`` the constant-curvature arc (midpoint heading times the
    chord factor sinc(Δθ/2)). All arrays broadcast; shapes (M,).
    """
    theta = np.asarray(theta, dtype=float)
    dd = np.asarray(dd, dtype=float)
    dtheta = np.asarray(dtheta, dtype=float)
    if method == "euler":
        heading, length = theta, dd
    elif method == "midpoint":
        heading, length = theta + 0.5 * dtheta, dd
    elif method == "exact":
        heading, length = theta + 0.5 * dtheta, dd * sinc_half(dtheta)
    else:
        raise ValueError(f"unknown integration method {method!r}; expected one of {METHODS}")
    return length * np.cos(heading), length * np.sin(heading)


def step_jacobians(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: Method = "exact"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Jacobians of one step of :func:`step_displacement` plus ``θ' = θ + Δθ``.

    Returns
    -------
    F : ndarray, shape (M, 3, 3)
        ∂(x', y', θ')/∂(x, y, θ) = [[1, 0, −Δy], [0, 1, Δx], [0, 0, 1]]
        (Chong–Kleeman eq. 16 in chord form, valid on straight lines too).
    G : ndarray, shape (M, 3, 2)
        ∂(x', y', θ')/∂(Δd, Δθ).
    """
    theta = np.asarray(theta, dtype=float)
    dd = np.asarray(dd, dtype=float)
    dtheta = np.asarray(dtheta, dtype=float)
    theta, dd, dtheta = np.broadcast_arrays(theta, dd, dtheta)
    dx, dy = step_displacement(theta, dd, dtheta, method)
    m = theta.shape
    F = np.zeros(m + (3, 3))
    F[..., 0, 0] = F[..., 1, 1] = F[..., 2, 2] = 1.0
    F[..., 0, 2] = -dy
    F[..., 1, 2] = dx
    G = np.zeros(m + (3, 2))
    G[..., 2, 1] = 1.0
    if method == "euler":
        G[..., 0, 0], G[..., 1, 0] = np.cos(theta), np.sin(theta)
        return F, G
    heading = theta + 0.5 * dtheta
    c, s = np.cos(heading), np.sin(heading)
    factor = sinc_half(dtheta) if method == "exact" else np.ones_like(dtheta)
    dfactor = sinc_half_derivative(dtheta) if method == "exact" else np.zeros_like(dtheta)
    G[..., 0, 0] = factor * c
    G[..., 1, 0] = factor * s
    # d/dΔθ [Δd·f(Δθ)·cos(θ+Δθ/2)] = Δd·(f'·cos − f·sin/2)
    G[..., 0, 1] = dd * (dfactor * c - 0.5 * factor * s)
    G[..., 1, 1] = dd * (dfactor * s + 0.5 * factor * c)
    return F, G


@dataclass(frozen=True)
class BodySteps:
    """Body motion of every step of a log (step k goes from row k to row k+1).

    Parameters
    ----------
    dd : ndarray, shape (M,)
        Arc length travelled by the reference point [m].
    dtheta : ndarray, shape (M,)
        Heading change [rad]. For direct-heading odometry it is the change of the
        measured heading.
    dt : ndarray, shape (M,)
        Step duration [s] (zero for repeated timestamps).
    inputs : mapping of str to ndarray, shape (M,)
        The raw per-step inputs the covariance engines need, in SI units:
        diff ``d_left``, ``d_right`` [m] (from ticks, metres or wheel speeds); tricycle
        and car ``travel`` (of the measuring wheel) [m], ``steer`` [rad]; gyro and
        unicycle ``yaw_rate`` [rad/s]; compass ``heading`` (shape (M+1,)) [rad].
    robot : Robot
        The robot that produced these steps.

    Notes
    -----
    The heading at the start of each step depends on the initial pose, so it is not
    stored here: integrate with :func:`odomkit.integrate.dead_reckon` and take
    ``poses[:-1, 2]``.
    """

    dd: NDArray[np.float64]
    dtheta: NDArray[np.float64]
    dt: NDArray[np.float64]
    inputs: Mapping[str, NDArray[np.float64]]
    robot: Robot

    def __len__(self) -> int:
        return int(self.dd.shape[0])


def _travel(log: OdometryLog, m_per_tick: float, correction: float = 1.0,
            prefix: str = "") -> NDArray[np.float64]:
    """Per-step distance [m] from ``ticks``/``dist`` increments or a ``speed`` rate, shape (N − 1,);
    ``prefix`` ``"left"``/``"right"``: that wheel's ``ticks_*``, ``dist_*`` or ``speed_*``.

    Increments count the step that ends at their row (row k+1 for step k). A speed [m/s]
    is held from its row over the step after it (zero-order hold: ``speed[:-1]·Δt``), as
    :mod:`odomkit.log` says of every rate: a speed sampled at row k is the best knowledge
    of the step after it, and a command logged when it changes holds exactly so. Wheel
    speeds follow the same rule as a body ``speed``, so both read alike.

    Only tick counts are converted by ``m_per_tick`` [m/tick]; ``dist`` [m] and ``speed``
    [m/s] are metres already, whatever encoder the robot describes (issue 10: a metre log
    read with a robot file that has an encoder resolution was scaled by ~1e-4). The
    dimensionless calibration ``correction`` (c_left, c_right, c_scale;
    Borenstein–Feng eq. 4.30–4.31) applies to every form: it corrects the wheel, not the unit.
    """
    suffix = f"_{prefix}" if prefix else ""
    if f"ticks{suffix}" in log.channels:
        return log.channels[f"ticks{suffix}"][1:] * (correction * m_per_tick)
    if f"dist{suffix}" in log.channels:
        return log.channels[f"dist{suffix}"][1:] * correction
    if f"speed{suffix}" in log.channels:
        return log.channels[f"speed{suffix}"][:-1] * np.diff(log.t) * correction
    wanted = f"ticks{suffix} or dist{suffix} or speed{suffix}"
    raise InputError(f"log has no {wanted} channel (it has {sorted(log.channels)})",
                     source=log.source)


def _steer_per_step(log: OdometryLog) -> NDArray[np.float64]:
    """Steering angle over each step: with a speed rate (held from row k) the angle of
    row k; with increments (counted over the step) the mean of both ends, which is
    second-order accurate for a steering angle that changes during the step."""
    steer = log.channel("steer")
    if "speed" in log.channels and "ticks" not in log.channels and "dist" not in log.channels:
        return steer[:-1]
    return 0.5 * (steer[:-1] + steer[1:])


def _diff_steps(robot: DiffDrive, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    wheel_channels(log.channels, log.source)  # one form for both wheels, or a clear error
    d_left = _travel(log, robot.m_per_tick_left, robot.c_left, "left")
    d_right = _travel(log, robot.m_per_tick_right, robot.c_right, "right")
    dd, dtheta = diff_body_steps(d_left, d_right, robot.effective_wheel_base)
    return BodySteps(dd, dtheta, dt, {"d_left": d_left, "d_right": d_right}, robot)


def _tricycle_steps(robot: Tricycle, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    travel = _travel(log, robot.m_per_tick, robot.c_scale)
    steer = _steer_per_step(log) / robot.steering_ratio + robot.steering_offset
    dd, dtheta = tricycle_body_steps(travel, steer, robot.wheel_to_axle)
    return BodySteps(dd, dtheta, dt, {"travel": travel, "steer": steer}, robot)


def _gyro_steps(robot: GyroOdometry, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    dd = _travel(log, robot.m_per_tick)
    rate = robot.gyro_scale * (log.channel("yaw_rate")[:-1] - robot.gyro_bias)
    return BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, robot)


def _compass_steps(robot: CompassOdometry, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    dd = _travel(log, robot.m_per_tick)
    heading = unwrap_angle(log.channel("heading") + robot.heading_offset)
    return BodySteps(dd, np.diff(heading), dt, {"heading": heading}, robot)


def _unicycle_steps(robot: Unicycle, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    if "ticks" in log.channels:
        # A unicycle's channels are body velocities; ticks need a wheel size (gyro robot).
        raise InputError("a unicycle reads speed [m/s] (or dist [m]) and yaw_rate, not ticks; "
                         "describe an encoder robot as type = \"gyro\"", source=log.source)
    dd = _travel(log, 1.0, robot.c_scale)
    measured = log.channel("yaw_rate")[:-1]
    rate = np.where(unicycle_moving(dd, measured),
                    robot.yaw_rate_scale * (measured - robot.yaw_rate_bias), 0.0)
    return BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, robot)


def moving_speed(steps: BodySteps) -> float | None:
    """The median speed [m/s] of the steps that move and take time, |Δd|/Δt (None where
    none does): a few spikes (a counter that wraps, read as increments) do not move it."""
    dt = np.asarray(steps.dt, dtype=float)
    with np.errstate(all="ignore"):
        speed = np.abs(np.asarray(steps.dd, dtype=float)) / dt
    moving = speed[(dt > 0) & np.isfinite(speed) & (speed > 0)]
    return float(np.median(moving)) if moving.size else None


def too_fast(steps: BodySteps, log: OdometryLog) -> tuple[str, str] | None:
    """(what, what to do) where the moving steps of ``steps`` (of ``log``) go faster, at the
    median, than any wheeled vehicle (:data:`odomkit.units.FASTEST_SPEED`), else None.

    The speed is :func:`moving_speed`'s: a few spikes do not move it, a whole log read wrong
    does (a raw counter read as increments: every row's count is the distance since the
    start; ticks read as metres; a distance in mm or a speed in mm/s read as metres). The
    advice names the channel the travel came from.
    """
    from odomkit.units import FAST_TRAVEL, FASTEST_SPEED

    median = moving_speed(steps)
    if median is None or not median > FASTEST_SPEED:
        return None
    travel = float(np.nansum(np.abs(steps.dd)))
    duration = float(log.t[-1] - log.t[0]) if len(log) > 1 else 0.0
    what = (f"the odometry moves at {median:.3g} m/s (the median of its moving steps; {travel:.4g} m in "
            f"{duration:.4g} s), {FAST_TRAVEL} ({FASTEST_SPEED:g} m/s)")
    channels = set(log.channels)
    if any(c.startswith("ticks") for c in channels):
        advice = ("a raw counter read as increments? (--cumulative, and --wrap-bits where it wraps); else "
                  "m_per_tick in the robot file (metres per tick: the wheel's circumference over the ticks "
                  "per revolution)")
    elif any(c.startswith("dist") for c in channels):
        advice = ("a distance since the start read as increments (--cumulative), or in mm or cm read as "
                  "metres?")
    else:
        advice = ("a speed in mm/s or cm/s read as m/s, or a time column read in a unit finer than its own "
                  "(--time-unit)?")
    return what, advice


def unicycle_moving(dd: ArrayLike, yaw_rate: ArrayLike) -> NDArray[np.bool_]:
    """Which steps of a unicycle move: those with travel ``dd`` [m] or a yaw rate [rad/s]
    other than zero, shape (n,).

    A unicycle's channels are body velocities, commanded (``cmd_vel``) or reported by the
    base (``odom``): zero speed and zero yaw rate is a base standing still, which no
    yaw-rate bias turns and no noise moves (:class:`odomkit.noise.kelly.GyroNoise`). The
    calibration, the bias sensitivities and the Monte Carlo apply the same rule.
    """
    return (np.asarray(dd) != 0) | (np.asarray(yaw_rate) != 0)


def car_road_wheel_angle(robot: Car, measured: ArrayLike) -> NDArray[np.float64]:
    """The bicycle's road-wheel angle α [rad] of a measured steering angle, shape as given:
    α = s + steering_cubic·s³ + steering_offset with s = measured / steering_ratio
    (:class:`~odomkit.robot.Car`)."""
    s = np.asarray(measured, dtype=float) / robot.steering_ratio
    return s + robot.steering_cubic * s**3 + robot.steering_offset


def car_measured_steer(robot: Car, alpha: float) -> float:
    """The measured steering angle that gives road-wheel angle ``alpha`` [rad]: the inverse
    of :func:`car_road_wheel_angle` (Newton's method on s + k·s³ = α − offset from s = α −
    offset; one step for k = 0)."""
    target, k, s = alpha - robot.steering_offset, robot.steering_cubic, alpha - robot.steering_offset
    for _ in range(50):
        step = (s + k * s**3 - target) / (1 + 3 * k * s**2)
        s -= step
        if abs(step) <= 1e-15 * max(1.0, abs(s)):
            break
    return s * robot.steering_ratio


def _car_steps(robot: Car, log: OdometryLog, dt: NDArray[np.float64]) -> BodySteps:
    travel = _travel(log, robot.m_per_tick, robot.c_scale)
    steer = car_road_wheel_angle(robot, _steer_per_step(log))
    _warn_past_lock(steer, robot, log.source)
    try:
        dd, dtheta = car_body_steps(travel, steer, robot.wheel_base, robot.encoder_offset,
                                    robot.encoder_at)
    except ModelError as exc:
        raise InputError(str(exc), source=log.source) from None
    return BodySteps(dd, dtheta, dt, {"travel": travel, "steer": steer}, robot)


#: A car's road wheels turn about ±35–45° at full lock; a bicycle angle beyond 60° is a
#: steering-wheel angle read without its ratio (Car.steering_ratio), or degrees as radians.
CAR_LOCK = np.pi / 3


def _warn_past_lock(steer: NDArray[np.float64], robot: Car, source: str) -> None:
    """Warn where a car's road-wheel angle goes past any car's lock (:data:`CAR_LOCK`): the
    track would be silently wrong (tan α of a steering-wheel angle)."""
    finite = np.abs(steer[np.isfinite(steer)])
    if finite.size and float(finite.max()) > CAR_LOCK:
        warnings.warn(
            f"{source}: the car's road-wheel angle reaches {float(finite.max()):.3g} rad "
            f"({math.degrees(float(finite.max())):.0f}°) with steering_ratio {robot.steering_ratio:g}, past "
            f"any car's lock ({math.degrees(CAR_LOCK):.0f}°): is the steer channel a steering-wheel angle? "
            f"set steering_ratio in the robot file (about 12-18 for a car), or is it in degrees (steer_deg)?",
            UserWarning, stacklevel=2)


# One entry per vehicle, keyed by its robot-file type: a new vehicle adds one function here.
_BODY_STEPS: dict[str, Callable[[Any, OdometryLog, NDArray[np.float64]], BodySteps]] = {
    "diff": _diff_steps,
    "tricycle": _tricycle_steps,
    "gyro": _gyro_steps,
    "compass": _compass_steps,
    "unicycle": _unicycle_steps,
    "car": _car_steps,
}


def body_steps(robot: Robot, log: OdometryLog) -> BodySteps:
    """Convert a log's sensor channels into body motion for ``robot``.

    Parameters
    ----------
    robot : DiffDrive | Tricycle | GyroOdometry | CompassOdometry | Unicycle | Car
    log : OdometryLog, N rows

    Returns
    -------
    BodySteps with M = N − 1 steps.
    """
    convert = _BODY_STEPS.get(getattr(robot, "type_name", ""))
    if convert is None:
        raise ModelError(f"not an odomkit robot: {type(robot).__name__}")
    return convert(robot, log, np.diff(log.t))
