"""ROS interface formats: the ``geometry_msgs/PoseWithCovariance`` covariance layout and the
ROS 2 ``diff_drive_controller`` parameter file (YAML).

**Pose covariance.** ROS stores a pose covariance as 36 numbers, a row-major 6×6 matrix
over (x, y, z, rotation about X, rotation about Y, rotation about Z) — REP 103 axes, with
the rotations as fixed-axis roll, pitch, yaw. A planar robot's θ is the yaw, so odomkit's
(x, y, θ) block lands on indices (0, 1, 5). A twist covariance
(``geometry_msgs/TwistWithCovariance``) has the same layout over (v_x, v_y, v_z, ω_x, ω_y,
ω_z): a planar robot's forward speed and yaw rate land on indices (0, 5).

The three axes planar odometry does not observe (z, roll, pitch) get a large variance,
:data:`UNOBSERVED_VARIANCE` = 1e6 (m² or rad²), the value ROS's
``diff_drive_controller`` configurations use in ``pose_covariance_diagonal``
([0.001, 0.001, 1e6, 1e6, 1e6, 1e3]). A large variance rather than zero, because zero
would claim those axes are known exactly and an EKF (e.g. robot_localization) fusing
this message would then trust them over every other sensor; 1e6 is large enough to be
ignored, yet finite so the matrix stays invertible.

**Controller parameters.** The numbers (wheel separation, radius and their multipliers;
a tricycle's wheelbase and radius) come from :mod:`odomkit.calibrate.export`; this module
only lays them out as the controllers' YAML and writes the files. With a fitted noise
model the snippets also carry ``twist_covariance_diagonal``: the (v, ω) variances of
:func:`odomkit.calibrate.export.twist_covariance` at a stated speed, which is what
``robot_localization`` fuses from the controller's ``/odom`` messages.

**nav2 AMCL.** :func:`nav2_amcl_yaml` writes fitted α's (``odomkit fit-amcl``) with the
motion model and the update thresholds they were fitted at, under ``amcl:`` /
``ros__parameters:`` as nav2's parameter files have them.

The YAML is written as text (no YAML library is a dependency): keys are plain words and
every value a number, a list of numbers or a quoted plain string, so the text is valid
YAML as written; the tests read it back with PyYAML.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from odomkit.calibrate.export import (
    TwistCovariance,
    diff_drive_controller_parameters,
    tricycle_controller_parameters,
)
from odomkit.errors import ModelError
from odomkit.io.files import write_new_text
from odomkit.robot import DiffDrive, Tricycle

__all__ = ["nav2_amcl_yaml", "NAV2_MOTION_MODELS", "ros2_controller_yaml", "ros2_diff_drive_yaml",
           "ros2_tricycle_yaml", "ros_pose_covariance", "ros_twist_covariance",
           "ros_twist_covariance_diagonal", "UNIFORM_HEADING_VARIANCE", "UNOBSERVED_VARIANCE",
           "write_ros2_yaml", "yaw_variance_note"]

#: nav2's motion-model plugin class for each ``odomkit fit-amcl --model``.
NAV2_MOTION_MODELS = {"diff": "nav2_amcl::DifferentialMotionModel", "omni": "nav2_amcl::OmniMotionModel"}

UNOBSERVED_VARIANCE = 1e6
"""Variance given to z [m²], roll and pitch [rad²]."""

UNIFORM_HEADING_VARIANCE = math.pi**2 / 3
"""Variance of a heading spread uniformly around the circle, (2π)²/12 = π²/3 ≈ 3.29 [rad²]:
a Gaussian yaw variance beyond it claims more spread than knowing nothing of the heading."""

_ROS_INDEX = (0, 1, 5)  # x, y, yaw in ROS's (x, y, z, roll, pitch, yaw)
_ROS_TWIST_INDEX = (0, 5)  # v_x, ω_z in ROS's (v_x, v_y, v_z, ω_x, ω_y, ω_z)


def ros_pose_covariance(
    cov3: ArrayLike, unobserved_variance: float = UNOBSERVED_VARIANCE
) -> list[float]:
    """The 36-element ROS pose covariance of a planar (x, y, θ) covariance.

    Parameters
    ----------
    cov3 : array_like, shape (3, 3)
        Covariance in the order x, y, θ [m², m·rad, rad²].
    unobserved_variance : float
        Diagonal entry for z, roll and pitch; their covariances with everything are 0.

    Returns
    -------
    list of float, length 36
        Row-major 6×6 over (x, y, z, roll, pitch, yaw).

    Examples
    --------
    >>> c = ros_pose_covariance([[1.0, 0.1, 0.2], [0.1, 2.0, 0.3], [0.2, 0.3, 3.0]])
    >>> c[0], c[1], c[5], c[7], c[11], c[35], c[14]
    (1.0, 0.1, 0.2, 2.0, 0.3, 3.0, 1000000.0)
    """
    return _ros_6x6(cov3, _ROS_INDEX, "pose covariance must be 3x3 (x, y, theta)", unobserved_variance)


def yaw_variance_note(var_theta: float, where: str) -> str | None:
    """What is wrong with a ROS pose covariance whose yaw variance ``var_theta`` [rad²] is
    beyond :data:`UNIFORM_HEADING_VARIANCE`, or None: ``where`` names the covariance
    exported (the messages of a bag, a JSON key).

    Examples
    --------
    >>> yaw_variance_note(3.0, "x") is None
    True
    >>> yaw_variance_note(7.0, "the bag's messages")[:68]
    "the yaw variance of the bag's messages reaches 7 rad², beyond π²/3 ≈"
    """
    if not var_theta > UNIFORM_HEADING_VARIANCE:
        return None
    return (f"the yaw variance of {where} reaches {var_theta:.4g} rad², beyond π²/3 ≈ "
            f"{UNIFORM_HEADING_VARIANCE:.3g} rad² (the variance of a heading spread uniformly around the "
            "circle): as a Gaussian's it is meaningless, yet a consumer such as robot_localization would "
            "take it literally")


def ros_twist_covariance(
    cov2: ArrayLike, unobserved_variance: float = UNOBSERVED_VARIANCE
) -> list[float]:
    """The 36-element ROS twist covariance of a planar (v, ω) covariance.

    Parameters
    ----------
    cov2 : array_like, shape (2, 2)
        Covariance of the forward speed and the yaw rate [m²/s², m·rad/s²; rad²/s²].
    unobserved_variance : float
        Diagonal entry for v_y, v_z, ω_x and ω_y; their covariances with everything are 0.

    Returns
    -------
    list of float, length 36
        Row-major 6×6 over (v_x, v_y, v_z, ω_x, ω_y, ω_z).

    Examples
    --------
    >>> c = ros_twist_covariance([[1.0, 0.1], [0.1, 2.0]])
    >>> c[0], c[5], c[30], c[35], c[7], c[28]
    (1.0, 0.1, 0.1, 2.0, 1000000.0, 1000000.0)
    """
    return _ros_6x6(cov2, _ROS_TWIST_INDEX, "twist covariance must be 2x2 (v, omega)", unobserved_variance)


def _ros_6x6(cov_in: ArrayLike, index: tuple[int, ...], what: str, unobserved_variance: float) -> list[float]:
    cov = np.asarray(cov_in, dtype=float)
    if cov.shape != (len(index), len(index)):
        raise ModelError(f"{what}, got shape {cov.shape}")
    if not (np.isfinite(unobserved_variance) and unobserved_variance > 0):
        raise ModelError(f"unobserved_variance must be positive, got {unobserved_variance!r}")
    out = np.zeros((6, 6))
    for i in set(range(6)) - set(index):
        out[i, i] = unobserved_variance
    out[np.ix_(index, index)] = cov
    return [float(v) for v in out.reshape(-1)]


def ros2_diff_drive_yaml(
    robot: DiffDrive,
    wheel_radius: float,
    *,
    controller_name: str = "diff_drive_controller",
    nominal_m_per_tick: float | None = None,
    twist: TwistCovariance | None = None,
) -> str:
    """ROS 2 ``diff_drive_controller`` parameters for a calibrated robot (YAML text).

    Parameters
    ----------
    robot : DiffDrive
        Calibrated robot.
    wheel_radius : float
        Nominal wheel radius configured in the controller [m].
    controller_name : str
        Top-level key (the controller's node name).
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to (see
        :func:`odomkit.calibrate.export.diff_drive_controller_parameters`).
    twist : TwistCovariance, optional
        Adds ``twist_covariance_diagonal`` (:func:`ros_twist_covariance_diagonal`) and a
        comment saying at which speed it holds.

    Examples
    --------
    >>> print(ros2_diff_drive_yaml(DiffDrive(0.2, 1e-4, 1e-4, 0.999, 1.001, 1.006), 0.042))
    diff_drive_controller:
      ros__parameters:
        wheel_separation: 0.2
        wheel_radius: 0.042
        wheel_separation_multiplier: 1.006
        left_wheel_radius_multiplier: 0.999
        right_wheel_radius_multiplier: 1.001
    <BLANKLINE>
    """
    values: dict[str, float | list[float]] = dict(
        diff_drive_controller_parameters(robot, wheel_radius, nominal_m_per_tick=nominal_m_per_tick))
    notes = []
    if twist is not None:
        values["twist_covariance_diagonal"] = ros_twist_covariance_diagonal(twist)
        notes = _twist_notes(twist)
    return _snippet(controller_name, values, notes)


def ros2_tricycle_yaml(
    robot: Tricycle,
    wheel_radius: float,
    *,
    controller_name: str = "tricycle_controller",
    nominal_m_per_tick: float | None = None,
    twist: TwistCovariance | None = None,
) -> str:
    """ROS 2 ``tricycle_controller`` parameters for a calibrated tricycle (YAML text).

    ``wheelbase`` and ``wheel_radius`` from
    :func:`odomkit.calibrate.export.tricycle_controller_parameters` (the calibrated scale
    folded into the radius). The controller has no steering-offset parameter, so a
    calibrated offset is written as a comment: apply it where the steering joint is
    calibrated (its zero in the URDF or hardware interface).

    Examples
    --------
    >>> print(ros2_tricycle_yaml(Tricycle(0.157, 1.2e-4, -0.02, 1.01), 0.0325))
    tricycle_controller:
      ros__parameters:
        wheelbase: 0.157
        wheel_radius: 0.032825
        # steering_offset -0.02 rad (added to the measured steering angle) has no
        # tricycle_controller parameter: set it in the steering joint's calibration.
    <BLANKLINE>
    """
    values: dict[str, float | list[float]] = dict(
        tricycle_controller_parameters(robot, wheel_radius, nominal_m_per_tick=nominal_m_per_tick))
    notes = []
    if twist is not None:
        values["twist_covariance_diagonal"] = ros_twist_covariance_diagonal(twist)
        notes = _twist_notes(twist)
    if robot.steering_offset != 0.0:
        notes += [f"steering_offset {robot.steering_offset!r} rad (added to the measured steering angle) "
                  "has no", "tricycle_controller parameter: set it in the steering joint's calibration."]
    if robot.steering_ratio != 1.0:
        notes += [f"steering_ratio {robot.steering_ratio!r} (the logged steering per radian of the wheel) "
                  "has no", "tricycle_controller parameter: the steering joint's state must be in the "
                  "wheel's radians."]
    return _snippet(controller_name, values, notes)


def ros2_controller_yaml(robot: DiffDrive | Tricycle, wheel_radius: float, **kwargs: Any) -> str:
    """:func:`ros2_diff_drive_yaml` or :func:`ros2_tricycle_yaml`, by the robot's type."""
    if isinstance(robot, Tricycle):
        return ros2_tricycle_yaml(robot, wheel_radius, **kwargs)
    return ros2_diff_drive_yaml(robot, wheel_radius, **kwargs)


def write_ros2_yaml(path: str | Path, robot: DiffDrive | Tricycle, wheel_radius: float, *,
                    overwrite: bool = False, **kwargs: Any) -> Path:
    """Write :func:`ros2_controller_yaml` to ``path`` (never over an existing file unless
    ``overwrite``); ``kwargs`` go to the controller's writer."""
    return write_new_text(path, ros2_controller_yaml(robot, wheel_radius, **kwargs), overwrite)


def ros_twist_covariance_diagonal(
    twist: TwistCovariance, unobserved_variance: float = UNOBSERVED_VARIANCE
) -> list[float]:
    """The six-number ``twist_covariance_diagonal`` (vx, vy, vz, ωx, ωy, ωz) of a twist
    covariance.

    vx and ωz are the fitted noise's; vz, ωx, ωy are not observed (``unobserved_variance``).
    vy: the kinematic model has no lateral slip, so it has no variance of its own, and a
    zero would tell an EKF the robot can never slide; it gets vx's variance as a stand-in
    of the right size. The vx–ωz covariance a diagonal cannot hold is dropped (see
    :func:`odomkit.calibrate.export.twist_covariance`; zero on a straight line for equal
    wheels).

    Examples
    --------
    >>> t = TwistCovariance(1e-4, 2e-3, 0.0, 0.5, 0.0, 0.01, 10)
    >>> ros_twist_covariance_diagonal(t)
    [0.0001, 0.0001, 1000000.0, 1000000.0, 1000000.0, 0.002]
    """
    if not (np.isfinite(unobserved_variance) and unobserved_variance > 0):
        raise ModelError(f"unobserved_variance must be positive, got {unobserved_variance!r}")
    u = float(unobserved_variance)
    return [twist.var_speed, twist.var_speed, u, u, u, twist.var_yaw_rate]


def _twist_notes(twist: TwistCovariance) -> list[str]:
    # "of the robot file's white noise", not "fitted": a user study published a hand-set
    # k = 0.01 under a comment that called it fitted (fit-noise writes a fitted one).
    return [f"twist covariance of the robot file's white noise ([noise]; fitted only if odomkit "
            f"fit-noise wrote it) at v = {twist.speed:g} m/s,",
            f"yaw rate {twist.yaw_rate:g} rad/s, update period {twist.period:g} s, "
            f"averaged over {twist.window} updates (velocity_rolling_window_size): it changes with "
            "speed and averaging time,",
            "so it holds there only; bias (calibration) errors and vx-yaw correlation are not in "
            "a diagonal.",
            "pose_covariance_diagonal is left out: a pose's covariance grows with the distance "
            "driven (odomkit track gives it at every pose), which no constant diagonal holds."]


_PLAIN_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def _yaml_number(value: float) -> str:
    """Shortest round-tripping text, with a dot in the mantissa: YAML 1.1 readers (PyYAML,
    libyaml's resolver) read ``1e-05`` as a string, ``1.0e-05`` as a float."""
    if not math.isfinite(value):
        raise ModelError(f"a ROS parameter must be a finite number, got {value!r}")
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    if e and "." not in mantissa:
        text = f"{mantissa}.0e{exponent}"
    return text


def _yaml_value(value: float | str | Sequence[float]) -> str:
    if isinstance(value, str):
        if not re.fullmatch(r"[A-Za-z0-9_:./ -]*", value):
            raise ModelError(f"a ROS string parameter must be plain text, got {value!r}")
        return f'"{value}"'
    if isinstance(value, Sequence):
        return "[" + ", ".join(_yaml_number(float(v)) for v in value) + "]"
    return _yaml_number(value)


def _snippet(node: str, values: Mapping[str, float | str | Sequence[float]],
             notes: Sequence[str] = ()) -> str:
    """``node:`` / ``ros__parameters:`` / one ``key: value`` line each, then ``# notes``."""
    if not node or not _PLAIN_KEY.match(node):
        raise ModelError(f"controller_name must be a plain ROS node name, got {node!r}")
    body = "".join(f"    {k}: {_yaml_value(v)}\n" for k, v in values.items())
    body += "".join(f"    # {line}\n" for line in notes)
    return f"{node}:\n  ros__parameters:\n{body}"


def nav2_amcl_yaml(
    alpha: Mapping[str, float],
    model: str = "diff",
    *,
    update_min_d: float = 0.25,
    update_min_a: float = 0.2,
    node_name: str = "amcl",
    notes: Sequence[str] = (),
) -> str:
    """A nav2 AMCL parameter snippet with fitted motion-model α's (YAML text).

    The α's only mean what they were fitted to at the update thresholds they were fitted
    at (the variances scale with the squared motion between updates), so the snippet also
    sets ``update_min_d``, ``update_min_a`` and the motion model (``robot_model_type``).

    Parameters
    ----------
    alpha : mapping
        ``alpha1`` … ``alpha4`` (and ``alpha5`` for omni), as :func:`odomkit.calibrate.amcl.fit_amcl`.
    model : {"diff", "omni"}
    update_min_d, update_min_a : float
        [m], [rad].
    node_name : str
    notes : lines written as YAML comments.

    Examples
    --------
    >>> print(nav2_amcl_yaml({"alpha1": 0.05, "alpha2": 0.1, "alpha3": 0.04, "alpha4": 0.2}))
    amcl:
      ros__parameters:
        robot_model_type: "nav2_amcl::DifferentialMotionModel"
        alpha1: 0.05
        alpha2: 0.1
        alpha3: 0.04
        alpha4: 0.2
        update_min_d: 0.25
        update_min_a: 0.2
    <BLANKLINE>
    """
    if model not in NAV2_MOTION_MODELS:
        raise ModelError(f"the AMCL model must be one of {', '.join(NAV2_MOTION_MODELS)}, got {model!r}")
    wanted = ("alpha1", "alpha2", "alpha3", "alpha4") + (("alpha5",) if model == "omni" else ())
    missing = [k for k in wanted if k not in alpha]
    if missing:
        raise ModelError(f"the {model} motion model needs {', '.join(missing)}")
    for k in wanted:
        if not alpha[k] >= 0:
            raise ModelError(f"{k} must be a variance factor >= 0, got {alpha[k]!r}")
    values: dict[str, float | str | Sequence[float]] = {"robot_model_type": NAV2_MOTION_MODELS[model]}
    values.update({k: float(alpha[k]) for k in wanted})
    values["update_min_d"] = float(update_min_d)
    values["update_min_a"] = float(update_min_a)
    return _snippet(node_name, values, notes)
