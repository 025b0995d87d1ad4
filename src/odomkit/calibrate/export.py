"""What robots consume, as numbers: the ROS 2 ``diff_drive_controller`` and
``tricycle_controller`` settings of a calibrated robot, and the odometry twist covariance
that a fitted white noise implies (what ``robot_localization`` fuses).

The YAML files the controllers read are written by :mod:`odomkit.io.ros`; the corrected
robot itself by :func:`odomkit.io.robotfile.write_robot`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.errors import InputError, ModelError
from odomkit.kinematics import car_measured_steer, car_speed_factor
from odomkit.log import OdometryLog
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Robot, Tricycle, Unicycle

__all__ = ["controller_radius", "diff_drive_controller_parameters", "tricycle_controller_parameters",
           "turn_noise_note", "twist_covariance", "TwistCovariance"]


def controller_radius(given: float | None, file_radius: float | None,
                      source: str | None = None) -> float | None:
    """The nominal wheel radius [m] of a ROS 2 controller's parameters (``calibrate --ros-yaml``,
    ``report``'s snippet): ``given`` (``--wheel-radius``), else the robot file's own
    (``file_radius``: :func:`odomkit.workflows.calibration.file_wheel_radius`, the mean of its
    wheels), else None (a file in metres per tick, wheel speeds logged with ``m_per_tick = 1``).

    A ``given`` radius that is not a positive number of metres, or that differs from the
    file's, is an :class:`~odomkit.errors.InputError` naming ``source`` (the robot file): the
    multipliers are computed against the file's nominal wheels.

    Examples
    --------
    >>> controller_radius(0.035, None), controller_radius(None, 0.05), controller_radius(None, None)
    (0.035, 0.05, None)
    """
    if given is None:
        return file_radius
    if not (isinstance(given, int | float) and math.isfinite(given) and given > 0):
        raise InputError(f"--wheel-radius must be a positive number of metres, got {given!r}")
    if file_radius is not None and abs(given - file_radius) > 1e-9 * file_radius:
        raise InputError(f"--wheel-radius {given:g} m conflicts with the robot file's wheel size "
                         f"(radius {file_radius:g} m): the multipliers are relative to the file's wheels; "
                         "leave --wheel-radius out or fix the file", source=source)
    return float(given)


def diff_drive_controller_parameters(
    robot: DiffDrive,
    wheel_radius: float,
    *,
    nominal_m_per_tick: float | None = None,
) -> dict[str, float]:
    """ROS 2 ``diff_drive_controller`` parameters that reproduce a calibrated robot.

    The controller computes wheel travel as ``radius · multiplier · joint angle`` and uses
    ``wheel_separation · wheel_separation_multiplier`` as the wheel base, so:

    * ``wheel_separation`` = the nominal wheel base, multiplier = ``c_wheel_base``;
    * ``wheel_radius`` = the nominal radius you give, and each wheel's radius multiplier
      = its corrected metres per tick over the nominal metres per tick that radius stands
      for (``nominal_m_per_tick``, default the mean of the robot's two nominal values):
      ``c_left`` and ``c_right`` when both wheels have the same nominal size.

    Parameters
    ----------
    robot : DiffDrive
        Calibrated robot.
    wheel_radius : float
        Nominal wheel radius configured in the controller [m].
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to.

    Returns
    -------
    dict
        ``wheel_separation`` [m], ``wheel_radius`` [m], ``wheel_separation_multiplier``,
        ``left_wheel_radius_multiplier``, ``right_wheel_radius_multiplier`` (in the
        controller's YAML order).

    Examples
    --------
    >>> p = diff_drive_controller_parameters(DiffDrive(0.2, 1e-4, 1e-4, 0.999, 1.001, 1.006), 0.042)
    >>> p["wheel_separation_multiplier"], p["left_wheel_radius_multiplier"]
    (1.006, 0.999)
    """
    if not isinstance(robot, DiffDrive):
        raise ModelError("diff_drive_controller parameters need a DiffDrive robot")
    if not (isinstance(wheel_radius, int | float) and wheel_radius > 0):
        raise ModelError(f"wheel_radius must be a positive number of metres, got {wheel_radius!r}")
    ref = nominal_m_per_tick or 0.5 * (robot.m_per_tick_left + robot.m_per_tick_right)
    return {
        "wheel_separation": float(robot.wheel_base),
        "wheel_radius": float(wheel_radius),
        "wheel_separation_multiplier": float(robot.c_wheel_base),
        "left_wheel_radius_multiplier": float(robot.scale_left / ref),
        "right_wheel_radius_multiplier": float(robot.scale_right / ref),
    }


def tricycle_controller_parameters(
    robot: Tricycle,
    wheel_radius: float,
    *,
    nominal_m_per_tick: float | None = None,
) -> dict[str, float]:
    """ROS 2 ``tricycle_controller`` parameters that reproduce a calibrated tricycle.

    The controller (ros2_controllers ``tricycle_controller_parameter.yaml``) has no
    multipliers: its traction travel is ``wheel_radius · joint angle`` and its
    ``wheelbase`` is the steering-wheel-to-rear-axle distance. So the calibrated scale goes
    into the radius, ``wheel_radius · (corrected metres per tick / nominal metres per
    tick)`` (= ``wheel_radius · c_scale`` when ``nominal_m_per_tick`` is the robot's own),
    and ``wheelbase`` is the (calibrated) ``wheel_to_axle``. The steering offset has no
    controller parameter: it belongs in the steering joint's calibration (URDF or
    hardware interface), see :func:`odomkit.io.ros.ros2_tricycle_yaml`.

    Parameters
    ----------
    robot : Tricycle
        Calibrated robot.
    wheel_radius : float
        Nominal traction-wheel radius [m] (the one ``m_per_tick`` was computed from).
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to (default the robot's
        ``m_per_tick``).

    Returns
    -------
    dict
        ``wheelbase`` [m], ``wheel_radius`` [m].

    Examples
    --------
    >>> tricycle_controller_parameters(Tricycle(0.157, 1.2e-4, -0.02, 1.01), 0.0325)
    {'wheelbase': 0.157, 'wheel_radius': 0.032825}
    """
    if not isinstance(robot, Tricycle):
        raise ModelError("tricycle_controller parameters need a Tricycle robot")
    radius = validate.positive(wheel_radius, "wheel_radius", unit="m")
    ref = validate.positive(nominal_m_per_tick or robot.m_per_tick, "nominal_m_per_tick", unit="m")
    return {"wheelbase": float(robot.wheel_to_axle), "wheel_radius": float(radius * robot.scale / ref)}


@dataclass(frozen=True)
class TwistCovariance:
    """The covariance of an odometry twist (v, ω) that a white noise model implies.

    Parameters
    ----------
    var_speed : float
        Variance of the forward speed v [m²/s²].
    var_yaw_rate : float
        Variance of the yaw rate ω [rad²/s²].
    cov_speed_yaw_rate : float
        Their covariance [m·rad/s²].
    speed, yaw_rate, period, window : float, float, float, int
        Where it was computed: the steady motion [m/s, rad/s], the controller's update
        period [s] and the number of updates the published velocity averages.
    """

    var_speed: float
    var_yaw_rate: float
    cov_speed_yaw_rate: float
    speed: float
    yaw_rate: float
    period: float
    window: int


def _steady_log(robot: Robot, speed: float, yaw_rate: float, period: float, n: int) -> OdometryLog:
    """A log of ``n`` steps of steady motion whose corrected channels give (v, ω) exactly."""
    t: NDArray[np.float64] = period * np.arange(n + 1, dtype=float)
    ones = np.ones(n + 1)
    d, turn = speed * period, yaw_rate * period
    if isinstance(robot, DiffDrive):
        half = 0.5 * turn * robot.effective_wheel_base
        channels = {"dist_left": ones * (d - half) / robot.c_left,
                    "dist_right": ones * (d + half) / robot.c_right}
    elif isinstance(robot, Tricycle):
        # Δd = s·cos α, Δθ = s·sin α / L (kinematics.tricycle_body_steps)
        alpha = math.atan2(turn * robot.wheel_to_axle, d)
        s = math.hypot(d, turn * robot.wheel_to_axle)
        channels = {"dist": ones * s / robot.c_scale,
                    "steer": ones * (alpha - robot.steering_offset) * robot.steering_ratio}
    elif isinstance(robot, GyroOdometry):
        channels = {"speed": ones * speed, "yaw_rate": ones * (yaw_rate / robot.gyro_scale + robot.gyro_bias)}
    elif isinstance(robot, Unicycle):
        channels = {"speed": ones * speed / robot.c_scale,
                    "yaw_rate": ones * (yaw_rate / robot.yaw_rate_scale + robot.yaw_rate_bias)}
    elif isinstance(robot, Car):
        # ω = v·tan α / L (the bicycle); the measuring wheel travels d / car_speed_factor(α)
        alpha = math.atan2(turn * robot.wheel_base, d)
        s = d / float(car_speed_factor(alpha, robot.wheel_base, robot.encoder_offset, robot.encoder_at))
        channels = {"dist": ones * s / robot.c_scale, "steer": ones * car_measured_steer(robot, alpha)}
    elif isinstance(robot, CompassOdometry):
        channels = {"speed": ones * speed, "heading": yaw_rate * t - robot.heading_offset}
    else:
        raise ModelError(f"a twist covariance is computed for diff, tricycle, gyro and compass robots, "
                         f"not a {type(robot).__name__}")
    return OdometryLog(t, channels, source="<steady motion>")


def turn_noise_note(noise: object, period: float, window: int = 1) -> str | None:
    """What a twist covariance at zero yaw rate leaves out of a :class:`~odomkit.noise.TurnNoise`,
    or None where the noise has none.

    Over the W updates of T [s] a controller averages, a turn at yaw rate ω gathers
    α_turn·|ω|·W·T of heading variance and α_turn_travel·|ω|·W·T of travel variance, so the
    published ω and v gain var ω = α_turn·|ω|/(W·T) and var v = α_turn_travel·|ω|/(W·T):
    nothing on a straight line (:func:`twist_covariance` at ``yaw_rate=0``), the note's
    figures per rad/s of yaw rate otherwise."""
    from odomkit.noise import NoiseSet, TurnNoise

    turn = [m for m in NoiseSet.of(noise).white if isinstance(m, TurnNoise)]  # type: ignore[arg-type]
    heading = sum(m.alpha_turn for m in turn)
    travel = sum(m.alpha_turn_travel for m in turn)
    if heading <= 0 and travel <= 0:
        return None
    span = validate.positive(period, "period", unit="s") * validate.positive_int(window, "window")
    return (f"the twist covariance is the robot's on a straight line (ω = 0), where the robot file's "
            f"TurnNoise (alpha_turn {heading:.3g}, alpha_turn_travel {travel:.3g}) adds nothing; "
            f"turning, it raises var ω by {heading / span:.4g} rad²/s² and var v by {travel / span:.4g} "
            "m²/s² per rad/s of yaw rate (α·|ω|/(W·T)): a base whose heading noise fit-noise put on its "
            "turns publishes a yaw-rate variance too small while it turns; give robot_localization the "
            "variance at the yaw rate it turns at (odomkit.calibrate.export.twist_covariance(..., "
            "yaw_rate=ω))")


def twist_covariance(
    robot: Robot,
    noise: object,
    speed: float,
    period: float,
    *,
    window: int = 1,
    yaw_rate: float = 0.0,
) -> TwistCovariance:
    """The covariance of the (v, ω) a controller publishes, implied by a white noise model.

    A controller measures the motion of each update period T and publishes the mean
    velocity over its last W updates (``velocity_rolling_window_size`` in the ROS 2
    diff_drive and tricycle controllers): v = ΣΔd / (W·T), ω = ΣΔθ / (W·T). The white
    noise is independent from step to step, so with Q_k the covariance of (Δd, Δθ) of
    step k (the noise protocol's ``input_cov``, :mod:`odomkit.noise.base`)
    cov(v, ω) = Σ_k Q_k / (W·T)². For the per-wheel model on a straight line that is
    var v = (k_L² + k_R²)·v / (4·W·T) and var ω = (k_L² + k_R²)·v / (b²·W·T): it grows
    with speed and shrinks with a longer averaging time, which is why no single fixed
    diagonal fits a robot at every speed. A measured heading (compass) gives
    var ω = (σ²_θ,start + σ²_θ,end)/(W·T)². Bias noise (``[noise.parameters]`` in bias
    mode) is constant over a run, not white, and is left out: no twist covariance can
    carry it.

    Parameters
    ----------
    robot : Robot
    noise : noise model, sequence of models, or NoiseSet
    speed : float
        Steady forward speed [m/s] (≥ 0).
    period : float
        Controller update period T [s].
    window : int
        Number of updates averaged, W (≥ 1).
    yaw_rate : float
        Steady yaw rate ω [rad/s].

    Returns
    -------
    TwistCovariance

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> c = twist_covariance(DiffDrive(0.4), WheelNoise(0.001, 0.001), 0.5, 0.01, window=10)
    >>> k2, v, WT = 2e-6, 0.5, 10 * 0.01
    >>> round(c.var_speed / (k2 * v / (4 * WT)), 12), round(c.var_yaw_rate / (k2 * v / (0.4**2 * WT)), 12)
    (1.0, 1.0)
    """
    from odomkit.kinematics import body_steps
    from odomkit.noise import NoiseSet

    v = validate.non_negative(speed, "speed", unit="m/s")
    w = validate.finite(yaw_rate, "yaw_rate", unit="rad/s")
    T = validate.positive(period, "period", unit="s")
    n = validate.positive_int(window, "window")
    models = NoiseSet.of(noise)  # type: ignore[arg-type]
    models.check_robot(robot)
    if not models.white:
        raise ModelError("the noise has no white part: a twist covariance needs white noise "
                         "(bias noise is constant over a run)")
    steps = body_steps(robot, _steady_log(robot, v, w, T, n))
    q = models.input_cov(steps, 0, n).sum(axis=0) / (n * T) ** 2
    heading = models.heading_variances(steps)
    if heading is not None:  # a measured heading: ω from the heading at both ends
        q[1, 1] = (heading[0] + heading[-1]) / (n * T) ** 2
        q[0, 1] = q[1, 0] = 0.0
    return TwistCovariance(float(q[0, 0]), float(q[1, 1]), float(q[0, 1]), v, w, T, n)
