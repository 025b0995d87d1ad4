"""What one Monte Carlo run does: path, noise and robot -> per-partition coefficients.

Every partition's body motion is an affine map of two standard normals z0, z1
(see :mod:`odomkit.simulate._kernels`), so all noise models share one kernel.

Bias noise (:class:`~odomkit.noise.ParameterUncertainty`): each run draws its parameter
errors β ~ N(0, diag σ²) once (p standard normals, :mod:`odomkit.simulate.blocks`), and
every partition of segment j then moves by K_j β more, K_j = ∂(Δd, Δθ)/∂β of that
partition (the model's own ``bias_jacobian``, checked against the vehicles' kinematics by
finite differences in tests/noise): ``Plan.bias`` holds K_j diag(σ). A compass's heading
offset moves every reading (``Plan.bias_heading`` = ∂θ/∂β · σ).

Lateral slip (:class:`~odomkit.noise.LateralSlipNoise`): every partition of segment j also
moves across its own (noisy) chord by ``Plan.lateral[j]`` = √(α_lat·|Δd|) times a third
standard normal (:mod:`odomkit.simulate.blocks` draws three per partition then).

A sample period T (``sample_period``; required with per-sample noise such as a
:class:`~odomkit.noise.TricycleNoise`, :func:`odomkit.propagate.paths.path_model`) makes
the partitions the samples: segment j is cut into its D_j/T samples (``Plan.counts``),
each with its own noise, as the rows of a log at that period are.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, steering_body_steps
from odomkit.noise import NoiseSet
from odomkit.path import Arc, KellyArc, Segment, Spin, Straight
from odomkit.propagate.paths import PathModel, check_segments, compass_samples, path_model, segment_samples
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import DiffDrive, Robot, SystematicErrors

__all__ = ["Plan", "resolve_model", "make_plan"]


@dataclass(frozen=True)
class Plan:
    """What one run does, in kernel terms (picklable, sent to Dask workers).

    ``coefs[j]`` maps two standard normals to the body motion of one partition of segment
    j (see :mod:`odomkit.simulate._kernels`); ``kind`` is ``"increment"`` (exact arc),
    ``"classical"`` (rotate, then translate) or ``"compass"`` (7 coefficients, see
    :func:`odomkit.simulate._kernels.advance_compass_numpy`). ``partitions`` is the number
    of kernel steps per segment (a compass segment may use fewer: its ``m``).
    ``bias[j]`` (2, p) = K_j diag(σ) moves each partition of segment j by ``bias[j] @ zβ``
    for a run's p bias normals zβ; ``bias_heading`` (p,) moves a compass's every reading
    by ``bias_heading @ zβ``. Both None without bias noise. ``lateral[j]`` is the σ [m]
    of the sideways slip of one kernel step of segment j (along the step's chord, times
    a third normal per step); None without a lateral slip (or with a zero one), so that
    the draws, and every number, stay as without the model. ``counts`` (S,), when set,
    is the number of kernel steps of each segment (its samples at a sample period);
    ``partitions`` is then the largest.
    """

    kind: str
    coefs: NDArray[np.float64]  # (S, 6); (S, 7) for a compass
    partitions: int
    pose0: NDArray[np.float64]  # (3,)
    factor0: NDArray[np.float64]  # (3, 3): initial pose = pose0 + factor0 @ z
    bias: NDArray[np.float64] | None = None  # (S, 2, p)
    bias_heading: NDArray[np.float64] | None = None  # (p,)
    lateral: NDArray[np.float64] | None = None  # (S,)
    counts: NDArray[np.int64] | None = None  # (S,)


def _cov_factor(cov0: ArrayLike | None) -> NDArray[np.float64]:
    """A with A·Aᵀ = cov0, from the eigen-decomposition so a singular PSD cov0 works."""
    if cov0 is None:
        return np.zeros((3, 3))
    cov = validate.covariance(cov0, "initial covariance", variances=True)
    w, v = np.linalg.eigh(cov)
    # directions with rounding-level variance are the null space: sample nothing there
    w = np.where(w > 1e-14 * max(float(np.max(w)), 0.0), w, 0.0)
    return np.asarray(v * np.sqrt(w))


def resolve_model(noise: NoiseArg, wheel_base: float | None = 1.0,
                  compass_period: float | None = None, robot: Robot | None = None,
                  sample_period: float | None = None) -> PathModel:
    """The odometry model a noise argument selects, as in ``predict``
    (:func:`odomkit.propagate.paths.path_model`).

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> resolve_model(WheelNoise(0.001, 0.001)).family
    'wheel'
    """
    return path_model(noise, wheel_base if robot is None else None, purpose="simulation",
                      compass_period=compass_period, robot=robot, sample_period=sample_period)


def _partition_steps(model: PathModel, path: Sequence[Segment], counts: Sequence[int], robot: Robot,
                     scales: tuple[float, float]) -> BodySteps:
    """One partition (1/k_j, k_j = ``counts[j]``) of every segment, as the steps the noise
    models are asked about: a differential drive's commanded wheel travels (nominal wheel
    base) scaled by the true wheel sizes, Kelly's speed·Δt and yaw rate·Δt, or a steered
    vehicle's wheel travel and steering angle."""
    dd, dth, dt, d_left, d_right = (np.empty(len(path)) for _ in range(5))
    travel, steer = np.empty(len(path)), np.empty(len(path))
    for j, (seg, count) in enumerate(zip(path, counts, strict=True)):
        k = max(count, 1)  # a segment of no duration has no sample (the kernel takes none)
        if model.steered:
            dt[j] = seg.duration / k  # type: ignore[union-attr]
            travel[j], steer[j] = seg.speed * dt[j], seg.steer  # type: ignore[union-attr]
            step_d, step_a = steering_body_steps(robot, travel[j], steer[j])  # type: ignore[arg-type]
            dd[j], dth[j] = float(step_d), float(step_a)
        elif model.diff:
            left, right = seg.wheel_travel(model.robot.wheel_base)  # type: ignore[union-attr]
            d_left[j], d_right[j] = scales[0] * left / k, scales[1] * right / k
            # Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b, Borenstein–Feng (2.2)–(2.4)
            dd[j] = 0.5 * (d_left[j] + d_right[j])
            dth[j] = (d_right[j] - d_left[j]) / robot.effective_wheel_base  # type: ignore[union-attr]
            dt[j] = 0.0
        else:
            dt[j] = seg.duration / k  # type: ignore[union-attr]
            dd[j], dth[j] = seg.speed * dt[j], seg.yaw_rate * dt[j]  # type: ignore[union-attr]
    if model.diff:
        inputs = {"d_left": d_left, "d_right": d_right}
    elif model.steered:
        inputs = {"travel": travel, "steer": steer}
    else:
        inputs = {"yaw_rate": np.divide(dth, dt, out=np.zeros_like(dth), where=dt > 0)}
    return BodySteps(dd, dth, dt, inputs, robot)


def _bias_factor(model: PathModel, steps: BodySteps) -> NDArray[np.float64] | None:
    """K diag(σ) of each step, (S, 2, p), or None without bias noise."""
    if not model.noise.bias:
        return None
    sigma = np.sqrt(model.noise.bias_variances(steps.robot))
    return np.asarray(model.noise.bias_jacobian(steps, 0, len(steps)) * sigma)


def _lateral_factor(model: PathModel, steps: BodySteps) -> NDArray[np.float64] | None:
    """σ of the sideways slip of each step [m], (S,), or None when there is none (no
    position-only model, or zero variance everywhere: the runs then draw as without)."""
    var = model.noise.lateral_variances(steps, 0, len(steps))
    if var is None or not np.any(var > 0):
        return None
    return np.sqrt(var)


def _coefs(model: PathModel, path: Sequence[Segment], counts: Sequence[int],
           systematic: SystematicErrors | None
           ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.float64] | None]:
    """(S, 6) kernel coefficients: the mean body motion of one partition of each segment
    and a factor A (A Aᵀ = Q) of its white noise, as the noise models give them
    (:meth:`odomkit.noise.NoiseSet.input_factor`); the bias factor (S, 2, p) or None; the
    lateral slip's σ (S,) or None."""
    robot = model.robot
    scales = (1.0, 1.0)
    if model.diff:
        sys_err = systematic or SystematicErrors()
        scales = sys_err.wheel_scales()
        robot = DiffDrive(model.robot.effective_wheel_base * sys_err.E_b)  # type: ignore[union-attr]
    elif systematic is not None:
        raise ModelError("systematic errors (E_d, E_b, E_s) apply to the diff model only")
    steps = _partition_steps(model, path, counts, robot, scales)
    factor = model.noise.input_factor(steps, 0, len(steps))
    coefs = np.empty((len(path), 6))
    coefs[:, 0], coefs[:, 3] = steps.dd, steps.dtheta
    coefs[:, 1], coefs[:, 2] = factor[:, 0, 0], factor[:, 0, 1]
    coefs[:, 4], coefs[:, 5] = factor[:, 1, 0], factor[:, 1, 1]
    return coefs, _bias_factor(model, steps), _lateral_factor(model, steps)


def _compass_coefs(model: PathModel, path: Sequence[Segment], k: int, theta0: float
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None,
                              NDArray[np.float64] | None]:
    """(S, 7) compass kernel coefficients ``[dd, σ_d, θ_start, dθ, σ_h, q, m]``.

    The compass is read every T = ``model.compass_period``; segment j lasts n_j readings
    and is cut into q_j = ⌈K/n_j⌉ kernel steps per reading, m_j = q_j·n_j in all, so
    every reading falls on a step boundary whatever K. The steps divide each exact arc
    between two readings into q_j equal arcs (the same arc: K only splits the speed
    noise). Each step: distance dd + σ_d·z0 (the speed noise of T/q_j), nominal heading
    change dθ; σ_h = √(σ_θθ/T) is the σ of each reading's error (one z1 per reading).
    Also the bias factor of each kernel step (S, 2, p), or None, and the lateral slip's σ
    of each kernel step (S,), or None.
    """
    period = model.compass_period
    assert period is not None
    counts = compass_samples(path, period)
    q = np.array([max(1, math.ceil(k / n)) if n else 1 for n in counts], dtype=float)
    dt = period / q
    speed = np.array([seg.speed for seg in path])  # type: ignore[union-attr]
    rate = np.array([seg.yaw_rate for seg in path])  # type: ignore[union-attr]
    steps = BodySteps(speed * dt, rate * dt, dt, {}, model.robot)
    sigma_d = model.noise.input_factor(steps, 0, len(steps))[:, 0, 0]
    turns = rate * period * np.asarray(counts, dtype=float)
    coefs = np.empty((len(path), 7))
    coefs[:, 0], coefs[:, 1], coefs[:, 3] = steps.dd, sigma_d, steps.dtheta
    coefs[:, 2] = theta0 + np.concatenate([[0.0], np.cumsum(turns)[:-1]])
    coefs[:, 4] = math.sqrt(model.var_heading)
    coefs[:, 5], coefs[:, 6] = q, q * np.asarray(counts, dtype=float)
    return coefs, _bias_factor(model, steps), _lateral_factor(model, steps)


def make_plan(path: Sequence[Segment], noise: NoiseArg, wheel_base: float | None, partitions: int,
              pose0: ArrayLike = (0.0, 0.0, 0.0), cov0: ArrayLike | None = None,
              systematic: SystematicErrors | None = None,
              compass_period: float | None = None, robot: Robot | None = None,
              sample_period: float | None = None) -> Plan:
    """Translate path, noise and robot into per-segment kernel coefficients.

    ``robot`` names the vehicle (:func:`odomkit.propagate.paths.path_model`; required for a
    tricycle or car). A ``sample_period`` T [s] cuts each segment into its samples
    instead of ``partitions`` (required with per-sample noise). A compass (``compass_period`` T [s], default
    :data:`~odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`) starts from its first reading:
    the θ row and column of ``cov0`` give way to that reading's error, variance σ_θθ/T,
    independent of the start position (as in ``predict`` and ``track``).
    """
    validate.positive_int(partitions, "partitions")
    path = list(path)
    if len(path) == 0:
        raise ModelError("the path needs at least one segment")
    p0 = validate.pose(pose0)
    k = int(partitions)
    family = NoiseSet.of(noise).family
    if robot is None and family in ("wheel", "classical") and (
            wheel_base is None or not (math.isfinite(wheel_base) and wheel_base > 0)):
        raise ModelError(f"the {family} model needs a positive wheel_base [m], got {wheel_base!r}")
    model = resolve_model(noise, wheel_base, compass_period, robot, sample_period)
    if model.diff:
        for j, seg in enumerate(path):
            if not isinstance(seg, Arc | Straight | Spin):
                raise ModelError(f"segment {j + 1} ({seg!r}) is not a diff-drive segment; "
                                 "expected arc:L,R, straight:D or spin:DTHETA")
    elif not model.steered:
        for j, seg in enumerate(path):
            if not isinstance(seg, KellyArc):
                raise ModelError(f"segment {j + 1} ({seg!r}) is not a speed/yaw-rate segment; "
                                 "expected arc:V,OMEGA,T or straight:V,T")
    if model.steered or model.sample_period is not None:
        check_segments(path, model)  # a steered vehicle's kind; whole samples
    if model.compass_period is not None:
        if systematic is not None:
            raise ModelError("systematic errors (E_d, E_b, E_s) apply to the diff model only")
        coefs, bias, lateral = _compass_coefs(model, path, k, float(p0[2]))
        start = np.zeros((3, 3))
        if cov0 is not None:
            start[:2, :2] = validate.covariance(cov0, "initial covariance", variances=True)[:2, :2]
        start[2, 2] = model.var_heading
        heading = None
        if bias is not None:
            heading = model.noise.bias_heading(model.robot) * np.sqrt(
                model.noise.bias_variances(model.robot))
        return Plan("compass", coefs, max(1, int(np.max(coefs[:, 6]))), p0, _cov_factor(start),
                    bias, heading, lateral)
    # the classical model moves by its own map (rotate, then translate), on any vehicle
    kind = "classical" if model.noise.step_map("exact") == "classical" else "increment"
    if model.sample_period is not None:
        counts = np.array(segment_samples(path, model.sample_period), dtype=np.int64)
        coefs, bias, lateral = _coefs(model, path, counts.tolist(), systematic)
        return Plan(kind, coefs, max(1, int(counts.max())), p0, _cov_factor(cov0), bias,
                    lateral=lateral, counts=counts)
    coefs, bias, lateral = _coefs(model, path, [k] * len(path), systematic)
    return Plan(kind, coefs, k, p0, _cov_factor(cov0), bias, lateral=lateral)
