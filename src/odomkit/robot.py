"""Frozen parameter sets for every vehicle in the papers.

A robot says how raw log channels become body motion; it holds no noise (see
:mod:`odomkit.noise`) and no state. All lengths are metres, angles radians.

Log channels each robot consumes (see :mod:`odomkit.log`):

=========================  ======================================================
robot                      channels
=========================  ======================================================
:class:`DiffDrive`         ``ticks_left``, ``ticks_right`` (increments), or
                           ``dist_left``, ``dist_right`` (m increments), or
                           ``speed_left``, ``speed_right`` (wheel speeds, m/s)
:class:`Tricycle`          ``ticks``/``dist`` (traction-wheel increments) or ``speed`` (m/s),
                           plus ``steer`` (rad, positive = left/CCW)
:class:`GyroOdometry`      ``ticks``/``dist``/``speed`` plus ``yaw_rate`` (rad/s)
:class:`CompassOdometry`   ``ticks``/``dist``/``speed`` plus ``heading`` (rad)
:class:`Unicycle`          ``speed`` (m/s; or ``dist`` increments) plus ``yaw_rate``
                           (rad/s): body velocities, e.g. a base's ``cmd_vel``
:class:`Car`               ``ticks``/``dist``/``speed`` of one wheel plus ``steer`` (rad,
                           the front (bicycle) angle, positive = left/CCW)
=========================  ======================================================

Only ``ticks*`` channels are converted by ``m_per_tick*``; ``dist*`` [m] and ``speed*``
[m/s] are metres already. The calibration factors (``c_*``) apply to all three.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, ClassVar

from odomkit import validate
from odomkit.errors import ModelError

__all__ = [
    "ROBOT_TYPES", "Car", "CompassOdometry", "DiffDrive", "ENCODER_POSITIONS", "GyroOdometry",
    "metres_per_tick", "Robot", "robot_type_name", "SystematicErrors", "Tricycle", "true_robot",
    "Unicycle"
]


def _positive_fields(obj: object, *names: str) -> None:
    for name in names:
        validate.positive(getattr(obj, name), f"{type(obj).__name__}.{name}")


def metres_per_tick(wheel_diameter: float, encoder_resolution: float, gear_ratio: float = 1.0) -> float:
    """Distance one encoder tick moves a wheel, Borenstein–Feng eq. (2.1).

    ``c_m = π·D_n / (n·C_e)`` with D_n the nominal wheel diameter [m], n the gear ratio
    between motor (where the encoder sits) and wheel, C_e the encoder resolution
    [ticks per motor revolution].

    Examples
    --------
    >>> round(metres_per_tick(0.084, 64, 43.7), 10)   # OptiOdom differential robot
    9.43556e-05
    """
    d = validate.positive(wheel_diameter, "metres_per_tick.wheel_diameter", unit="m")
    c_e = validate.positive(encoder_resolution, "metres_per_tick.encoder_resolution")
    n = validate.positive(gear_ratio, "metres_per_tick.gear_ratio")
    return math.pi * d / (n * c_e)


@dataclass(frozen=True)
class DiffDrive:
    """Differential-drive robot.

    Parameters
    ----------
    wheel_base : float
        Nominal distance b between the wheel contact points [m].
    m_per_tick_left, m_per_tick_right : float
        Nominal distance per encoder tick of each wheel [m], Borenstein–Feng eq. (2.1).
        It converts ``ticks_*`` channels only: ``dist_*`` [m] and ``speed_*`` [m/s]
        channels are metres already.
    c_left, c_right : float
        Dimensionless wheel-scale corrections (Borenstein–Feng eq. 4.30–4.31): the
        distance a wheel travelled is ``c · m_per_tick · ticks`` (``c · dist`` for a
        channel in metres, ``c · speed · Δt`` for a wheel speed).
    c_wheel_base : float
        Dimensionless wheel-base correction: the effective wheel base is
        ``c_wheel_base · wheel_base`` (Borenstein–Feng eq. 4.32, b_new = E_b·b_nominal).
    """

    type_name: ClassVar[str] = "diff"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = False
    """Heading is integrated from the steps, not measured."""

    wheel_base: float
    m_per_tick_left: float = 1.0
    m_per_tick_right: float = 1.0
    c_left: float = 1.0
    c_right: float = 1.0
    c_wheel_base: float = 1.0

    def __post_init__(self) -> None:
        _positive_fields(self, *(f.name for f in fields(self)))

    @classmethod
    def from_wheels(
        cls,
        wheel_base: float,
        wheel_diameter_left: float,
        wheel_diameter_right: float | None = None,
        encoder_resolution: float = 1.0,
        gear_ratio: float = 1.0,
        **corrections: float,
    ) -> DiffDrive:
        """Build from wheel diameters [m], encoder ticks per motor turn and gear ratio."""
        right = wheel_diameter_left if wheel_diameter_right is None else wheel_diameter_right
        return cls(
            wheel_base=wheel_base,
            m_per_tick_left=metres_per_tick(wheel_diameter_left, encoder_resolution, gear_ratio),
            m_per_tick_right=metres_per_tick(right, encoder_resolution, gear_ratio),
            **corrections,
        )

    @property
    def effective_wheel_base(self) -> float:
        """Wheel base used in the kinematics, ``c_wheel_base · wheel_base`` [m]."""
        return self.c_wheel_base * self.wheel_base

    @property
    def scale_left(self) -> float:
        """Metres per tick of the left wheel after correction."""
        return self.c_left * self.m_per_tick_left

    @property
    def scale_right(self) -> float:
        """Metres per tick of the right wheel after correction."""
        return self.c_right * self.m_per_tick_right


@dataclass(frozen=True)
class Tricycle:
    """Tricycle: one front wheel that steers and drives; the reference point is the
    centre of the rear axle (Snowhite; OptiOdom ``tricyc``).

    Parameters
    ----------
    wheel_to_axle : float
        Distance L from the front wheel contact point to the rear axle centre [m].
    m_per_tick : float
        Traction-wheel distance per tick [m]; converts a ``ticks`` channel only
        (``dist`` [m] and ``speed`` [m/s] are metres already).
    steering_offset : float
        Added to the steering wheel's angle [rad]: α = α_measured / steering_ratio +
        steering_offset.
    c_scale : float
        Dimensionless traction-wheel scale correction (applies to ticks, ``dist`` and
        ``speed`` alike).
    steering_ratio : float
        The ``steer`` channel per radian of the steered wheel's angle [1]: 1 (default) for
        a channel in radians; an absolute steering encoder's ticks per radian (8192 ticks a
        turn: 1303.8) or a steering gear's ratio otherwise. The offset and the steering
        noise are the wheel's radians either way.
    """

    type_name: ClassVar[str] = "tricycle"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = False
    """Heading is integrated from the steps, not measured."""

    wheel_to_axle: float
    m_per_tick: float = 1.0
    steering_offset: float = 0.0
    c_scale: float = 1.0
    steering_ratio: float = 1.0

    def __post_init__(self) -> None:
        _positive_fields(self, "wheel_to_axle", "m_per_tick", "c_scale", "steering_ratio")
        validate.finite(self.steering_offset, "Tricycle.steering_offset")

    @property
    def scale(self) -> float:
        """Metres per tick of the traction wheel after correction."""
        return self.c_scale * self.m_per_tick


@dataclass(frozen=True)
class GyroOdometry:
    """Integrated-heading odometry (Kelly): speed from an encoder, heading rate from a gyro.

    Parameters
    ----------
    m_per_tick : float
        Distance per tick [m]; converts a ``ticks`` channel only (``dist`` [m] and
        ``speed`` [m/s] are metres already).
    gyro_bias : float
        Subtracted from the measured yaw rate [rad/s].
    gyro_scale : float
        Dimensionless; the yaw rate used is ``gyro_scale · (measured − gyro_bias)``.
    """

    type_name: ClassVar[str] = "gyro"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = False
    """Heading is integrated from the steps, not measured."""

    m_per_tick: float = 1.0
    gyro_bias: float = 0.0
    gyro_scale: float = 1.0

    def __post_init__(self) -> None:
        _positive_fields(self, "m_per_tick", "gyro_scale")
        validate.finite(self.gyro_bias, "GyroOdometry.gyro_bias")


@dataclass(frozen=True)
class CompassOdometry:
    """Direct-heading odometry (Kelly): speed from an encoder, heading from a compass.

    Parameters
    ----------
    m_per_tick : float
        Distance per tick [m]; converts a ``ticks`` channel only (``dist`` [m] and
        ``speed`` [m/s] are metres already).
    heading_offset : float
        Added to the measured heading [rad].
    """

    type_name: ClassVar[str] = "compass"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = True
    """Heading is measured (direct heading), not integrated."""

    m_per_tick: float = 1.0
    heading_offset: float = 0.0

    def __post_init__(self) -> None:
        _positive_fields(self, "m_per_tick")
        validate.finite(self.heading_offset, "CompassOdometry.heading_offset")


@dataclass(frozen=True)
class Unicycle:
    """Body-velocity odometry: forward speed and yaw rate of the reference point, e.g. a
    mobile base's commanded (``cmd_vel``) or measured (``odom`` twist) velocities.

    The calibration factors mirror :class:`GyroOdometry`'s: the yaw rate used is
    ``yaw_rate_scale · (measured − yaw_rate_bias)``; the speed used is
    ``c_scale · measured`` (as :class:`Tricycle`'s ``c_scale``).

    Parameters
    ----------
    c_scale : float
        Dimensionless speed-scale correction.
    yaw_rate_bias : float
        Subtracted from the measured yaw rate [rad/s].
    yaw_rate_scale : float
        Dimensionless yaw-rate scale correction.
    """

    type_name: ClassVar[str] = "unicycle"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = False
    """Heading is integrated from the steps, not measured."""

    c_scale: float = 1.0
    yaw_rate_bias: float = 0.0
    yaw_rate_scale: float = 1.0

    def __post_init__(self) -> None:
        _positive_fields(self, "c_scale", "yaw_rate_scale")
        validate.finite(self.yaw_rate_bias, "Unicycle.yaw_rate_bias")


ENCODER_POSITIONS = ("rear", "front")
"""Where a :class:`Car`'s speed-measuring wheel sits: on the rear or the front axle."""


@dataclass(frozen=True)
class Car:
    """Car-like (Ackermann) vehicle as a bicycle: the reference point is the centre of the
    rear axle, the steering angle is that of a virtual front wheel on the centre line, and
    the speed is measured at one real wheel (docs/reference/robot-files.md, the ``car`` row).

    With ω = v·tan α / L the yaw rate of the rear-axle speed v, the measuring wheel at
    lateral offset H (+ left) moves at

    * ``encoder_at="rear"``: v_e = v − ωH = v·(1 − tan α·H/L), so v = v_e / (1 − tan α·H/L);
    * ``encoder_at="front"``: its contact point (L, H) moves at (v − ωH, ωL) in the body
      frame and the wheel rolls along it (Ackermann), so
      v_e = v·√((1 − tan α·H/L)² + tan² α), i.e. v = v_e·cos α / √((cos α − sin α·H/L)² + sin² α)
      (H = 0: v = v_e cos α, the tricycle).

    (:func:`odomkit.kinematics.car_speed_factor`; derived here, checked against a closed
    circle in the tests.)

    Parameters
    ----------
    wheel_base : float
        L, rear axle to front axle [m].
    encoder_offset : float
        H, lateral offset of the measuring wheel from the centre line [m], + left.
    encoder_at : {"rear", "front"}
        Axle of the measuring wheel.
    m_per_tick : float
        Distance per tick of the measuring wheel [m]; converts a ``ticks`` channel only
        (``dist`` [m] and ``speed`` [m/s] are metres already).
    steering_offset : float
        Added to the road-wheel angle [rad]: α = s + steering_cubic·s³ + steering_offset
        with s = α_measured / steering_ratio.
    c_scale : float
        Dimensionless scale correction of the measuring wheel (ticks, ``dist`` and
        ``speed`` alike).
    steering_ratio : float
        Measured steering angle per road-wheel angle [1]: 1 for a ``steer`` channel that is
        the (virtual) front wheel's angle, about 12–18 for a car's CAN steering-wheel angle.
        Read as a road-wheel angle, a steering-wheel angle of 100° would steer the bicycle
        past its lock (tan α of 1.7 rad); the offset and the steering noise are road-wheel
        radians either way.
    steering_cubic : float
        k [rad⁻²] of a steering ratio that varies with the angle (a variable-ratio rack):
        the road wheel turns s + k·s³ for s = α_measured / steering_ratio. 0 (default) is a
        constant ratio. On a real car whose calibration failed without it (a BMW, CAN
        steering-wheel angle over 15) k came out near 40: 60 % more road-wheel angle than
        s at 110° of steering wheel (docs/results/honesty.md).
    """

    type_name: ClassVar[str] = "car"
    """The robot-file ``type``."""
    measures_heading: ClassVar[bool] = False
    """Heading is integrated from the steps, not measured."""

    wheel_base: float
    encoder_offset: float = 0.0
    encoder_at: str = "rear"
    m_per_tick: float = 1.0
    steering_offset: float = 0.0
    c_scale: float = 1.0
    steering_ratio: float = 1.0
    steering_cubic: float = 0.0

    def __post_init__(self) -> None:
        _positive_fields(self, "wheel_base", "m_per_tick", "c_scale", "steering_ratio")
        validate.finite(self.encoder_offset, "Car.encoder_offset")
        validate.finite(self.steering_cubic, "Car.steering_cubic")
        validate.finite(self.steering_offset, "Car.steering_offset")
        if self.encoder_at not in ENCODER_POSITIONS:
            raise ModelError(f"Car.encoder_at must be 'rear' or 'front', got {self.encoder_at!r}")

    @property
    def scale(self) -> float:
        """Metres per tick of the measuring wheel after correction."""
        return self.c_scale * self.m_per_tick


@dataclass(frozen=True)
class SystematicErrors:
    """The true systematic errors of a virtual differential robot (Borenstein–Feng II-B).

    All three are relative to the robot's *nominal* parameters (a
    :class:`~odomkit.robot.DiffDrive` with its ``m_per_tick_*`` and ``wheel_base``,
    ignoring its correction factors).

    Parameters
    ----------
    E_d : float
        D_R/D_L, the ratio of the actual wheel diameters (eq. 2.3), each measured in units
        of its nominal diameter: true metres per tick are ``m_per_tick_left·2E_s/(E_d+1)``
        and ``m_per_tick_right·2E_s·E_d/(E_d+1)``.
    E_b : float
        b_actual/b_nominal (eq. 2.4).
    E_s : float
        D_avg/D_nominal, the average-diameter scale error (section II-B); it scales both
        legs and turns (eq. 2.15) and UMBmark cannot see it in the legs.

    Examples
    --------
    >>> left, right = SystematicErrors(E_d=1.002).wheel_scales()  # relative to nominal
    >>> round(right / left, 12), round((left + right) / 2, 12)       # E_d and E_s
    (1.002, 1.0)
    """

    E_d: float = 1.0
    E_b: float = 1.0
    E_s: float = 1.0

    def __post_init__(self) -> None:
        _positive_fields(self, "E_d", "E_b", "E_s")

    def wheel_scales(self) -> tuple[float, float]:
        """True/nominal distance per tick of the left and right wheel."""
        return 2.0 * self.E_s / (self.E_d + 1.0), 2.0 * self.E_s * self.E_d / (self.E_d + 1.0)


def true_robot(true_errors: SystematicErrors, robot: DiffDrive) -> DiffDrive:
    """The true robot as a :class:`~odomkit.robot.DiffDrive` with no corrections.

    Examples
    --------
    >>> round(true_robot(SystematicErrors(E_b=1.01), DiffDrive(0.34)).wheel_base, 12)
    0.3434
    """
    left, right = true_errors.wheel_scales()
    return DiffDrive(
        wheel_base=true_errors.E_b * robot.wheel_base,
        m_per_tick_left=left * robot.m_per_tick_left,
        m_per_tick_right=right * robot.m_per_tick_right,
    )


Robot = DiffDrive | Tricycle | GyroOdometry | CompassOdometry | Unicycle | Car

ROBOT_TYPES: dict[str, type[Any]] = {
    "diff": DiffDrive,
    "tricycle": Tricycle,
    "gyro": GyroOdometry,
    "compass": CompassOdometry,
    "unicycle": Unicycle,
    "car": Car,
}


def robot_type_name(robot: Robot) -> str:
    """The robot-file ``type`` string of a robot instance."""
    name = getattr(robot, "type_name", None)
    if name not in ROBOT_TYPES or not isinstance(robot, ROBOT_TYPES[name]):
        raise ModelError(f"not an odomkit robot: {type(robot).__name__}")
    return name
