"""What one Monte Carlo run does: path, noise and robot -> per-partition coefficients.

Every partition's body motion is an affine map of two standard normals z0, z1
(see :mod:`odomkit.simulate._kernels`), so all noise models share one kernel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps
from odomkit.noise import NoiseSet
from odomkit.path import Arc, KellyArc, Segment, Spin, Straight
from odomkit.propagate.paths import PathModel, path_model
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import DiffDrive, Robot, SystematicErrors

__all__ = ["Plan", "resolve_model", "make_plan"]


@dataclass(frozen=True)
class Plan:
    """What one run does, in kernel terms (picklable, sent to Dask workers).

    ``coefs[j]`` maps two standard normals to the body motion of one partition of segment
    j (see :mod:`odomkit.simulate._kernels`); ``kind`` is ``"increment"`` (exact arc),
    ``"classical"`` (rotate, then translate) or ``"compass"``.
    """

    kind: str
    coefs: NDArray[np.float64]  # (S, 6)
    partitions: int
    pose0: NDArray[np.float64]  # (3,)
    factor0: NDArray[np.float64]  # (3, 3): initial pose = pose0 + factor0 @ z


def _cov_factor(cov0: ArrayLike | None) -> NDArray[np.float64]:
    """A with A·Aᵀ = cov0, from the eigen-decomposition so a singular PSD cov0 works."""
    if cov0 is None:
        return np.zeros((3, 3))
    cov = validate.covariance(cov0, "initial covariance", variances=True)
    w, v = np.linalg.eigh(cov)
    # directions with rounding-level variance are the null space: sample nothing there
    w = np.where(w > 1e-14 * max(float(np.max(w)), 0.0), w, 0.0)
    return np.asarray(v * np.sqrt(w))


def resolve_model(noise: NoiseArg, wheel_base: float | None = 1.0) -> PathModel:
    """The odometry model a noise argument selects, as in ``predict``
    (:func:`odomkit.propagate.paths.path_model`).

    >>> from odomkit.noise import WheelNoise
    >>> resolve_model(WheelNoise(0.001, 0.001)).family
    'wheel'
    """
    return path_model(noise, wheel_base, purpose="simulation")


def _partition_steps(model: PathModel, path: Sequence[Segment], k: int, robot: Robot,
                     scales: tuple[float, float]) -> BodySteps:
    """One partition (1/k) of every segment, as the steps the noise models are asked
    about: a differential drive's commanded wheel travels (nominal wheel base) scaled by
    the true wheel sizes, or Kelly's speed·Δt and yaw rate·Δt."""
    dd, dth, dt, d_left, d_right = (np.empty(len(path)) for _ in range(5))
    for j, seg in enumerate(path):
        if model.diff:
            left, right = seg.wheel_travel(model.robot.wheel_base)  # type: ignore[union-attr]
            d_left[j], d_right[j] = scales[0] * left / k, scales[1] * right / k
            # Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b, Borenstein–Feng (2.2)–(2.4)
            dd[j] = 0.5 * (d_left[j] + d_right[j])
            dth[j] = (d_right[j] - d_left[j]) / robot.effective_wheel_base  # type: ignore[union-attr]
            dt[j] = 0.0
        else:
            dt[j] = seg.duration / k  # type: ignore[union-attr]
            dd[j], dth[j] = seg.speed * dt[j], seg.yaw_rate * dt[j]  # type: ignore[union-attr]
    inputs = {"d_left": d_left, "d_right": d_right} if model.diff else {}
    return BodySteps(dd, dth, dt, inputs, robot)


def _coefs(model: PathModel, path: Sequence[Segment], k: int,
           systematic: SystematicErrors | None, theta0: float) -> NDArray[np.float64]:
    """(S, 6) kernel coefficients: the mean body motion of one partition of each segment
    and a factor A (A Aᵀ = Q) of its white noise, as the noise models give them
    (:meth:`odomkit.noise.NoiseSet.input_factor`)."""
    robot = model.robot
    scales = (1.0, 1.0)
    if model.diff:
        sys_err = systematic or SystematicErrors()
        scales = sys_err.wheel_scales()
        robot = DiffDrive(model.robot.wheel_base * sys_err.E_b)  # type: ignore[union-attr]
    elif systematic is not None:
        raise ModelError("systematic errors (E_d, E_b, E_s) apply to the diff model only")
    steps = _partition_steps(model, path, k, robot, scales)
    factor = model.noise.input_factor(steps, 0, len(steps))
    coefs = np.empty((len(path), 6))
    coefs[:, 0], coefs[:, 3] = steps.dd, steps.dtheta
    coefs[:, 1], coefs[:, 2] = factor[:, 0, 0], factor[:, 0, 1]
    coefs[:, 4], coefs[:, 5] = factor[:, 1, 0], factor[:, 1, 1]
    if robot.measures_heading:
        # Direct heading: slot 2 holds the nominal heading at the partition's middle and
        # slot 4 the σ of each measured heading (white compass error of density psd
        # sampled every Δt: variance psd/Δt, noise.CompassNoise).
        theta_start = theta0
        for j, seg in enumerate(path):
            coefs[j, 2] = theta_start + 0.5 * steps.dtheta[j]
            one = BodySteps(steps.dd[j:j + 1], steps.dtheta[j:j + 1], steps.dt[j:j + 1], {}, robot)
            var_h = model.noise.heading_variances(one) if steps.dt[j] > 0 else None
            coefs[j, 4] = math.sqrt(var_h[0]) if var_h is not None else 0.0
            coefs[j, 5] = 0.0
            theta_start += seg.yaw_rate * seg.duration  # type: ignore[union-attr]
    return coefs


def make_plan(path: Sequence[Segment], noise: NoiseArg, wheel_base: float | None, partitions: int,
              pose0: ArrayLike = (0.0, 0.0, 0.0), cov0: ArrayLike | None = None,
              systematic: SystematicErrors | None = None) -> Plan:
    """Translate path, noise and robot into per-segment kernel coefficients."""
    validate.positive_int(partitions, "partitions")
    path = list(path)
    if len(path) == 0:
        raise ModelError("the path needs at least one segment")
    p0 = validate.pose(pose0)
    k = int(partitions)
    family = NoiseSet.of(noise).family
    if family in ("wheel", "classical") and (
            wheel_base is None or not (math.isfinite(wheel_base) and wheel_base > 0)):
        raise ModelError(f"the {family} model needs a positive wheel_base [m], got {wheel_base!r}")
    model = resolve_model(noise, wheel_base)
    for j, seg in enumerate(path):
        if model.diff and not isinstance(seg, Arc | Straight | Spin):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a diff-drive segment; "
                             "expected arc:L,R, straight:D or spin:DTHETA")
        if not model.diff and not isinstance(seg, KellyArc):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a speed/yaw-rate segment; "
                             "expected arc:V,OMEGA,T or straight:V,T")
    coefs = _coefs(model, path, k, systematic, float(p0[2]))
    kind = {"classical": "classical", "compass": "compass"}.get(model.family, "increment")
    return Plan(kind, coefs, k, p0, _cov_factor(cov0))
