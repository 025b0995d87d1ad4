"""A planned path of segments as the steps of a vehicle, for prediction and Monte Carlo.

One place decides what a noise argument means for a *path* (``odomkit predict`` and
``odomkit simulate``): :func:`path_model` validates the models into a :class:`PathModel`
(the closed-form family, the vehicle, the noise set), and :func:`path_steps` cuts the
segments into equal steps that the same engines as a logged track consume.

=================================  ==========  ========  ==============================
noise                              family      vehicle   segments
=================================  ==========  ========  ==============================
``WheelNoise``                     wheel       diff      Arc, Straight, Spin
``ClassicalNoise``                 classical   diff      Arc, Straight, Spin
``(SpeedNoise, GyroNoise)``        gyro        gyro      KellyArc
``(SpeedNoise, CompassNoise)``     compass     compass   KellyArc
=================================  ==========  ========  ==============================
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps
from odomkit.noise import NoiseModel, NoiseSet
from odomkit.path import Arc, KellyArc, Segment, Spin, Straight
from odomkit.robot import ROBOT_TYPES, DiffDrive, Robot

__all__ = [
    "PathModel",
    "path_model",
    "segment_motion",
    "path_steps",
    "check_segments",
    "check_partitions",
    "check_wheel_base",
]

# family -> (the models it may hold, the vehicle it describes); SpeedNoise is optional.
_FAMILIES: dict[str, tuple[frozenset[str], str]] = {
    "wheel": (frozenset({"WheelNoise"}), "diff"),
    "classical": (frozenset({"ClassicalNoise"}), "diff"),
    "gyro": (frozenset({"GyroNoise", "SpeedNoise"}), "gyro"),
    "compass": (frozenset({"CompassNoise", "SpeedNoise"}), "compass"),
}
_EXPECTED = ("WheelNoise, ClassicalNoise, (SpeedNoise, GyroNoise) or (SpeedNoise, CompassNoise)")


@dataclass(frozen=True)
class PathModel:
    """What a noise argument means for a planned path.

    Attributes
    ----------
    family : {"wheel", "classical", "gyro", "compass"}
        The closed-form family (Chong–Kleeman or Kelly).
    noise : NoiseSet
        The validated models.
    robot : Robot
        The vehicle: ``DiffDrive(wheel_base)`` for the differential-drive families, a
        nominal ``GyroOdometry``/``CompassOdometry`` for Kelly's.
    """

    family: str
    noise: NoiseSet
    robot: Robot

    @property
    def diff(self) -> bool:
        """Segments are wheel travels (Arc, Straight, Spin), not speed/yaw rate (KellyArc)."""
        return self.robot.type_name == "diff"


def check_partitions(partitions: int) -> int:
    """A positive whole number of steps per segment."""
    return validate.positive_int(partitions, "partitions")


def check_wheel_base(wheel_base: float | None) -> float:
    """The differential-drive models' wheel base, a positive number of metres."""
    if wheel_base is None:
        raise ModelError("the differential-drive model needs a wheel base (--wheel-base, metres)")
    return validate.positive(wheel_base, "wheel base", unit="m")


def path_model(noise: NoiseModel | Sequence[NoiseModel | None] | NoiseSet,
               wheel_base: float | None = None, purpose: str = "prediction") -> PathModel:
    """Validate a noise argument for a path and pick its family and vehicle.

    Parameters
    ----------
    noise : NoiseModel, sequence of NoiseModel, or NoiseSet
        See the module table; SpeedNoise may be left out of the Kelly families.
    wheel_base : float, optional
        B [m], required by the differential-drive families.
    purpose : str
        Named in the error message (``"prediction"`` or ``"simulation"``).

    >>> from odomkit.noise import WheelNoise
    >>> path_model(WheelNoise(0.001, 0.001), 0.4).family
    'wheel'
    """
    models = NoiseSet.of(noise)
    names = frozenset(type(m).__name__ for m in models.models)
    family = models.family
    if family not in _FAMILIES or not names <= _FAMILIES[family][0]:
        listed = ", ".join(type(m).__name__ for m in models.models) or "nothing"
        raise ModelError(f"noise ({listed}) is not a {purpose} model; expected {_EXPECTED}")
    vehicle = _FAMILIES[family][1]
    robot: Robot = (DiffDrive(check_wheel_base(wheel_base)) if vehicle == "diff"
                    else ROBOT_TYPES[vehicle]())
    models.check_robot(robot)
    return PathModel(family, models, robot)


def check_segments(segments: Iterable[Segment], model: PathModel) -> list[Segment]:
    """The segments as a list, each of the kind the model's vehicle drives."""
    segs = list(segments)
    for k, seg in enumerate(segs):
        ok = isinstance(seg, Arc | Straight | Spin) if model.diff else isinstance(seg, KellyArc)
        if not ok:
            want = "Arc, Straight or Spin" if model.diff else "KellyArc (speed, yaw rate, duration)"
            raise ModelError(f"segment {k + 1} is {seg!r}; the {model.family} model needs {want}")
    return segs


def segment_motion(seg: Segment, wheel_base: float) -> tuple[float, float]:
    """(arc length [m], heading change [rad]) of one segment."""
    if isinstance(seg, KellyArc):
        return seg.speed * seg.duration, seg.yaw_rate * seg.duration
    left, right = seg.wheel_travel(wheel_base)
    return 0.5 * (left + right), (right - left) / wheel_base  # Chong–Kleeman eq. (14)


def path_steps(segments: Sequence[Segment], model: PathModel, partitions: int,
               robot: Robot | None = None, scales: tuple[float, float] = (1.0, 1.0)) -> BodySteps:
    """Cut each segment into ``partitions`` equal steps of the model's vehicle.

    Parameters
    ----------
    segments : sequence of Segment, length S
    model : PathModel
    partitions : int
        Steps per segment, n.
    robot : Robot, optional
        The vehicle that drives the path (default ``model.robot``); a Monte Carlo of a
        robot with systematic errors drives the commanded wheel travels with its true
        wheel base.
    scales : (float, float)
        True/nominal distance per tick of the left and right wheel (systematic errors).

    Returns
    -------
    BodySteps
        S·n steps: ``dd``, ``dtheta``, ``dt`` (Kelly segments; zero for wheel segments)
        and the raw inputs the noise models ask for (``d_left``/``d_right`` [m] of a
        differential drive).
    """
    n = check_partitions(partitions)
    robot = model.robot if robot is None else robot
    dd, dth, dt, d_left, d_right = [], [], [], [], []
    for seg in segments:
        if model.diff:
            # commanded travels use the nominal wheel base (a spin is commanded with it)
            left, right = seg.wheel_travel(model.robot.wheel_base)  # type: ignore[union-attr]
            left, right = scales[0] * left, scales[1] * right
            base = robot.effective_wheel_base  # type: ignore[union-attr]
            d, a = 0.5 * (left + right), (right - left) / base
            d_left.append(np.full(n, left / n))
            d_right.append(np.full(n, right / n))
            dt.append(np.zeros(n))
        else:
            d, a = segment_motion(seg, 1.0)
            dt.append(np.full(n, seg.duration / n))  # type: ignore[union-attr]
        dd.append(np.full(n, d / n))
        dth.append(np.full(n, a / n))

    def cat(parts: list[NDArray[np.float64]]) -> NDArray[np.float64]:
        return np.concatenate(parts) if parts else np.zeros(0)

    inputs = {"d_left": cat(d_left), "d_right": cat(d_right)} if model.diff else {}
    return BodySteps(cat(dd), cat(dth), cat(dt), inputs, robot)
