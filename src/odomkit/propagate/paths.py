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
``TurnNoise`` (and those two)      gyro        gyro, unicycle  KellyArc
``(SpeedNoise, CompassNoise)``     compass     compass         KellyArc
``TricycleNoise``, ``SpeedNoise``  steering    tricycle, car   SteerArc
=================================  ==========  ==============  ==========================

The vehicle is the family's first unless a ``robot`` is given (a unicycle, a steered
vehicle, or a robot with its own geometry). With a ``robot`` the path takes every set of
models that ``odomkit track`` takes for that vehicle on a log (each model's own
``check_robot``): a fitted robot's noise as ``fit-noise`` wrote it (a diff robot's
WheelNoise, SpeedNoise, LateralSlipNoise and ParameterUncertainty), bias alone, a lateral
slip alone. Without one the set must name its family (the table); SpeedNoise,
ParameterUncertainty and LateralSlipNoise join any family but the classical (which takes
a lateral slip only). A closed form exists for the table's white models alone
(:attr:`PathModel.closed_form`); every other set is predicted by the track's engines on
the path's steps. One exception: a diff path's segments (Arc, Straight, Spin) have no
duration, so noise that grows with time (a GyroNoise) cannot be predicted on one.

Noise given *per sample* (:attr:`odomkit.noise.NoiseModel.per_sample`: a TricycleNoise's
σ of each sample's speed, steering angle and period) means something only with the sample
period T: a stretch of D seconds has D/T samples, each with its own error. A path with
such noise needs ``sample_period``, and its steps are then the samples (D/T per segment,
a whole number), as a log's rows are in ``track``, whatever ``partitions`` says. Any
path with durations may be given one (the engines then step its samples). A compass path
needs its compass's period (``compass_period``, default
:data:`odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`; ``sample_period`` is the same period):
its steps are the compass samples, each reading with an error of variance σ_θθ/T.
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
from odomkit.noise import CompassNoise, GyroNoise, NoiseModel, NoiseSet
from odomkit.noise.kelly import DEFAULT_COMPASS_PERIOD, compass_sample_count
from odomkit.path import Arc, KellyArc, Segment, Spin, SteerArc, Straight
from odomkit.robot import ROBOT_TYPES, DiffDrive, Robot

__all__ = [
    "PathModel",
    "path_model",
    "segment_motion",
    "path_steps",
    "compass_samples",
    "segment_samples",
    "check_segments",
    "check_partitions",
    "check_wheel_base",
]

# family -> the vehicles it describes (the first by default)
_FAMILIES: dict[str, tuple[str, ...]] = {
    "wheel": ("diff",), "classical": ("diff",), "gyro": ("gyro", "unicycle"), "compass": ("compass",),
    "steering": ("tricycle", "car"),
}
# family -> the models its closed form takes (odomkit.propagate.predict): white noise only;
# every other set goes to the track's engines.
_CLOSED: dict[str, frozenset[str]] = {
    "wheel": frozenset({"WheelNoise", "LateralSlipNoise"}),
    "classical": frozenset({"ClassicalNoise", "LateralSlipNoise"}),
    "gyro": frozenset({"GyroNoise", "SpeedNoise", "TurnNoise", "LateralSlipNoise"}),
    "compass": frozenset({"CompassNoise", "SpeedNoise", "LateralSlipNoise"}),
}
_EXPECTED = ("WheelNoise, ClassicalNoise, (SpeedNoise, GyroNoise, TurnNoise) or (SpeedNoise, CompassNoise), "
             "with or without a SpeedNoise, a ParameterUncertainty and a LateralSlipNoise; or "
             "robot= and any noise odomkit track takes for it")
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
    sample_period : float or None
        The other families: the sample period T [s] whose samples are the path's steps
        (required with per-sample noise); None where ``partitions`` cut the segments.
    """

    family: str
    noise: NoiseSet
    robot: Robot
    compass_period: float | None = None
    sample_period: float | None = None

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

    @property
    def closed_form(self) -> bool:
        """The family has a closed form for these models: white noise of the family's own
        (:mod:`odomkit.propagate.predict`), no bias, no other model beside it."""
        names = {type(m).__name__ for m in self.noise.models}
        return not self.noise.bias and self.family in _CLOSED and names <= _CLOSED[self.family]


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
               compass_period: float | None = None, robot: Robot | None = None,
               sample_period: float | None = None) -> PathModel:
    """Validate a noise argument for a path and pick its family and vehicle.

    Parameters
    ----------
    noise : NoiseModel, sequence of NoiseModel, or NoiseSet
        See the module docstring: without ``robot`` a set that names its family (the
        table); with ``robot`` any set ``odomkit track`` takes for that vehicle.
    wheel_base : float, optional
        B [m], required by the differential-drive families unless ``robot`` is given.
    purpose : str
        Named in the error message (``"prediction"`` or ``"simulation"``).
    compass_period : float, optional
        Compass family: the sample period T [s] of the compass (default
        :data:`~odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`); an error for the others.
    robot : Robot, optional
        The vehicle (default: the family's, see the module docstring).
    sample_period : float, optional
        The sample period T [s] of the odometry: a segment of D seconds has D/T samples,
        which become the path's steps. Required with per-sample noise
        (:attr:`~odomkit.noise.NoiseModel.per_sample`, a TricycleNoise); a compass's is
        its ``compass_period``; a diff path (no durations) takes none.

    Examples
    --------
    >>> from odomkit.noise import SpeedNoise, WheelNoise
    >>> path_model(WheelNoise(0.001, 0.001), 0.4).family
    'wheel'
    >>> m = path_model((WheelNoise(0.001, 0.001), SpeedNoise(1e-5)), 0.4)
    >>> m.family, m.closed_form
    ('wheel', False)
    """
    models = NoiseSet.of(noise)
    names = frozenset(type(m).__name__ for m in models.models)
    listed = ", ".join(type(m).__name__ for m in models.models) or "nothing"
    if robot is not None:
        # The vehicle decides, as on a log: a set is a model of it when every model
        # applies to it (checked below); the classical model keeps its own step map.
        family = "classical" if models.family == "classical" and robot.type_name == "diff" else next(
            (f for f, vehicles in _FAMILIES.items() if robot.type_name in vehicles), None)
        if family is None:
            raise ModelError(f"a {type(robot).__name__} has no planned-path model")
        if robot.type_name == "diff" and wheel_base is not None and wheel_base != robot.wheel_base:  # type: ignore[union-attr]
            raise ModelError(f"wheel_base {wheel_base!r} m differs from the robot's "
                             f"{robot.wheel_base!r} m; give one")  # type: ignore[union-attr]
    else:
        family = models.family
        if family is None and "TricycleNoise" in names:
            raise ModelError(f"noise ({listed}) is not a {purpose} model without a robot: it "
                             "describes a steered vehicle; give the robot (a Tricycle or Car)")
        if family not in _FAMILIES:
            raise ModelError(f"noise ({listed}) is not a {purpose} model; expected {_EXPECTED}")
        vehicle = _FAMILIES[family][0]
        robot = DiffDrive(check_wheel_base(wheel_base)) if vehicle == "diff" else ROBOT_TYPES[vehicle]()
    try:
        models.check_robot(robot)
    except ModelError as exc:
        raise ModelError(f"noise ({listed}) is not a {purpose} model of a {robot.type_name} robot "
                         f"({exc}); expected {_EXPECTED}") from None
    if robot.type_name == "diff" and models.get(GyroNoise) is not None:
        # A log has time stamps; a diff path's segments are wheel travels only.
        raise ModelError("GyroNoise grows with time, and a diff path's segments (Arc, Straight, "
                         "Spin) have no duration; predict a gyro robot's path (KellyArc) instead")
    own_map = [type(m).__name__ for m in models.models if m.step_map is not None]
    if own_map and robot.measures_heading:
        raise ModelError(f"{own_map[0]} rotates, then translates, by an integrated heading; a "
                         f"{robot.type_name} robot measures its heading")
    if family == "compass":
        if sample_period is not None and compass_period is not None and sample_period != compass_period:
            raise ModelError(f"sample_period {sample_period!r} s and compass_period "
                             f"{compass_period!r} s differ; a compass's samples are its readings: give one")
        period = next((p for p in (compass_period, sample_period) if p is not None), DEFAULT_COMPASS_PERIOD)
        return PathModel(family, models, robot, validate.positive(period, "compass_period", unit="s"))
    if compass_period is not None:
        raise ModelError(f"compass_period applies to the compass model, not the {family} model")
    if sample_period is not None:
        if robot.type_name == "diff":
            raise ModelError("sample_period (--sample-period) needs segments with durations (KellyArc, "
                             "SteerArc: --segment arc:V,OMEGA,T); a diff path's segments are wheel travels")
        return PathModel(family, models, robot,
                         sample_period=validate.positive(sample_period, "sample_period", unit="s"))
    # A model with a step map of its own (classical) has its σ per step: on a diff path
    # the steps are its partitions (Chong–Kleeman's model), on a log its rows, so on any
    # other vehicle's path its samples.
    per_sample = [type(m).__name__ for m in models.models
                  if m.per_sample or (m.step_map is not None and family != "classical")]
    if per_sample:
        raise ModelError(f"{per_sample[0]} is white noise per sample: give the sample period T "
                         "(sample_period [s], --sample-period), so that a segment of D seconds has "
                         "D/T samples")
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
    if model.sample_period is not None:
        segment_samples(segs, model.sample_period)
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
    return segment_samples(segments, period, "compass")


def segment_samples(segments: Sequence[Segment], period: float, sensor: str = "sample") -> list[int]:
    """Samples (steps) of each segment with a duration (KellyArc, SteerArc) at the sample
    period ``period`` [s]: duration/period, which must be a whole number
    (:func:`odomkit.noise.kelly.compass_sample_count`; ``sensor`` names the period in
    its message).

    Examples
    --------
    >>> segment_samples([SteerArc(1.0, 0.1, 2.0), SteerArc(1.0, 0.0, 0.5)], 0.05)
    [40, 10]
    """
    return [compass_sample_count(seg.duration, period, k + 1, sensor=sensor)  # type: ignore[union-attr]
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
        Steps per segment, n. Ignored with a sample period (``model.sample_period``: a
        segment's steps are its samples, :func:`segment_samples`) and by the compass
        family (its steps are the compass samples, :func:`compass_samples`), as the rows
        of a log are.
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
        S·n steps (their samples with a sample period): ``dd``, ``dtheta``, ``dt`` (Kelly
        and steering segments; zero for wheel segments) and the raw inputs the noise
        models ask for (``d_left``/``d_right`` [m] of a differential drive; ``travel``
        [m] and ``steer`` [rad] of a steered vehicle; ``yaw_rate`` [rad/s] of gyro and
        unicycle; ``heading`` (M + 1,) [rad] of a compass).

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
    counts = (segment_samples(segments, model.sample_period) if model.sample_period is not None
              else [check_partitions(partitions)] * len(segments))
    robot = model.robot if robot is None else robot
    dd, dth, dt, d_left, d_right, travel, steer = [], [], [], [], [], [], []
    for seg, n in zip(segments, counts, strict=True):
        per = max(n, 1)  # a segment of no duration has no sample: no step
        if model.steered:
            s_k = seg.speed * seg.duration / per  # type: ignore[union-attr]
            travel.append(np.full(n, s_k))
            steer.append(np.full(n, seg.steer))  # type: ignore[union-attr]
            step_d, step_a = steering_body_steps(robot, s_k, seg.steer)  # type: ignore[arg-type, union-attr]
            dt.append(np.full(n, seg.duration / per))  # type: ignore[union-attr]
            dd.append(np.full(n, float(step_d)))
            dth.append(np.full(n, float(step_a)))
            continue
        if model.diff:
            # commanded travels use the nominal wheel base (a spin is commanded with it)
            left, right = seg.wheel_travel(model.robot.wheel_base)  # type: ignore[union-attr]
            left, right = scales[0] * left, scales[1] * right
            base = robot.effective_wheel_base  # type: ignore[union-attr]
            d, a = 0.5 * (left + right), (right - left) / base
            d_left.append(np.full(n, left / per))
            d_right.append(np.full(n, right / per))
            dt.append(np.zeros(n))
        else:
            d, a = segment_motion(seg, 1.0)
            dt.append(np.full(n, seg.duration / per))  # type: ignore[union-attr]
        dd.append(np.full(n, d / per))
        dth.append(np.full(n, a / per))

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
