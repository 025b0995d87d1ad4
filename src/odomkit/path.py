"""Planned paths as sequences of constant-curvature segments.

Used by ``predict`` (closed-form covariance) and ``simulate`` (Monte Carlo). A
differential-drive segment is given by wheel travels; Kelly's gyro and compass models and
a unicycle use speed, yaw rate and duration; a steered vehicle (tricycle, car) the speed
of its measuring wheel, its steering angle and a duration (:class:`SteerArc`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from odomkit import validate
from odomkit.errors import ModelError

__all__ = ["Arc", "DiffSegment", "KellyArc", "parse_segment", "Segment", "Spin", "SteerArc", "Straight"]


@dataclass(frozen=True)
class Arc:
    """Differential drive: left and right wheel travel [m] of one constant-curvature arc
    (Chong–Kleeman's L and R). ``left == right`` is a straight line, ``left == -right``
    a spin on the spot; negative values drive backwards."""

    left: float
    right: float

    def __post_init__(self) -> None:
        validate.finite(self.left, "Arc.left", unit="m")
        validate.finite(self.right, "Arc.right", unit="m")

    def wheel_travel(self, wheel_base: float) -> tuple[float, float]:
        return self.left, self.right


@dataclass(frozen=True)
class Straight:
    """Differential drive: a straight line of signed length ``distance`` [m]."""

    distance: float

    def __post_init__(self) -> None:
        validate.finite(self.distance, "Straight.distance", unit="m")

    def wheel_travel(self, wheel_base: float) -> tuple[float, float]:
        return self.distance, self.distance


@dataclass(frozen=True)
class Spin:
    """Differential drive: a turn on the spot by ``dtheta`` [rad] (positive = CCW)."""

    dtheta: float

    def __post_init__(self) -> None:
        validate.finite(self.dtheta, "Spin.dtheta", unit="rad")

    def wheel_travel(self, wheel_base: float) -> tuple[float, float]:
        half = 0.5 * wheel_base * self.dtheta
        return -half, half


@dataclass(frozen=True)
class KellyArc:
    """Gyro/compass models: constant speed ``speed`` [m/s] and yaw rate ``yaw_rate``
    [rad/s] for ``duration`` [s] (Kelly eq. 14–15). ``yaw_rate == 0`` is a straight line
    (Kelly eq. 13)."""

    speed: float
    yaw_rate: float
    duration: float

    def __post_init__(self) -> None:
        validate.finite(self.speed, "KellyArc.speed", unit="m/s")
        validate.finite(self.yaw_rate, "KellyArc.yaw_rate", unit="rad/s")
        validate.non_negative(self.duration, "segment duration", unit="s")


@dataclass(frozen=True)
class SteerArc:
    """Steered vehicles (tricycle, car): the measuring wheel's speed ``speed`` [m/s] and
    the steering angle ``steer`` [rad] (as the kinematics use them: calibrations and
    offset applied), constant for ``duration`` [s]. The body motion is the vehicle's
    (:func:`odomkit.kinematics.steering_body_steps`): a constant-curvature arc."""

    speed: float
    steer: float
    duration: float

    def __post_init__(self) -> None:
        validate.finite(self.speed, "SteerArc.speed", unit="m/s")
        validate.finite(self.steer, "SteerArc.steer", unit="rad")
        if not abs(self.steer) < math.pi / 2:
            raise ModelError(f"SteerArc.steer must lie within ±π/2 rad, got {self.steer!r}")
        validate.non_negative(self.duration, "segment duration", unit="s")


DiffSegment = Arc | Straight | Spin
Segment = Arc | Straight | Spin | KellyArc | SteerArc

# keyed by the model (odomkit predict --model) or the robot type (--robot)
_SYNTAX = {
    "diff": "arc:L,R | straight:D | spin:DTHETA",
    "gyro": "arc:V,OMEGA,T | straight:V,T",
    "compass": "arc:V,OMEGA,T | straight:V,T",
    "unicycle": "arc:V,OMEGA,T | straight:V,T",
    "tricycle": "arc:V,ALPHA,T | straight:V,T",
    "car": "arc:V,ALPHA,T | straight:V,T",
}


def parse_segment(text: str, model: str = "diff") -> Segment:
    """Parse a ``--segment`` option.

    Examples
    --------
    >>> parse_segment("arc:3,1")
    Arc(left=3.0, right=1.0)
    >>> parse_segment("straight:0.5,10", model="gyro")
    KellyArc(speed=0.5, yaw_rate=0.0, duration=10.0)
    >>> parse_segment("arc:0.5,0.2,10", model="tricycle")  # wheel speed, steering angle, duration
    SteerArc(speed=0.5, steer=0.2, duration=10.0)
    """
    if model not in _SYNTAX:
        raise ModelError(f"unknown model {model!r}; expected one of {', '.join(_SYNTAX)}")
    kind, sep, rest = text.partition(":")
    try:
        values = [float(v) for v in rest.split(",")] if sep else []
    except ValueError:
        values = []
        sep = ""
    if sep and all(math.isfinite(v) for v in values):
        kind = kind.strip().lower()
        if model == "diff":
            if kind == "arc" and len(values) == 2:
                return Arc(*values)
            if kind == "straight" and len(values) == 1:
                return Straight(values[0])
            if kind == "spin" and len(values) == 1:
                return Spin(values[0])
        elif model in ("tricycle", "car"):
            if kind == "arc" and len(values) == 3:
                return SteerArc(*values)
            if kind == "straight" and len(values) == 2:
                return SteerArc(values[0], 0.0, values[1])
        else:
            if kind == "arc" and len(values) == 3:
                return KellyArc(*values)
            if kind == "straight" and len(values) == 2:
                return KellyArc(values[0], 0.0, values[1])
    raise ModelError(
        f"--segment {text!r} is not understood for model {model!r}; expected {_SYNTAX[model]}"
    )
