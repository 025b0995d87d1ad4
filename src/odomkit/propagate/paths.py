"""A planned path of segments as the steps of a vehicle, for prediction and Monte Carlo.

One place decides what a noise argument means for a *path* (``odomkit predict`` and
``odomkit simulate``): :func:`path_model` validates the models into a :class:`PathModel`
(the closed-form family, the vehicle, the noise set), and :func:`path_steps` cuts the
segments into equal steps that the same engines as a logged track consume.

=================================  ==========  ==============  ==========================
noise                              family      vehicle         segments
=================================  ==========  ==============  ==========================
``WheelNoise``                     wheel       diff            Arc, Straight, Spin
``ClassicalNoise``                 classical   diff            Arc, Straight, Spin
``(SpeedNoise, GyroNoise)``        gyro        gyro, unicycle  KellyArc
``(SpeedNoise, CompassNoise)``     compass     compass         KellyArc
``TricycleNoise``, ``SpeedNoise``  steering    tricycle, car   SteerArc
=================================  ==========  ==============  ==========================

Any family but the classical takes a :class:`~odomkit.noise.ParameterUncertainty` (the
vehicle's bias) too, and every family a :class:`~odomkit.noise.LateralSlipNoise`. The
vehicle is the family's first unless a ``robot`` is given (a unicycle, a steered vehicle,
or a robot with its own geometry); a set of models that names no family (bias alone,
steering noise, a lateral slip alone) needs the robot.

A compass path also needs the compass's sample period T (``compass_period``, default
:data:`odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`): its steps are the compass samples,
each reading with an error of variance σ_θθ/T, as a compass log's rows are in ``track``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, steering_body_steps
from odomkit.noise import CompassNoise, NoiseModel, NoiseSet
from odomkit.noise.kelly import DEFAULT_COMPASS_PERIOD, compass_sample_count
from odomkit.path import Arc, KellyArc, Segment, Spin, SteerArc, Straight
from odomkit.robot import ROBOT_TYPES, DiffDrive, Robot

__all__ = [
    "PathModel",
    "path_model",
    "segment_motion",
    "path_steps",
    "compass_samples",
    "check_segments",
    "check_partitions",
    "check_wheel_base",
]

# family -> (the models it may hold, the vehicles it describes: the first by default);
# SpeedNoise, ParameterUncertainty and LateralSlipNoise (every family) are optional.
_FAMILIES: dict[str, tuple[frozenset[str], tuple[str, ...]]] = {
    "wheel": (frozenset({"WheelNoise", "ParameterUncertainty", "LateralSlipNoise"}), ("diff",)),
    "classical": (frozenset({"ClassicalNoise", "LateralSlipNoise"}), ("diff",)),
    "gyro": (frozenset({"GyroNoise", "SpeedNoise", "ParameterUncertainty", "LateralSlipNoise"}),
             ("gyro", "unicycle")),
    "compass": (frozenset({"CompassNoise", "SpeedNoise", "ParameterUncertainty", "LateralSlipNoise"}),
                ("compass",)),
    "steering": (frozenset({"TricycleNoise", "SpeedNoise", "ParameterUncertainty", "LateralSlipNoise"}),
                 ("tricycle", "car")),
}
_EXPECTED = ("WheelNoise, ClassicalNoise, (SpeedNoise, GyroNoise) or (SpeedNoise, CompassNoise), "
             "with or without a ParameterUncertainty and a LateralSlipNoise; or a robot and its noise")
# The segments each vehicle drives.
_SEGMENTS: dict[str, tuple[type, ...]] = {
    "diff": (Arc, Straight, Spin), "gyro": (KellyArc,), "unicycle": (KellyArc,),
    "compass": (KellyArc,), "tricycle": (SteerArc,), "car": (SteerArc,),
}
_SEGMENT_NAMES = {"diff": "Arc, Straight or Spin", "gyro": "KellyArc (speed, yaw rate, duration)",
                  "tricycle": "SteerArc (wheel speed, steering angle, duration)"}


@dataclass(frozen=True)
class PathModel:
    """What a noise argument means for a planned path.

    Attributes
    ----------
    family : {"wheel", "classical", "gyro", "compass", "steering"}
        The family (Chong–Kleeman's or Kelly's closed forms; steered vehicles have none).
    noise : NoiseSet
        The validated models.
    robot : Robot
        The vehicle: the ``robot`` given, else ``DiffDrive(wheel_base)`` for the
        differential-drive families, a nominal ``GyroOdometry``/``CompassOdometry`` for
        Kelly's.
    compass_period : float or None
        Compass family: the compass's sample period T [s]; None for the others.
    """

    family: str
    noise: NoiseSet
    robot: Robot
    compass_period: float | None = None

    @property
    def var_heading(self) -> float:
        """Compass family: variance of one compass reading, σ_θθ/T [rad²]."""
        if self.compass_period is None:
            raise ModelError(f"the {self.family} model has no compass")
        compass = self.noise.get(CompassNoise)
        return 0.0 if compass is None else compass.sample_variance(self.compass_period)

    @property
    def diff(self) -> bool:
        """Segments are wheel travels (Arc, Straight, Spin), not speed/yaw rate (KellyArc)."""
        return self.robot.type_name == "diff"

    @property
    def steered(self) -> bool:
        """Segments are a steered vehicle's wheel speed and steering angle (SteerArc)."""
        return self.robot.type_name in ("tricycle", "car")


def check_partitions(partitions: int) -> int:
    """A positive whole number of steps per segment."""
    return validate.positive_int(partitions, "partitions")


def check_wheel_base(wheel_base: float | None) -> float:
    """The differential-drive models' wheel base, a positive number of metres."""
    if wheel_base is None:
        raise ModelError("the differential-drive model needs a wheel base (--wheel-base, metres)")
    return validate.positive(wheel_base, "wheel base", unit="m")


def path_model(noise: NoiseModel | Sequence[NoiseModel | None] | NoiseSet,
               wheel_base: float | None = None, purpose: str = "prediction",
               compass_period: float | None = None, robot: Robot | None = None) -> PathModel:
    """Validate a noise argument for a path and pick its family and vehicle.

    Parameters
    ----------
    noise : NoiseModel, sequence of NoiseModel, or NoiseSet
        See the module table; SpeedNoise may be left out of the Kelly families.
    wheel_base : float, optional
        B [m], required by the differential-drive families unless ``robot`` is given.
    purpose : str
        Named in the error message (``"prediction"`` or ``"simulation"``).
    compass_period : float, optional
        Compass family: the sample period T [s] of the compass (default
        :data:`~odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`); an error for the others.
    robot : Robot, optional
        The vehicle (default: the family's, see the module docstring).

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> path_model(WheelNoise(0.001, 0.001), 0.4).family
    'wheel'
    """
    models = NoiseSet.of(noise)
    names = frozenset(type(m).__name__ for m in models.models)
    listed = ", ".join(type(m).__name__ for m in models.models) or "nothing"
    family = models.family
    if family is None and robot is not None:
        family = next((f for f, (_, vehicles) in _FAMILIES.items() if robot.type_name in vehicles
                       and f != "classical"), None)
    elif family is None and "TricycleNoise" in names and names <= _FAMILIES["steering"][0]:
        raise ModelError(f"noise ({listed}) is not a {purpose} model without a robot: it "
                         "describes a steered vehicle; give the robot (a Tricycle or Car)")
    if family not in _FAMILIES or not names <= _FAMILIES[family][0]:
        raise ModelError(f"noise ({listed}) is not a {purpose} model"
                         + (f" of a {robot.type_name} robot" if robot is not None else "")
                         + f"; expected {_EXPECTED}")
    vehicles = _FAMILIES[family][1]
    if robot is None:
        vehicle = vehicles[0]
        robot = (DiffDrive(check_wheel_base(wheel_base)) if vehicle == "diff"
                 else ROBOT_TYPES[vehicle]())
    elif robot.type_name not in vehicles:
        raise ModelError(f"noise ({listed}) is a {family} model, not one of a {robot.type_name} robot")
    elif robot.type_name == "diff" and wheel_base is not None and wheel_base != robot.wheel_base:  # type: ignore[union-attr]
        raise ModelError(f"wheel_base {wheel_base!r} m differs from the robot's "
                         f"{robot.wheel_base!r} m; give one")  # type: ignore[union-attr]
    models.check_robot(robot)
    if family == "compass":
        period = DEFAULT_COMPASS_PERIOD if compass_period is None else compass_period
        return PathModel(family, models, robot,
                         validate.positive(period, "compass_period", unit="s"))
    if compass_period is not None:
        raise ModelError(f"compass_period applies to the compass model, not the {family} model")
    return PathModel(family, models, robot)


def check_segments(segments: Iterable[Segment], model: PathModel) -> list[Segment]:
    """The segments as a list, each of the kind the model's vehicle drives (and, for a
    compass, lasting a whole number of compass periods: :func:`compass_samples`)."""
    segs = list(segments)
    kinds = _SEGMENTS[model.robot.type_name]
    for k, seg in enumerate(segs):
        if not isinstance(seg, kinds):
            want = _SEGMENT_NAMES.get(model.robot.type_name) or _SEGMENT_NAMES[
                "tricycle" if model.steered else "gyro"]
            raise ModelError(f"segment {k + 1} is {seg!r}; the {model.family} model needs {want}")
    if model.compass_period is not None:
        compass_samples(segs, model.compass_period)
        for k, seg in enumerate(segs):
            turn = abs(seg.yaw_rate) * model.compass_period  # type: ignore[union-attr]
            if not turn < math.pi:
                # two readings half a turn apart cannot tell which way the robot turned
                raise ModelError(f"segment {k + 1} turns by {turn:.3g} rad between compass "
                                 "readings (|yaw rate| × compass period); it must be below π")
    return segs


def compass_samples(segments: Sequence[Segment], period: float) -> list[int]:
    """Compass samples (steps) of each KellyArc segment: duration/period, which must be a
    whole number (:func:`odomkit.noise.kelly.compass_sample_count`).

    Examples
    --------
    >>> compass_samples([KellyArc(1.0, 0.0, 2.0), KellyArc(1.0, 0.5, 0.5)], 0.1)
    [20, 5]
    """
    return [compass_sample_count(seg.duration, period, k + 1)  # type: ignore[union-attr]
            for k, seg in enumerate(segments)]


def segment_motion(seg: Segment, wheel_base: float, robot: Robot | None = None) -> tuple[float, float]:
    """(arc length [m], heading change [rad]) of one segment (a SteerArc needs its
    ``robot``, a Tricycle or Car)."""
    if isinstance(seg, KellyArc):
        return seg.speed * seg.duration, seg.yaw_rate * seg.duration
    if isinstance(seg, SteerArc):
        if robot is None:
            raise ModelError("a SteerArc's motion depends on the vehicle: give the robot")
        d, a = steering_body_steps(robot, seg.speed * seg.duration, seg.steer)  # type: ignore[arg-type]
        return float(d), float(a)
    left, right = seg.wheel_travel(wheel_base)
    return 0.5 * (left + right), (right - left) / wheel_base  # Chong–Kleeman eq. (14)


def path_steps(segments: Sequence[Segment], model: PathModel, partitions: int,
               robot: Robot | None = None, scales: tuple[float, float] = (1.0, 1.0),
               theta0: float = 0.0) -> BodySteps:
    """Cut each segment into ``partitions`` equal steps of the model's vehicle.

    Parameters
    ----------
    segments : sequence of Segment, length S
    model : PathModel
    partitions : int
        Steps per segment, n. The compass family ignores it: its steps are the compass
        samples (:func:`compass_samples`), as the rows of a compass log are.
    robot : Robot, optional
        The vehicle that drives the path (default ``model.robot``); a Monte Carlo of a
        robot with systematic errors drives the commanded wheel travels with its true
        wheel base.
    scales : (float, float)
        True/nominal distance per tick of the left and right wheel (systematic errors).
    theta0 : float
        Start heading [rad]; the compass family's measured headings start there.

    Returns
    -------
    BodySteps
        S·n steps: ``dd``, ``dtheta``, ``dt`` (Kelly and steering segments; zero for wheel
        segments) and the raw inputs the noise models ask for (``d_left``/``d_right`` [m]
        of a differential drive; ``travel`` [m] and ``steer`` [rad] of a steered vehicle;
        ``yaw_rate`` [rad/s] of gyro and unicycle; ``heading`` (M + 1,) [rad] of a compass).

    Examples
    --------
    >>> from odomkit.noise import CompassNoise
    >>> model = path_model(CompassNoise(1e-4), compass_period=0.5)
    >>> steps = path_steps([KellyArc(1.0, 0.2, 1.0)], model, 100)
    >>> steps.dt.tolist(), steps.inputs["heading"].tolist()
    ([0.5, 0.5], [0.0, 0.1, 0.2])
    """
    if model.compass_period is not None:
        return _compass_steps(segments, model, float(theta0))
    n = check_partitions(partitions)
    robot = model.robot if robot is None else robot
    dd, dth, dt, d_left, d_right, travel, steer = [], [], [], [], [], [], []
    for seg in segments:
        if model.steered:
            s_k = seg.speed * seg.duration / n  # type: ignore[union-attr]
            travel.append(np.full(n, s_k))
            steer.append(np.full(n, seg.steer))  # type: ignore[union-attr]
            step_d, step_a = steering_body_steps(robot, s_k, seg.steer)  # type: ignore[arg-type, union-attr]
            dt.append(np.full(n, seg.duration / n))  # type: ignore[union-attr]
            dd.append(np.full(n, float(step_d)))
            dth.append(np.full(n, float(step_a)))
            continue
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

    steps_dd, steps_dth, steps_dt = cat(dd), cat(dth), cat(dt)
    if model.diff:
        inputs = {"d_left": cat(d_left), "d_right": cat(d_right)}
    elif model.steered:
        inputs = {"travel": cat(travel), "steer": cat(steer)}
    else:
        rate = np.divide(steps_dth, steps_dt, out=np.zeros_like(steps_dth), where=steps_dt > 0)
        inputs = {"yaw_rate": rate}
    return BodySteps(steps_dd, steps_dth, steps_dt, inputs, robot)


def _compass_steps(segments: Sequence[Segment], model: PathModel, theta0: float) -> BodySteps:
    """One step per compass sample: Δd = V·T, Δθ = ω·T, dt = T; the nominal headings
    measured at the samples as the ``heading`` input."""
    period = model.compass_period
    assert period is not None
    counts = compass_samples(segments, period)
    speed = np.repeat([seg.speed for seg in segments], counts)  # type: ignore[union-attr]
    rate = np.repeat([seg.yaw_rate for seg in segments], counts)  # type: ignore[union-attr]
    dtheta = rate * period
    heading = theta0 + np.concatenate([[0.0], np.cumsum(dtheta)])
    return BodySteps(speed * period, dtheta, np.full(speed.size, period), {"heading": heading},
                     model.robot)
