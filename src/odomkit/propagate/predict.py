"""Error prediction for a planned path of segments: the library call behind
``odomkit predict``.

The noise model decides the odometry type:

=================================  ===========  ========================================
noise                              segments     closed form
=================================  ===========  ========================================
``WheelNoise``                     Arc, ...     Chong–Kleeman eq. (23), (25)
``ClassicalNoise``                 Arc, ...     Chong–Kleeman eq. (1)–(3), per piece
``(SpeedNoise, GyroNoise)``        KellyArc     Kelly eq. (11), (13), (15)
``TurnNoise`` (+ those two)        KellyArc     the same integral, q += α·|ωT|
``(SpeedNoise, CompassNoise)``     KellyArc     Kelly eq. (10) sampled every T (see
                                               :func:`~odomkit.propagate.closed_kelly.compass_arc_cov`)
``TricycleNoise`` (+ ``robot``)    SteerArc     none: ``recursion`` or ``transition``, at a ``sample_period``
=================================  ===========  ========================================

With a ``robot`` (the vehicle: a unicycle, a tricycle or car with its geometry, a robot
whose bias sensitivities need its parameters) ``noise`` may be any set of models that
``odomkit track`` propagates on that vehicle's logs, e.g. a fitted robot file's
``read_robot(path)`` pair as it is (:func:`odomkit.propagate.paths.path_model`). The
closed forms take the table's white models alone (and a lateral slip); bias noise
(:class:`~odomkit.noise.ParameterUncertainty`, a constant error over the run), a
:class:`~odomkit.noise.SpeedNoise` beside the wheels' and every other set are predicted
by the ``recursion`` and ``transition`` engines: the very engines of ``odomkit track``
(:func:`odomkit.propagate.recursion.iter_track_covariance`) on the path's steps
(:func:`odomkit.propagate.paths.path_steps`), so a planned path and a log of it give the
same covariance. A :class:`~odomkit.noise.LateralSlipNoise` (sideways slip) joins every
family and every engine: its sum adds to the position block, in the closed forms as its
integral over each arc (the exact sum over a compass's samples, or over the classical
model's pieces).

Engines: ``closed`` composes the closed forms segment by segment; ``recursion`` and
``transition`` cut each segment into ``partitions`` exact-arc steps and run the step
recursion (:mod:`odomkit.propagate.recursion`) or Kelly's transition-matrix solution
(:mod:`odomkit.propagate.transition`) on them. They converge to ``closed`` as the steps
shrink, which is how the closed forms are cross-checked.

Noise per *sample* (a :class:`~odomkit.noise.TricycleNoise`: σ of each sample's speed,
steering angle and period) needs the odometry's sample period T (``sample_period``): a
segment of D seconds has D/T samples, each with its own error, and those samples are the
engines' steps (``partitions`` does not apply), as a log's rows are in ``track``. Without
it the answer would depend on ``partitions`` (σ ∝ 1/√partitions), so it is refused.

A compass is predicted as ``odomkit track`` propagates a compass log: read every
``compass_period`` T [s], each reading with an independent error of variance σ_θθ/T
(:class:`~odomkit.noise.CompassNoise`), so the end heading has that finite variance. Its
steps are the compass samples whatever ``partitions`` says; the ``recursion`` and
``transition`` engines run the track's direct-heading engines on them and agree with
``closed`` to rounding (the closed form is the exact sum, not a limit).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import step_displacement
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    SpeedNoise,
    TurnNoise,
    WheelNoise,
)
from odomkit.path import Segment
from odomkit.propagate.closed import classical_step, wheel_arc_cov
from odomkit.propagate.closed_kelly import compass_arc_cov, gyro_arc_cov
from odomkit.propagate.lateral import lateral_segment_cov
from odomkit.propagate.paths import (
    PathModel,
    check_partitions,
    check_segments,
    compass_samples,
    path_model,
    path_steps,
    segment_motion,
)
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import Robot

__all__ = [
    "Engine",
    "ENGINES",
    "DEFAULT_PARTITIONS",
    "Prediction",
    "check_covariance",
    "discretise_path",
    "predict",
]

Engine = Literal["closed", "recursion", "transition"]
ENGINES: tuple[Engine, ...] = ("closed", "recursion", "transition")
DEFAULT_PARTITIONS = 1000
"""Steps per segment for the ``recursion`` and ``transition`` engines."""


@dataclass(frozen=True)
class Prediction:
    """Predicted end pose and its covariance.

    Attributes
    ----------
    pose : ndarray, shape (3,)
        [x (m), y (m), θ (rad)], θ continuous (not wrapped).
    cov : ndarray, shape (3, 3)
        Covariance in the order x, y, θ [m², m·rad, rad²]. For compass odometry the θ
        variance is that of the last compass reading, σ_θθ/T.
    model : str
        ``wheel``, ``classical``, ``gyro``, ``compass`` or ``steering``.
    engine : str
    """

    pose: NDArray[np.float64]
    cov: NDArray[np.float64]
    model: str
    engine: str

    def __post_init__(self) -> None:
        for name in ("pose", "cov"):  # frozen means the numbers too
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def std(self) -> NDArray[np.float64]:
        """[σx, σy, σθ]; rounding-level negative variances read as 0."""
        var = np.diag(self.cov)
        return np.sqrt(np.where(var < 0, 0.0, var))

    @property
    def corr(self) -> dict[str, float]:
        """Correlation coefficients ``xy``, ``xtheta``, ``ytheta`` (NaN if a σ is 0)."""
        std = self.std
        out = {}
        for key, (i, j) in {"xy": (0, 1), "xtheta": (0, 2), "ytheta": (1, 2)}.items():
            den = std[i] * std[j]
            out[key] = float(self.cov[i, j] / den) if den > 0 else math.nan
        return out

    def to_dict(self) -> dict[str, Any]:
        """The prediction as plain values: keys ``pose`` [x, y, θ wrapped to [−π, π)],
        ``cov``, ``std``, ``corr`` {xy, xtheta, ytheta} (coefficients; NaN stands for
        undefined and prints as null), ``model`` and ``engine``. ``odomkit predict --json``
        adds the ROS layout of ``cov`` (:mod:`odomkit.workflows.predict`)."""
        pose = self.pose.copy()
        pose[2] = wrap_angle(pose[2])
        return {
            "pose": pose.tolist(),
            "cov": self.cov.tolist(),
            "std": self.std.tolist(),
            "corr": self.corr,
            "model": self.model,
            "engine": self.engine,
        }


def check_covariance(cov: ArrayLike, name: str = "initial covariance") -> NDArray[np.float64]:
    """Validate a 3×3 pose covariance: finite, symmetric, positive semi-definite.

    Raises :class:`~odomkit.errors.ModelError` naming ``name`` otherwise.

    Examples
    --------
    >>> check_covariance(np.diag([1.0, 1.0, 0.1])).shape
    (3, 3)
    """
    return validate.covariance(cov, name)


def discretise_path(
    segments: Iterable[Segment],
    noise: NoiseArg,
    wheel_base: float | None = None,
    partitions: int = DEFAULT_PARTITIONS,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Cut each segment into ``partitions`` equal exact-arc steps with their input noise
    (with ``sample_period``, into its samples: :func:`odomkit.propagate.paths.path_model`).

    The steps are :func:`odomkit.propagate.paths.path_steps`; each step's input
    covariance is the noise models' own (:meth:`odomkit.noise.NoiseSet.input_cov`):
    per-wheel noise gives each step's wheel travels L/n, R/n variances k²|L|/n, k²|R|/n
    (Chong–Kleeman eq. 18); gyro var(Δd) = α_ss·|V|·T/n, var(Δθ) = σ_gg·T/n (Kelly Table 1).

    Returns
    -------
    poses : ndarray, shape (M + 1, 3)
    dd, dtheta : ndarray, shape (M,)
        Step arc length [m] and heading change [rad].
    cov_input : ndarray, shape (M, 2, 2)
        Covariance of each step's (Δd, Δθ).

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Straight
    >>> poses, dd, dth, q = discretise_path([Straight(2.0)], WheelNoise(0.1, 0.1), 0.5, 4)
    >>> dd.tolist(), round(float(q[0, 0, 0]), 15)  # var(Δd) = (k²·0.5 + k²·0.5)/4
    ([0.5, 0.5, 0.5, 0.5], 0.0025)
    """
    model = path_model(noise, wheel_base, robot=robot, sample_period=sample_period)
    segs = check_segments(segments, model)
    if model.robot.measures_heading:
        raise ModelError("a compass path's steps are its compass samples, with no per-step "
                         "input covariance: use predict(..., engine='recursion') instead")
    steps = path_steps(segs, model, partitions)
    cov = model.noise.input_cov(steps, 0, len(steps))
    return _path_poses(steps.dd, steps.dtheta, pose0, model), steps.dd, steps.dtheta, cov


def _path_poses(dd: NDArray[np.float64], dth: NDArray[np.float64], pose0: ArrayLike,
                model: PathModel) -> NDArray[np.float64]:
    """The nominal poses of the path's steps by the noise's step map: the exact arc, or
    the classical model's own (Chong–Kleeman eq. (1): rotate by α, then translate D along
    the new heading)."""
    if model.noise.step_map("exact") == "exact":
        return dead_reckon(dd, dth, pose0, "exact")
    poses = np.empty((dd.size + 1, 3))
    poses[0] = np.asarray(pose0, dtype=float)
    poses[1:, 2] = poses[0, 2] + np.cumsum(dth)
    poses[1:, 0] = poses[0, 0] + np.cumsum(dd * np.cos(poses[1:, 2]))
    poses[1:, 1] = poses[0, 1] + np.cumsum(dd * np.sin(poses[1:, 2]))
    return poses


# --- closed forms, one per family: (pose, cov, segment, model) -> cov at the segment end
def _wheel_closed(pose: NDArray[np.float64], cov: NDArray[np.float64], seg: Segment,
                  model: PathModel) -> NDArray[np.float64]:
    b = model.robot.wheel_base  # type: ignore[union-attr]
    left, right = seg.wheel_travel(b)  # type: ignore[union-attr]
    return wheel_arc_cov(left, right, b, model.noise.require(WheelNoise), pose[2], cov)


def _gyro_closed(pose: NDArray[np.float64], cov: NDArray[np.float64], seg: Segment,
                 model: PathModel) -> NDArray[np.float64]:
    speed = model.noise.get(SpeedNoise) or SpeedNoise(0.0)
    gyro = model.noise.get(GyroNoise) or GyroNoise(0.0)
    if model.robot.type_name == "unicycle" and seg.speed == 0 and seg.yaw_rate == 0:  # type: ignore[union-attr]
        # A unicycle told to stand stands: no yaw-rate noise acts (GyroNoise.noisy_time),
        # as in the engines and the Monte Carlo.
        gyro = GyroNoise(0.0)
    return gyro_arc_cov(seg, speed, gyro, pose[2], cov, model.noise.get(TurnNoise))  # type: ignore[arg-type]


def _compass_closed(pose: NDArray[np.float64], cov: NDArray[np.float64], seg: Segment,
                    model: PathModel) -> NDArray[np.float64]:
    speed = model.noise.get(SpeedNoise) or SpeedNoise(0.0)
    return compass_arc_cov(seg, speed, model.noise.require(CompassNoise), pose[2], cov,  # type: ignore[arg-type]
                           period=model.compass_period)


def _compass_start(cov0: NDArray[np.float64], model: PathModel) -> NDArray[np.float64]:
    """The start covariance of a compass path: the heading is the first compass reading,
    whose error (variance σ_θθ/T) is independent of the start position; the θ row and
    column of ``cov0`` give way to it (as in ``track``)."""
    cov = np.zeros((3, 3))
    cov[:2, :2] = cov0[:2, :2]
    cov[2, 2] = model.var_heading
    return cov


def _compass_engines(segs: list[Segment], model: PathModel, p0: NDArray[np.float64],
                     c0: NDArray[np.float64], engine: str) -> Prediction:
    """The track's direct-heading engines on the compass samples of the path."""
    from odomkit.propagate.plan import plan_noise

    steps = path_steps(segs, model, 1, theta0=float(p0[2]))
    poses = dead_reckon(steps.dd, steps.dtheta, p0, "exact")
    if len(steps) == 0 and not model.noise.bias:  # no reading after the first: the start is the end
        return Prediction(poses[-1].copy(), c0, model.family, engine)
    if engine == "recursion" or model.noise.bias:
        from odomkit.propagate.recursion import iter_track_covariance

        cov_end = c0
        for _, chunk in iter_track_covariance(steps, poses, model.noise, c0, "exact", engine):
            cov_end = chunk[-1]
    else:
        from odomkit.propagate.transition import propagate_direct_heading

        plan = plan_noise(steps, model.noise, "exact")
        assert plan.var_heading is not None
        cov_end = propagate_direct_heading(poses[:-1, 2], steps.dd, steps.dtheta,
                                           plan.var_dd(0, len(steps)), plan.var_heading,
                                           c0[:2, :2], var_lateral=plan.var_lateral(0, len(steps)))[-1]
    cov_end = np.asarray(cov_end, dtype=float)
    return Prediction(poses[-1].copy(), 0.5 * (cov_end + cov_end.T), model.family, engine)


_CLOSED_FORMS = {"wheel": _wheel_closed, "gyro": _gyro_closed, "compass": _compass_closed}


def _track_engines(segs: list[Segment], model: PathModel, p0: NDArray[np.float64],
                   c0: NDArray[np.float64], engine: str, partitions: int) -> Prediction:
    """The track's engines (:func:`odomkit.propagate.recursion.iter_track_covariance`,
    white and bias, any set of models the vehicle takes) on the path cut into equal steps
    (or its samples): one engine for a log and a planned path."""
    from odomkit.propagate.recursion import iter_track_covariance

    steps = path_steps(segs, model, partitions)
    poses = _path_poses(steps.dd, steps.dtheta, p0, model)
    cov_end = c0
    for _, chunk in iter_track_covariance(steps, poses, model.noise, c0, "exact", engine):
        cov_end = chunk[-1]
    cov_end = np.asarray(cov_end, dtype=float)
    return Prediction(poses[-1].copy(), 0.5 * (cov_end + cov_end.T), model.family, engine)


def predict(
    segments: Iterable[Segment],
    noise: NoiseArg,
    wheel_base: float | None = None,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    engine: Engine = "closed",
    partitions: int | None = None,
    compass_period: float | None = None,
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> Prediction:
    """Predict the end pose of a path of segments and its covariance.

    Parameters
    ----------
    segments : iterable of Segment
        Arc/Straight/Spin for the differential-drive models, KellyArc for gyro/compass
        (and a unicycle), SteerArc for a tricycle or car.
    noise : WheelNoise, ClassicalNoise, a tuple (SpeedNoise, GyroNoise) or
        (SpeedNoise, CompassNoise); with ``robot``, any set of models ``track`` takes
        for it (e.g. the noise of ``read_robot``)
        Selects the model (see the module docstring).
    wheel_base : float, optional
        B [m]; required by the differential-drive models.
    pose0 : array_like, shape (3,)
        Start pose [m, m, rad].
    cov0 : array_like, shape (3, 3), optional
        Start covariance (default zero); must be symmetric PSD.
    engine : {"closed", "recursion", "transition"}
    partitions : int, optional
        Pieces per segment. ``closed``: ignored by the consistent models; for the
        classical model the number of eq. (1) steps per segment (default 1), which
        changes its answer. ``recursion``/``transition``: steps per segment (default
        :data:`DEFAULT_PARTITIONS`; the classical model then takes that many steps).
        Ignored with a ``sample_period`` and by the compass model: the steps are the
        samples.
    compass_period : float, optional
        Compass model only: the compass's sample period T [s] (default
        :data:`~odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`); every segment must last a
        whole number of periods. Each reading has an error of variance σ_θθ/T, which is
        the end heading's variance; the θ row and column of ``cov0`` give way to it.
    robot : Robot, optional
        The vehicle (:func:`odomkit.propagate.paths.path_model`): required for a tricycle
        or car (SteerArc segments), optional otherwise.
    sample_period : float, optional
        The odometry's sample period T [s]: every segment (KellyArc, SteerArc) lasts a
        whole number of periods, and its samples are the engines' steps. Required with
        per-sample noise (a TricycleNoise); a compass's is its ``compass_period``.

    Returns
    -------
    Prediction

    Notes
    -----
    The classical model moves as its eq. (1) says (rotate by α, then go D along the new
    heading, with D = (L + R)/2 and α = (R − L)/B per piece), so on a curved segment its
    mean is a polygon that approaches the arc only as the pieces shrink; on straight
    lines and spins it is exact.

    Examples
    --------
    Chong–Kleeman Table 1 (I): arc L = 3 m, R = 1 m, B = 0.4 m, k = 0.001 m^½.

    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Arc
    >>> p = predict([Arc(3.0, 1.0)], WheelNoise(0.001, 0.001), wheel_base=0.4)
    >>> [round(v, 6) for v in p.to_dict()["pose"]], [float(f"{s:.5g}") for s in p.std]
    ([-0.38357, -0.286535, 1.283185], [0.0014376, 0.0024666, 0.005])

    A tricycle (σ per sample of its 20 Hz log) with a steering offset it is unsure of:

    >>> from odomkit.noise import ParameterUncertainty, TricycleNoise
    >>> from odomkit.path import SteerArc
    >>> from odomkit.robot import Tricycle
    >>> p = predict([SteerArc(0.5, 0.2, 10.0)], (TricycleNoise(0.02, 0.01),
    ...             ParameterUncertainty(sigma_steering_offset=0.005)), robot=Tricycle(0.5),
    ...             engine="recursion", sample_period=0.05)
    >>> [float(f"{s:.3g}") for s in p.std]
    [0.108, 0.0258, 0.0498]
    """
    if engine not in ENGINES:
        raise ModelError(f"unknown engine {engine!r}; expected one of {', '.join(ENGINES)}")
    model = path_model(noise, wheel_base, compass_period=compass_period, robot=robot,
                       sample_period=sample_period)
    segs = check_segments(segments, model)
    p0 = validate.pose(pose0)
    c0 = np.zeros((3, 3)) if cov0 is None else check_covariance(cov0)
    b = model.robot.wheel_base if model.diff else 1.0  # type: ignore[union-attr]
    if engine == "closed" and not model.closed_form:
        listed = ", ".join(type(m).__name__ for m in model.noise.models)
        what = ("bias noise" if model.noise.bias else f"the {model.family} model"
                if model.family == "steering" else f"noise ({listed})")
        raise ModelError(f"{what} has no closed form here; use engine 'recursion' or 'transition' "
                         "(odomkit predict --engine recursion)")
    if model.compass_period is not None:
        c0 = _compass_start(c0, model)
        if engine != "closed":
            return _compass_engines(segs, model, p0, c0, engine)
    if engine != "closed":
        n = DEFAULT_PARTITIONS if partitions is None else check_partitions(partitions)
        return _track_engines(segs, model, p0, c0, engine, n)

    pose, cov = p0.copy(), c0
    slip = (model.noise.get(LateralSlipNoise) or LateralSlipNoise(0.0)).alpha_lateral
    if model.family == "classical":
        classical = model.noise.require(ClassicalNoise)
        pieces = 1 if partitions is None else check_partitions(partitions)
        for seg in segs:
            d, a = segment_motion(seg, b)
            for _ in range(pieces):
                pose, cov = classical_step(pose, cov, d / pieces, a / pieces, classical)  # type: ignore[arg-type]
                if slip:  # one straight piece along its new heading θ + α
                    cov = cov.copy()
                    cov[:2, :2] += lateral_segment_cov(slip, d / pieces, float(pose[2]), 0.0)
        return Prediction(pose, cov, model.family, engine)
    closed_form = _CLOSED_FORMS[model.family]
    samples = (compass_samples(segs, model.compass_period) if model.compass_period is not None
               else [None] * len(segs))
    for seg, count in zip(segs, samples, strict=True):
        cov = closed_form(pose, cov, seg, model)
        d, a = segment_motion(seg, b)
        if slip:
            # The slip's running sum adds to the position block whatever the other noise
            # does (odomkit.propagate.lateral): the integral over the arc, or the exact
            # sum over a compass's samples (the steps its engines take).
            cov = cov.copy()
            cov[:2, :2] += lateral_segment_cov(slip, d, float(pose[2]), a, count)
        dx, dy = step_displacement(pose[2], d, a, "exact")
        pose = pose + np.array([float(dx), float(dy), a])
    return Prediction(pose, cov, model.family, engine)

