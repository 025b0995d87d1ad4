"""Exact-model calibration: wheel scales, wheel base (or a tricycle's or car's scale,
steering offset and wheel base; a unicycle's speed scale, yaw-rate bias and yaw-rate scale;
a gyro robot's metres per tick, gyro bias and gyro scale) by nonlinear least squares on the
exact kinematics.

UMBmark (Borenstein–Feng section IV) linearises the square path (``L sin γ ≈ Lγ``) and
treats turns and straight legs as if they were driven perfectly apart from one error
each. Here the logs are re-integrated with candidate parameters by the same exact-arc
dead reckoning odomkit uses everywhere (:func:`odomkit.integrate.dead_reckon`), and the
parameters are chosen so the integrated poses match the ground truth:

* ``source="endpoints"``: only the final pose of each run is compared (what a UMBmark
  experiment measures);
* ``source="trajectory"``: every logged pose is compared (needs ground truth at every
  row, e.g. a motion-capture system). This also observes the overall scale E_s.

Why the overall scale is unobservable from closed-path endpoints: multiplying both wheel
scales *and* the wheel base by the same factor s leaves every Δθ unchanged and multiplies
every Δd by s, so the whole odometry track is scaled by s about the start pose. The end
of a closed square lies near the start, so the end pose hardly moves. :func:`calibrate_exact`
measures this (how far the compared poses lie from the start relative to the distance
travelled to reach them) and, when it is below ``SCALE_OBSERVABLE_BELOW``, keeps the mean
wheel scale fixed, the constraint UMBmark uses implicitly (Borenstein–Feng eq. 4.28: the
average diameter D_a is unchanged). The wheel base then absorbs any E_s: headings come out
right, distances stay scaled.

Standard errors are ``σ̂² (JᵀJ)⁻¹`` with ``σ̂² = |r|²/(m − p)``, J the (analytic)
Jacobian of the weighted residuals at the solution. This assumes the residuals are
independent with equal variance after weighting. It holds for endpoint residuals
whitened by a noise model (``noise=``); for unweighted endpoints it is approximate
(x, y and θ errors of one run are correlated); for trajectories it is optimistic,
because the errors along one track are a random walk, strongly correlated from row to
row — use :func:`jackknife_runs` there.

The re-integration with sensitivities, the parameter-to-body-step maps of each robot and
the weighted residuals with their Jacobian are in :mod:`odomkit.calibrate.residuals`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from odomkit import validate
from odomkit.calibrate.residuals import (
    CalibratedRobot,
    GyroCalibrationModel,
    ResidualProblem,
    UnicycleCalibrationModel,
    calibration_model,
    endpoint_whitening,
)
from odomkit.errors import InputError, ModelError
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import DiffDrive

__all__ = ["SCALE_OBSERVABLE_BELOW", "calibrate_exact", "ExactCalibration", "jackknife_runs", "Source"]

Source = Literal["endpoints", "trajectory"]

#: Below this relative sensitivity the overall scale counts as unobservable.
SCALE_OBSERVABLE_BELOW = 0.05


@dataclass(frozen=True)
class ExactCalibration:
    """Result of :func:`calibrate_exact`.

    Parameters
    ----------
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        The input robot with the fitted corrections in place.
    names : tuple of str
        Parameter names: ``c_left, c_right, c_wheel_base`` (diff),
        ``c_scale, steering_offset, wheel_to_axle`` (tricycle; m for ``wheel_to_axle``, rad for
        the offset), ``c_scale, steering_offset, wheel_base`` (car),
        ``c_scale, yaw_rate_bias, yaw_rate_scale`` (unicycle; rad/s for the bias) or
        ``m_per_tick, gyro_bias, gyro_scale`` (gyro; m, rad/s).
    values, std_errors : ndarray, shape (3,)
        Estimates and standard errors ``sqrt(diag(cov))``.
    cov, corr : ndarray, shape (3, 3)
        Parameter covariance ``σ̂²(JᵀJ)⁻¹`` and correlation matrix. With a fixed scale,
        c_left and c_right are perfectly anti-correlated (corr −1) and their sum has zero
        variance.
    residual_variance : float
        σ̂² of the weighted residuals (m² unless whitened, then dimensionless).
    n_residuals, n_runs : int
    source : {"endpoints", "trajectory", "positions"}
        ``positions``: :func:`odomkit.calibrate.positions.calibrate_positions` (truth
        positions on their own clock, start poses fitted).
    scale_fixed : bool
        True when the mean scale (diff) or speed scale (``c_scale``, ``m_per_tick``) was held
        at its input value (unobservable or asked).
    scale_sensitivity : float
        Relative sensitivity of the residuals to the overall scale at the start (0 = none).
    notes : tuple of str
        Human-readable remarks (why the scale was fixed, convergence).
    time_offset, time_offset_std_error : float or None
        ``positions`` with ``fit_time_offset``: the truth's clock offset δ [s] (a fix
        stamped t is the pose at log time t − δ) and its standard error; None otherwise.
    """

    robot: CalibratedRobot
    names: tuple[str, ...]
    values: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    cov: NDArray[np.float64]
    corr: NDArray[np.float64]
    residual_variance: float
    n_residuals: int
    n_runs: int
    source: str
    scale_fixed: bool
    scale_sensitivity: float
    notes: tuple[str, ...] = ()
    time_offset: float | None = None
    time_offset_std_error: float | None = None

    @property
    def E_d(self) -> float:
        """Borenstein–Feng eq. (2.3), D_R/D_L (diff only): ratio of the corrected metres per tick."""
        r = self._diff()
        return r.scale_right / r.scale_left

    @property
    def E_b(self) -> float:
        """Borenstein–Feng eq. (2.4), b_actual/b_nominal (diff only)."""
        return self._diff().c_wheel_base

    @property
    def E_s(self) -> float:
        """Scaling error (Borenstein–Feng section II-B): mean actual over mean nominal wheel
        diameter, (scale_left + scale_right)/(m_per_tick_left + m_per_tick_right)."""
        r = self._diff()
        return (r.scale_left + r.scale_right) / (r.m_per_tick_left + r.m_per_tick_right)

    def _diff(self) -> DiffDrive:
        if not isinstance(self.robot, DiffDrive):
            raise ModelError("E_d, E_b, E_s are defined for differential-drive robots only")
        return self.robot

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for JSON output."""
        out: dict[str, Any] = {
            "source": self.source,
            "parameters": {n: float(v) for n, v in zip(self.names, self.values, strict=True)},
            "std_errors": {n: float(v) for n, v in zip(self.names, self.std_errors, strict=True)},
            "corr": self.corr.tolist(),
            "residual_rms": float(np.sqrt(self.residual_variance)),
            "n_residuals": self.n_residuals,
            "n_runs": self.n_runs,
            "scale_fixed": self.scale_fixed,
            "scale_sensitivity": self.scale_sensitivity,
            "notes": list(self.notes),
        }
        if self.time_offset is not None:
            out["truth_time_offset"] = {"value": self.time_offset, "std_error": self.time_offset_std_error}
        if isinstance(self.robot, DiffDrive):
            out.update(E_d=self.E_d, E_b=self.E_b, E_s=self.E_s,
                       wheel_base=self.robot.effective_wheel_base)
        return out


def _hold_fixed(offset: NDArray[np.float64], T: NDArray[np.float64], held: Sequence[int],
                p0: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Restrict the map p = offset + T q, shapes (P,), (P, Q), to p[held] = p0[held].

    The constraint T[held] q = p0[held] − offset[held] has the solutions q = q* + N z with
    q* its least-squares solution and N an orthonormal basis of the null space of T[held];
    the new map is p = (offset + T q*) + (T N) z.
    """
    idx = np.asarray(held, dtype=np.intp)
    A = T[idx]
    q_star = np.linalg.lstsq(A, p0[idx] - offset[idx], rcond=None)[0]
    _, sv, vt = np.linalg.svd(A)
    rank = int(np.count_nonzero(sv > 1e-12 * max(1.0, float(sv.max(initial=0.0)))))
    N = vt[rank:].T
    new_offset = offset + T @ q_star
    new_offset[idx] = p0[idx]  # exactly, not to round-off
    T_new = T @ N
    T_new[idx] = 0.0
    return new_offset, T_new


def _check_runs(runs: Sequence[OdometryLog], source: str) -> None:
    if source not in ("endpoints", "trajectory"):
        raise ModelError(f"source must be 'endpoints' or 'trajectory', got {source!r}")
    if len(runs) < 1:
        raise InputError("calibration needs at least one run with ground truth")
    for log in runs:
        if log.ground_truth is None:
            raise InputError("run has no ground truth; calibration compares against it",
                             source=log.source)
        if len(log) < 2:
            raise InputError("run has fewer than two rows", source=log.source)
    if source == "endpoints":
        if len(runs) < 2:
            raise InputError(f"an endpoint calibration needs at least two runs, got {len(runs)}")
        turns = [float(log.ground_truth[-1, 2] - log.ground_truth[0, 2]) for log in runs]  # type: ignore[index]
        loops = [t for t in turns if abs(t) > np.pi]
        if len(loops) == len(turns) and (all(t > 0 for t in loops) or all(t < 0 for t in loops)):
            raise InputError(
                "all runs are closed loops turning the same way; their endpoints cannot separate "
                "the wheel-diameter and wheel-base errors (Borenstein–Feng section III-A): "
                "add runs in the other direction"
            )


def calibrate_exact(
    runs: Sequence[OdometryLog],
    robot: CalibratedRobot,
    source: Source = "endpoints",
    *,
    heading_weight: float | None = 0.0,
    fix_scale: bool | None = None,
    noise: NoiseArg | None = None,
    every: int = 1,
    method: Method = "exact",
    steering_cubic: bool = False,
) -> ExactCalibration:
    """Fit a robot's systematic parameters to ground truth on the exact kinematics.

    Parameters
    ----------
    runs : sequence of OdometryLog
        Logs with ``ground_truth`` (N, 3); diff robots need ``ticks_left/right`` (or
        ``dist_*``), tricycles and cars ``ticks`` (or ``dist``/``speed``) and ``steer``,
        unicycles ``speed`` (or ``dist``) and ``yaw_rate``, gyro robots ``ticks`` (or
        ``dist``/``speed``) and ``yaw_rate``. Each run is integrated from its first
        ground-truth pose.
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        Nominal parameters; its current corrections are the starting point. Fitted: diff
        (c_left, c_right, c_wheel_base), tricycle (c_scale, steering_offset [rad],
        wheel_to_axle [m]), car (c_scale, steering_offset [rad], wheel_base [m]), unicycle
        (c_scale, yaw_rate_bias [rad/s], yaw_rate_scale), gyro (m_per_tick [m], gyro_bias
        [rad/s], gyro_scale). A parameter the runs' channels do not depend on (a gyro
        robot's m_per_tick without a ``ticks`` channel) is held at its value, with a note.
    source : {"endpoints", "trajectory"}
        Compare only each run's final pose, or every row's pose.
    heading_weight : float or None
        Length [m/rad] that turns a heading residual into a position-like one; None means
        a quarter of the mean path length of the runs (the side of a square: a heading
        error δθ at the end counts like a lateral miss of side·δθ). The default 0 fits
        positions only, like UMBmark and E_max,syst; on the OptiOdom squares adding the
        heading made the calibration worse in and out of sample (docs/results/real-data.md).
    fix_scale : bool, optional
        Hold the mean scale (diff: (c_left + c_right)/2; tricycle, car, unicycle: c_scale;
        gyro: m_per_tick) at its input value. Default: automatically, when the compared
        poses lie closer to the start than ``SCALE_OBSERVABLE_BELOW`` times the distance
        travelled (closed paths, endpoints).
    noise : WheelNoise, optional
        Diff endpoints only: whiten each run's end residual by the end-pose covariance that
        this per-wheel noise predicts (Chong–Kleeman eq. 23), making the fit a generalised
        least-squares fit whose standard errors are valid.
    every : int
        Trajectory source: use every ``every``-th row.
    method : {"exact", "midpoint", "euler"}
        Integration method, as in dead reckoning.
    steering_cubic : bool
        A car's ``steering_cubic`` [rad⁻²] is fitted too, as a fourth parameter.

    Returns
    -------
    ExactCalibration

    Examples
    --------
    Noise-free straight-line-and-turn runs of a robot whose right wheel is 1 % large:

    >>> from odomkit.log import OdometryLog
    >>> from odomkit.integrate import dead_reckon
    >>> from odomkit.kinematics import diff_body_steps
    >>> nominal = DiffDrive(wheel_base=0.5)
    >>> def run(left, right):
    ...     a, r = np.full(200, left / 200), np.full(200, right / 200)
    ...     gt = dead_reckon(*diff_body_steps(a, 1.01 * r, 0.5))
    ...     ch = {"dist_left": np.r_[0, a], "dist_right": np.r_[0, r]}
    ...     return OdometryLog(np.arange(201.0), ch, gt)
    >>> cal = calibrate_exact([run(2, 2.5), run(2.5, 2)], nominal, "trajectory")
    >>> [round(float(v), 6) for v in cal.values]
    [1.0, 1.01, 1.0]
    """
    _check_runs(runs, source)
    every = validate.positive_int(every, "every")
    model = calibration_model(robot, runs, steering_cubic=steering_cubic)
    if heading_weight is None:
        lengths = [float(np.sum(np.abs(model.steps(model.p0, i)[0]))) for i in range(len(runs))]
        heading_weight = 0.25 * float(np.mean(lengths))
    heading_weight = validate.non_negative(heading_weight, "heading_weight", unit="m/rad")
    whiten = None
    if noise is not None:
        whiten = endpoint_whitening(model, runs, source, noise, method)
    prob = ResidualProblem(model, runs, source, heading_weight, every, whiten, method)
    p0 = model.p0.copy()
    scale_index = [k for k, positive in enumerate(model.positive) if positive]
    sens = prob.scale_sensitivity(p0)
    notes: list[str] = []
    held = [k for k, name in enumerate(model.names) if name in model.unobservable]
    for k in held:
        notes.append(f"{model.names[k]} held at {p0[k]:.6g}: {model.unobservable[model.names[k]]}")
    if fix_scale is None:
        fix_scale = sens < SCALE_OBSERVABLE_BELOW
        if fix_scale and 0 not in held:
            unobservable = (f"overall scale unobservable (relative sensitivity {sens:.3g} < "
                            f"{SCALE_OBSERVABLE_BELOW}): ")
            if isinstance(model, UnicycleCalibrationModel | GyroCalibrationModel):
                # Its speed scale stretches the track about the start and leaves every Δθ alone.
                notes.append(unobservable + f"speed scale {model.names[0]} held fixed; the heading "
                             "parameters are unaffected, distances keep any scale error")
            else:
                notes.append(unobservable + "mean wheel scale held fixed as in UMBmark; the wheel "
                             "base absorbs any scale error E_s")
    if fix_scale:
        prob.offset, prob.T = model.fixed_scale_map(p0)
    if held:
        prob.offset, prob.T = _hold_fixed(prob.offset, prob.T, held, p0)
    if fix_scale or held:
        q0 = np.asarray(np.linalg.lstsq(prob.T, p0 - prob.offset, rcond=None)[0], dtype=np.float64)
    else:
        q0 = p0.copy()
    r0 = prob.residuals(q0)
    n_res = r0.size
    if not (np.all(np.isfinite(r0)) and np.all(np.isfinite(prob.jacobian(q0)))):
        raise ModelError("the pose residuals at the robot's starting parameters are not finite: "
                         "the robot file's values overflow the dead reckoning (check their units)")
    if n_res <= q0.size:
        raise InputError(
            f"{n_res} residuals cannot determine {q0.size} parameters: give more runs "
            "(UMBmark endpoints need runs in both directions)"
        )
    sol = least_squares(prob.residuals, q0, jac=prob.jacobian, method="lm", x_scale="jac",
                        xtol=1e-13, ftol=1e-13, gtol=1e-13, max_nfev=200)
    if not sol.success:
        notes.append(f"least_squares: {sol.message}")
    J = sol.jac
    if not (np.all(np.isfinite(sol.x)) and np.all(np.isfinite(J)) and np.isfinite(sol.cost)):
        raise ModelError("the calibration diverged to non-finite parameters or residuals; check the "
                         "channel assignment (left/right) and the units of the robot file")
    dof = n_res - q0.size
    var_res = float(2.0 * sol.cost / dof)
    cov_q = var_res * np.linalg.pinv(J.T @ J)
    cov = prob.T @ cov_q @ prob.T.T
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, np.where(std > 0, 1.0, 0.0))
    p = prob.full(sol.x)
    if np.any(p[scale_index] <= 0):
        raise ModelError(f"calibration diverged to non-positive parameters {p.tolist()}; "
                         "check the channel assignment (left/right) and the robot file")
    return ExactCalibration(
        robot=model.make_robot(p), names=model.names, values=p, std_errors=std, cov=cov,
        corr=corr, residual_variance=var_res, n_residuals=n_res, n_runs=len(runs),
        source=source, scale_fixed=bool(fix_scale) or 0 in held, scale_sensitivity=sens,
        notes=tuple(notes),
    )


def jackknife_runs(
    runs: Sequence[OdometryLog], robot: CalibratedRobot, source: Source = "trajectory",
    **kwargs: Any,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Delete-one-run jackknife standard errors of :func:`calibrate_exact`'s parameters.

    Each run's residuals are correlated along the track but runs are independent, so
    leaving out one run at a time gives honest standard errors where σ̂²(JᵀJ)⁻¹ does not
    (trajectories). Needs at least 3 runs.

    Returns
    -------
    values : ndarray, shape (3,)
        The all-runs estimate.
    std_errors : ndarray, shape (3,)
        ``sqrt((n−1)/n · Σ (θ_i − θ̄)²)`` (Efron's jackknife).
    """
    n = len(runs)
    if n < 3:
        raise InputError(f"jackknife needs at least 3 runs, got {n}")
    full = calibrate_exact(runs, robot, source, **kwargs).values
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loo = np.array([calibrate_exact([r for j, r in enumerate(runs) if j != i], robot, source,
                                        **kwargs).values for i in range(n)])
    return full, np.sqrt((n - 1) / n * np.sum((loo - loo.mean(axis=0)) ** 2, axis=0))
