"""What one Monte Carlo run does: path, noise and robot -> per-partition coefficients.

Every partition's body motion is an affine map of two standard normals z0, z1
(see :mod:`odomkit.simulate._kernels`), so all noise models share one kernel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc, Segment, Spin, Straight
from odomkit.robot import SystematicErrors


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
    cov = np.asarray(cov0, dtype=float)
    if cov.shape == (3,):
        cov = np.diag(cov)
    if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
        raise ModelError(f"initial covariance must be 3 variances or a 3x3 matrix, got {cov0!r}")
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-15):
        raise ModelError("initial covariance must be symmetric")
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    # eigenvalues a few ulps below zero are rounding of a PSD matrix, not negative variance
    tol = 1e-12 * max(1.0, float(np.max(np.abs(w))))
    if np.min(w) < -tol:
        raise ModelError(f"initial covariance must be positive semi-definite; eigenvalues {w}")
    # directions with rounding-level variance are the null space: sample nothing there
    w = np.where(w > 1e-14 * max(float(np.max(w)), 0.0), w, 0.0)
    return np.asarray(v * np.sqrt(w))


def resolve_model(noise: Any) -> tuple[str, tuple[Any, ...]]:
    """The odometry model a noise argument selects, as in ``predict``.

    ``WheelNoise`` -> ``"wheel"``, ``ClassicalNoise`` -> ``"classical"`` (both
    differential drive), ``(SpeedNoise, GyroNoise)`` -> ``"gyro"``,
    ``(SpeedNoise, CompassNoise)`` -> ``"compass"`` (SpeedNoise optional, any order).

    >>> resolve_model(WheelNoise(0.001, 0.001))[0]
    'wheel'
    """
    parts = tuple(p for p in (noise if isinstance(noise, list | tuple) else (noise,))
                  if p is not None)
    kinds = [type(p) for p in parts]
    if kinds == [WheelNoise]:
        return "wheel", parts
    if kinds == [ClassicalNoise]:
        return "classical", parts
    if len(set(kinds)) == len(kinds):
        speed = next((p for p in parts if isinstance(p, SpeedNoise)), SpeedNoise(0.0))
        if set(kinds) in ({GyroNoise}, {SpeedNoise, GyroNoise}):
            return "gyro", (speed, next(p for p in parts if isinstance(p, GyroNoise)))
        if set(kinds) in ({CompassNoise}, {SpeedNoise, CompassNoise}):
            return "compass", (speed, next(p for p in parts if isinstance(p, CompassNoise)))
    names = ", ".join(k.__name__ for k in kinds) or "nothing"
    raise ModelError(f"noise ({names}) is not a simulation model; expected WheelNoise, "
                     "ClassicalNoise, (SpeedNoise, GyroNoise) or (SpeedNoise, CompassNoise)")


def _diff_coefs(model: Any, wheel_base: float, path: Sequence[Segment], k: int,
                systematic: SystematicErrors | None) -> NDArray[np.float64]:
    sys_err = systematic or SystematicErrors()
    scale_left, scale_right = sys_err.wheel_scales()
    b = wheel_base * sys_err.E_b
    coefs = np.empty((len(path), 6))
    for j, seg in enumerate(path):
        if not isinstance(seg, Arc | Straight | Spin):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a diff-drive segment; "
                             "expected arc:L,R, straight:D or spin:DTHETA")
        # commanded travels use the nominal wheel base (a spin is commanded with it)
        left, right = seg.wheel_travel(wheel_base)
        left, right = scale_left * left / k, scale_right * right / k
        if isinstance(model, WheelNoise):
            # Chong–Kleeman eq. (4): each partition's wheel travel has variance k²·|d|
            sigma_l = model.k_left * math.sqrt(abs(left))
            sigma_r = model.k_right * math.sqrt(abs(right))
            # Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b, Borenstein–Feng (2.2)–(2.4)
            coefs[j] = (0.5 * (left + right), 0.5 * sigma_l, 0.5 * sigma_r,
                        (right - left) / b, -sigma_l / b, sigma_r / b)
        else:
            # Chong–Kleeman eq. (1)–(3): fixed σ per step, whatever the step's length
            coefs[j] = (0.5 * (left + right), model.sigma_distance, 0.0,
                        (right - left) / b, 0.0, model.sigma_angle)
    return coefs


def _kelly_coefs(model: str, parts: tuple[Any, ...], path: Sequence[Segment], k: int,
                 theta0: float) -> NDArray[np.float64]:
    speed_noise, heading_noise = parts
    coefs = np.empty((len(path), 6))
    theta_start = theta0
    for j, seg in enumerate(path):
        if not isinstance(seg, KellyArc):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a speed/yaw-rate segment; "
                             "expected arc:V,OMEGA,T or straight:V,T")
        dt = seg.duration / k
        dd0, dth0 = seg.speed * dt, seg.yaw_rate * dt
        # Kelly Table 1: σ_vv = α_ss·|V|, so a partition's distance has variance α_ss·|Δs|
        sigma_d = math.sqrt(speed_noise.alpha_ss * abs(dd0))
        if model == "gyro":
            # Kelly Table 1: σ_ωω = σ_gg, the integrated heading gains variance σ_gg·Δt
            coefs[j] = (dd0, sigma_d, 0.0, dth0, 0.0, math.sqrt(heading_noise.psd_gyro * dt))
        else:
            # white compass error of density σ_θθ sampled every Δt: variance σ_θθ/Δt
            # (noise.CompassNoise)
            sigma_h = math.sqrt(heading_noise.psd_compass / dt) if dt > 0 else 0.0
            coefs[j] = (dd0, sigma_d, theta_start + 0.5 * dth0, dth0, sigma_h, 0.0)
        theta_start += seg.yaw_rate * seg.duration
    return coefs


def make_plan(path: Sequence[Segment], noise: Any, wheel_base: float | None, partitions: int,
              pose0: ArrayLike = (0.0, 0.0, 0.0), cov0: ArrayLike | None = None,
              systematic: SystematicErrors | None = None) -> Plan:
    """Translate path, noise and robot into per-segment kernel coefficients."""
    if not isinstance(partitions, int | np.integer) or partitions < 1:
        raise ModelError(f"partitions must be a positive integer, got {partitions!r}")
    path = list(path)
    if len(path) == 0:
        raise ModelError("the path needs at least one segment")
    p0 = np.asarray(pose0, dtype=float).reshape(-1)
    if p0.shape != (3,) or not np.all(np.isfinite(p0)):
        raise ModelError(f"initial pose must be three finite numbers x, y, theta; got {pose0!r}")
    k = int(partitions)
    model, parts = resolve_model(noise)
    if model in ("wheel", "classical"):
        if wheel_base is None or not (math.isfinite(wheel_base) and wheel_base > 0):
            raise ModelError(f"the {model} model needs a positive wheel_base [m], "
                             f"got {wheel_base!r}")
        coefs = _diff_coefs(parts[0], float(wheel_base), path, k, systematic)
        kind = "classical" if model == "classical" else "increment"
    else:
        if systematic is not None:
            raise ModelError("systematic errors (E_d, E_b, E_s) apply to the diff model only")
        coefs = _kelly_coefs(model, parts, path, k, float(p0[2]))
        kind = "increment" if model == "gyro" else "compass"
    return Plan(kind, coefs, k, p0, _cov_factor(cov0))
