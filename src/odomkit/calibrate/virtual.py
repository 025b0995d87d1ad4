"""Virtual UMBmark: a simulated differential robot driving the square by its own odometry.

The robot has *true* wheels and wheel base (set by :class:`SystematicErrors`) and
*believed* ones (a :class:`~odomkit.robot.DiffDrive`, nominal or corrected). Its
controller commands wheel rotations (encoder ticks) that its odometry, using the believed
parameters, reads as a straight leg of length ``side`` or a 90° turn on the spot; the true
pose follows what the true wheels do with those same ticks. The return position error is
true minus odometry end position (Borenstein–Feng eq. 3.1).

Stopping: within a segment the controller commands the same believed wheel increment
every step (``step`` metres of wheel travel), so the odometry's progress (distance along
a leg, heading change in a turn) grows linearly; the segment ends in the step where the
odometry reaches its target, and that last step is shortened to the exact fraction
needed, so the stop is not quantised to the step size.

Wheel noise (:class:`~odomkit.noise.WheelNoise`, Chong–Kleeman eq. 4): the ground
distance a wheel really travels in a step differs from what its ticks imply by white
noise of variance k²·|d| (slip, contact-point wander). The odometry sees only the ticks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.calibrate.umbmark import UmbmarkResult, Variant, apply_corrections, umbmark
from odomkit.errors import ModelError
from odomkit.kinematics import step_displacement
from odomkit.noise import WheelNoise
from odomkit.robot import DiffDrive, SystematicErrors, true_robot

if TYPE_CHECKING:
    from odomkit.log import OdometryLog

__all__ = [
    "SystematicErrors",
    "VirtualRuns",
    "UmbmarkIterations",
    "true_robot",
    "square_wheel_steps",
    "run_virtual_umbmark",
    "iterate_umbmark",
    "virtual_umbmark_logs",
]


class VirtualRuns(NamedTuple):
    """Result of :func:`run_virtual_umbmark`; unpacks as a tuple.

    errors_cw, errors_ccw : (n, 2) return position errors, true − odometry [m] (eq. 3.1).
    true_end_cw, true_end_ccw : (n, 3) true end poses [x, y, θ] (θ continuous).
    odom_end_cw, odom_end_ccw : (n, 3) end poses computed by odometry.
    """

    errors_cw: NDArray[np.float64]
    errors_ccw: NDArray[np.float64]
    true_end_cw: NDArray[np.float64]
    true_end_ccw: NDArray[np.float64]
    odom_end_cw: NDArray[np.float64]
    odom_end_ccw: NDArray[np.float64]


def _segment(total: float, step: float) -> NDArray[np.float64]:
    """Equal increments of ``step`` with the last one cut so that they sum to ``total``."""
    n = max(1, math.ceil(total / step - 1e-9))
    inc = np.full(n, step)
    inc[-1] = total - step * (n - 1)
    return inc


def square_wheel_steps(
    robot: DiffDrive, side: float, direction: str, step: float = 0.01
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Believed wheel travel per step for one UMBmark square: four legs, four 90° turns.

    Parameters
    ----------
    robot : DiffDrive
        The believed robot; its effective wheel base sets how much wheel travel its
        odometry reads as 90°.
    side : float
        Leg length L [m].
    direction : {"cw", "ccw"}
    step : float
        Believed wheel travel per integration step [m].

    Returns
    -------
    d_left, d_right : ndarray, shape (S,)
        Wheel travel the odometry believes each step [m]; legs first, each followed by a
        turn on the spot (the fourth turn too, as Borenstein–Feng did).

    Examples
    --------
    >>> dl, dr = square_wheel_steps(DiffDrive(0.4), 1.0, "ccw", step=0.5)
    >>> round(float((dl + dr).sum() / 2), 12), round(float((dr - dl).sum() / 0.4), 9)
    (4.0, 6.283185307)
    """
    if direction not in ("cw", "ccw"):
        raise ModelError(f"direction must be 'cw' or 'ccw', got {direction!r}")
    sign = 1.0 if direction == "ccw" else -1.0
    leg = _segment(side, step)
    # A believed 90° turn needs each wheel to travel b_eff·(π/2)/2 (Borenstein–Feng eq. 2.10).
    turn = _segment(0.25 * math.pi * robot.effective_wheel_base, step)
    left = np.concatenate([leg, -sign * turn] * 4)
    right = np.concatenate([leg, sign * turn] * 4)
    return left, right


def _tracks(d_left: NDArray[np.float64], d_right: NDArray[np.float64],
            wheel_base: float) -> NDArray[np.float64]:
    """Poses after each step from (0, 0, 0); rows are runs, columns steps -> (..., S, 3)."""
    dd = 0.5 * (d_right + d_left)  # Borenstein–Feng eq. (2.2)–(2.4)
    dtheta = (d_right - d_left) / wheel_base
    theta_end = np.cumsum(dtheta, axis=-1)
    dx, dy = step_displacement(theta_end - dtheta, dd, dtheta, "exact")
    return np.stack([np.cumsum(dx, axis=-1), np.cumsum(dy, axis=-1), theta_end], axis=-1)


def _end_poses(d_left: NDArray[np.float64], d_right: NDArray[np.float64],
               wheel_base: float) -> NDArray[np.float64]:
    """End poses of dead reckoning from (0, 0, 0); rows are runs, columns steps."""
    return _tracks(d_left, d_right, wheel_base)[..., -1, :]


def _generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def _true_steps(true_errors: SystematicErrors, robot: DiffDrive, side: float, direction: str,
                runs: int, noise: WheelNoise | None, rng: np.random.Generator, step: float
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                           NDArray[np.float64], DiffDrive]:
    """Believed wheel travel (S,) and true wheel travel (runs, S) of each step."""
    bel_left, bel_right = square_wheel_steps(robot, side, direction, step)
    truth = true_robot(true_errors, robot)
    # Same ticks, true metres per tick: ticks = believed distance / believed scale.
    true_left = np.broadcast_to(bel_left * (truth.m_per_tick_left / robot.scale_left),
                                (runs, bel_left.size)).copy()
    true_right = np.broadcast_to(bel_right * (truth.m_per_tick_right / robot.scale_right),
                                 (runs, bel_right.size)).copy()
    if noise is not None:
        # Chong–Kleeman eq. (4): variance k²·|d| per step, independent steps and wheels.
        for travel, k in ((true_left, noise.k_left), (true_right, noise.k_right)):
            travel += k * np.sqrt(np.abs(travel)) * rng.standard_normal(travel.shape)
    return bel_left, bel_right, true_left, true_right, truth


def _drive(true_errors: SystematicErrors, robot: DiffDrive, side: float, direction: str,
           runs: int, noise: WheelNoise | None, rng: np.random.Generator,
           step: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    bel_left, bel_right, true_left, true_right, truth = _true_steps(
        true_errors, robot, side, direction, runs, noise, rng, step)
    true_end = _end_poses(true_left, true_right, truth.wheel_base)
    odom_end = np.broadcast_to(_end_poses(bel_left, bel_right, robot.effective_wheel_base),
                               (runs, 3)).copy()
    return true_end, odom_end


def _validate(true_errors: SystematicErrors, believed_robot: DiffDrive, side: float,
              runs_per_direction: int, step: float) -> None:
    if not isinstance(true_errors, SystematicErrors):
        raise ModelError("true_errors must be an odomkit.calibrate.virtual.SystematicErrors")
    if not isinstance(believed_robot, DiffDrive):
        raise ModelError("believed_robot must be an odomkit.robot.DiffDrive")
    validate.positive(side, "side", unit="m")
    validate.positive(step, "step", unit="m")
    validate.positive_int(runs_per_direction, "runs_per_direction")


def run_virtual_umbmark(
    true_errors: SystematicErrors,
    believed_robot: DiffDrive,
    side: float,
    runs_per_direction: int,
    noise: WheelNoise | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    step: float = 0.01,
) -> VirtualRuns:
    """Drive the UMBmark square ``runs_per_direction`` times CW and CCW.

    Parameters
    ----------
    true_errors : SystematicErrors
        E_d, E_b, E_s of the real robot relative to ``believed_robot``'s nominal values.
    believed_robot : DiffDrive
        What the odometry (and so the controller) uses, corrections included.
    side : float
        L [m].
    runs_per_direction : int
        n ≥ 1.
    noise : WheelNoise, optional
        Per-wheel random error; None for a noise-free robot (all runs identical).
    rng : numpy.random.Generator or int, optional
        Source of the noise (a seed is accepted); CW runs draw first, then CCW.
    step : float
        Wheel travel per integration step [m]; it matters only with noise (each step
        gets independent noise), the noise-free result is exact for any step.

    Returns
    -------
    VirtualRuns
        ``(errors_cw, errors_ccw, true_end_cw, true_end_ccw, odom_end_cw, odom_end_ccw)``.

    Examples
    --------
    A wheel base 1 % longer than believed: every turn falls short by α = (π/2)(1 − 1/1.01),
    and the CW run ends where Borenstein–Feng's eq. (4.5)–(4.8) put it before their
    small-angle approximation:

    >>> runs = run_virtual_umbmark(SystematicErrors(E_b=1.01), DiffDrive(0.34), 4.0, 1)
    >>> a, L = np.pi / 2 * (1 - 1 / 1.01), 4.0
    >>> x4 = L * (1 + np.sin(a) - np.cos(2 * a) - np.sin(3 * a))
    >>> y4 = L * (-np.cos(a) - np.sin(2 * a) + np.cos(3 * a))
    >>> np.allclose(runs.errors_cw, [[x4, y4]], rtol=0, atol=1e-12)
    True
    """
    _validate(true_errors, believed_robot, side, runs_per_direction, step)
    gen = _generator(rng)
    n = int(runs_per_direction)
    true_cw, odom_cw = _drive(true_errors, believed_robot, side, "cw", n, noise, gen, step)
    true_ccw, odom_ccw = _drive(true_errors, believed_robot, side, "ccw", n, noise, gen, step)
    return VirtualRuns(
        errors_cw=true_cw[:, :2] - odom_cw[:, :2],  # Borenstein–Feng eq. (3.1)
        errors_ccw=true_ccw[:, :2] - odom_ccw[:, :2],
        true_end_cw=true_cw,
        true_end_ccw=true_ccw,
        odom_end_cw=odom_cw,
        odom_end_ccw=odom_ccw,
    )


@dataclass(frozen=True)
class UmbmarkIterations:
    """Result of :func:`iterate_umbmark`.

    Attributes
    ----------
    robots : tuple of DiffDrive, length k+1
        ``robots[0]`` the robot as given, ``robots[i]`` after i compensations.
    results : tuple of UmbmarkResult, length k+1
        UMBmark of each robot (``results[i]`` was measured with ``robots[i]``).
    e_max_syst : tuple of float, length k+1
        E_max,syst of each robot [m].
    """

    robots: tuple[DiffDrive, ...]
    results: tuple[UmbmarkResult, ...]
    e_max_syst: tuple[float, ...]


def iterate_umbmark(
    true_errors: SystematicErrors,
    believed_robot: DiffDrive,
    side: float,
    runs_per_direction: int,
    iterations: int = 1,
    noise: WheelNoise | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    variant: Variant = "borenstein-feng",
    step: float = 0.01,
) -> UmbmarkIterations:
    """Run UMBmark, apply its corrections, run again — ``iterations`` times.

    Each pass treats the compensated robot as a new one (Borenstein–Feng section V);
    corrections compose (:func:`~odomkit.calibrate.umbmark.apply_corrections`).

    Examples
    --------
    >>> it = iterate_umbmark(SystematicErrors(1.002, 1.01), DiffDrive(0.34), 4.0, 1)
    >>> [round(e, 3) for e in it.e_max_syst]   # [m] before and after one compensation
    [0.448, 0.005]
    """
    iterations = validate.non_negative_int(iterations, "iterations")
    gen = _generator(rng)
    robots = [believed_robot]
    results: list[UmbmarkResult] = []
    for i in range(int(iterations) + 1):
        runs = run_virtual_umbmark(true_errors, robots[i], side, runs_per_direction, noise, gen,
                                   step=step)
        results.append(umbmark(runs.errors_cw, runs.errors_ccw, side,
                               robots[i].effective_wheel_base, variant=variant))
        if i < iterations:
            robots.append(apply_corrections(robots[i], results[i]))
    return UmbmarkIterations(tuple(robots), tuple(results),
                             tuple(r.e_max_syst for r in results))


def virtual_umbmark_logs(
    true_errors: SystematicErrors,
    believed_robot: DiffDrive,
    side: float,
    runs_per_direction: int,
    noise: WheelNoise | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    step: float = 0.01,
    speed: float = 0.2,
) -> list[OdometryLog]:
    """The virtual UMBmark runs as logs with ground truth (CW runs first, then CCW).

    Each log has one row per integration step plus the start row: channels
    ``ticks_left``, ``ticks_right`` (increments, *not* rounded to integers: what the
    believed robot's ``m_per_tick_*`` and ``c_*`` turn into its believed wheel travel),
    ``ground_truth`` the true pose after each step, time at ``speed`` m/s of wheel travel
    (Borenstein–Feng drove at 0.2 m/s), and ``meta`` {"direction", "side"}. With the same
    ``rng`` state the runs are the same as :func:`run_virtual_umbmark`'s.

    Examples
    --------
    >>> logs = virtual_umbmark_logs(SystematicErrors(E_b=1.01), DiffDrive(0.34), 4.0, 1)
    >>> [log.meta["direction"] for log in logs], logs[0].ground_truth.shape
    (['cw', 'ccw'], (1709, 3))
    """
    from odomkit.log import OdometryLog

    validate.positive(speed, "speed", unit="m/s")
    _validate(true_errors, believed_robot, side, runs_per_direction, step)
    gen = _generator(rng)
    logs: list[OdometryLog] = []
    for direction in ("cw", "ccw"):
        bel_left, bel_right, true_left, true_right, truth = _true_steps(
            true_errors, believed_robot, side, direction, int(runs_per_direction), noise, gen,
            step)
        gt = _tracks(true_left, true_right, truth.wheel_base)
        t = np.concatenate([[0.0], np.cumsum(np.maximum(np.abs(bel_left), np.abs(bel_right)))])
        ticks_left = np.concatenate([[0.0], bel_left / believed_robot.scale_left])
        ticks_right = np.concatenate([[0.0], bel_right / believed_robot.scale_right])
        for i in range(gt.shape[0]):
            logs.append(OdometryLog(
                t / speed,
                {"ticks_left": ticks_left.copy(), "ticks_right": ticks_right.copy()},
                np.vstack([np.zeros((1, 3)), gt[i]]),
                source=f"<virtual UMBmark {direction} run {i + 1}>",
                meta={"direction": direction, "side": float(side)},
            ))
    return logs
