"""Calibration from truth positions on their own clock (GPS-like truth, no heading).

:func:`odomkit.calibrate.exact.calibrate_exact` compares each run against ground truth at
every log row and starts each run from its first truth pose. A position-only truth with
metres of noise (GPS) and gaps gives neither: no start heading, a start position off by
its noise, and rows without truth. Here:

* the odometry is compared at the truth's own times: the dead-reckoned positions are
  interpolated there (linearly between the two log rows around each fix; the log is
  the denser clock), so each fix is one residual with its own noise, a gap in the truth
  is simply no residual, and fixes outside the log's span are left out and counted;
* each run's start pose (x₀, y₀, θ₀) is fitted with the robot's parameters (three
  nuisance parameters per run), so neither the start position nor the start heading is
  taken from a single noisy fix;
* the residuals are the position differences odometry − truth; where their noise is the
  truth's, independent from fix to fix, σ̂²(JᵀJ)⁻¹ is an honest covariance (its block of
  the robot's parameters, the start poses marginalised). Where the odometry drifts by
  more than the truth's noise over a run, the residuals are correlated and those
  standard errors optimistic: a warning says so when the residual RMS exceeds the
  truth's stated σ;
* the fit grows its horizon: a fit from nominal values over a whole long run falls into
  local minima (a steering offset bends the whole dead-reckoned track into a spiral that
  a rotation of the start cannot undo), so the first stage fits the start pose alone
  (an SE(2) alignment, Umeyama 1991, closed form) over a short prefix of each run, and
  each later stage refits everything over a prefix twice as long, starting from the
  previous stage's solution, until the whole run is used;
* optionally (``fit_time_offset``) the truth's clock offset δ is fitted too, one for all
  runs: a fix stamped t is compared with the odometry at log time t − δ. A GPS's latency
  or a commanded velocity's lag behind the motion makes the truth look late by a constant;
  left out, it reads as an along-track error proportional to speed. Its Jacobian column
  is −(the odometry's velocity at t − δ), the slope of the log segment the fix falls in
  (the residual is piecewise linear in δ). Fixes within :data:`MAX_TIME_OFFSET` of either
  end of the log are then left out, so the same fixes are compared at every δ.

The parameter-to-body-step maps are :mod:`odomkit.calibrate.residuals`' (diff, tricycle,
car) and the integration with sensitivities its
:func:`~odomkit.calibrate.residuals.integrate_with_sensitivity`.
"""

from __future__ import annotations

import warnings
from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from odomkit import validate
from odomkit.calibrate.exact import ExactCalibration, between_runs, between_runs_warning, warn_if_drifting
from odomkit.calibrate.residuals import (
    CALIBRATED_ROBOTS,
    CalibratedRobot,
    CalibrationModel,
    CarCalibrationModel,
    calibration_model,
    integrate_with_sensitivity,
)
from odomkit.errors import InputError, ModelError
from odomkit.evaluate import umeyama_se2
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.truth import Truth

__all__ = ["MAX_STEERING_OFFSET", "MAX_TIME_OFFSET", "MIN_FIRST_FIXES", "calibrate_positions",
           "compared_fixes", "runs_disagree", "scale_range"]

#: Fewest truth fixes in the first (shortest) stage of the growing horizon.
MIN_FIRST_FIXES = 30
#: The largest truth clock offset [s] the calibration fits: a GPS's latency or a
#: command's lag is a fraction of a second; beyond this the clocks differ, and the truth
#: file's times need shifting (``--truth-time-offset``).
MAX_TIME_OFFSET = 2.0


@dataclass(frozen=True)
class _Run:
    """The truth fixes of one run inside its log's span (less ``margin`` [s] at each end)."""

    log_t: NDArray[np.float64]  # (N,) the log's times [s]
    xy: NDArray[np.float64]  # (n, 2) truth positions [m]
    t: NDArray[np.float64]  # (n,) fix times [s]
    outside: int  # fixes outside the log's span
    near_ends: int = 0  # fixes inside it but within the margin of its ends
    margin: float = 0.0  # [s]

    def at(self, delta: float, keep: NDArray[np.bool_]) -> _FixRows:
        """Where the kept fixes fall on the log's clock at offset ``delta`` (each at its
        stamp − ``delta``)."""
        t, tau = self.log_t, self.t[keep] - delta
        row = np.clip(np.searchsorted(t, tau, side="right") - 1, 0, t.size - 2)
        span = t[row + 1] - t[row]
        w = np.divide(tau - t[row], span, out=np.zeros_like(tau), where=span > 0)
        return _FixRows(row.astype(np.intp), w, span)


@dataclass(frozen=True)
class _FixRows:
    """Fix j lies between log rows row[j] and row[j] + 1, a fraction w[j] of the way;
    span[j] [s] is that segment's length (0 where two rows share a time)."""

    row: NDArray[np.intp]  # (n,)
    w: NDArray[np.float64]  # (n,)
    span: NDArray[np.float64]  # (n,)

    def interpolate(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per-row ``values`` (N, ...) interpolated linearly at the fixes."""
        w = self.w.reshape(self.w.shape + (1,) * (values.ndim - 1))
        return (1.0 - w) * values[self.row] + w * values[self.row + 1]

    def rate(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """d/dt of that interpolation of ``values`` (N, 2) at the fixes (zero inside a
        segment of zero length)."""
        step = values[self.row + 1] - values[self.row]
        inverse = np.divide(1.0, self.span, out=np.zeros_like(self.span), where=self.span > 0)
        return step * inverse[:, None]


def compared_fixes(log_t: ArrayLike, fix_t: ArrayLike, margin: float = 0.0) -> NDArray[np.bool_]:
    """Which fixes (stamped ``fix_t``, shape (K,), on their own clock) a calibration compares
    with a log of times ``log_t`` [s]: those inside its span, ``margin`` [s] in from either
    end (:data:`MAX_TIME_OFFSET` where the clock offset is fitted, so that every offset tried
    compares the same fixes)."""
    t = np.asarray(log_t, dtype=float)
    stamps = np.asarray(fix_t, dtype=float)
    return (stamps >= t[0] + margin) & (stamps <= t[-1] - margin)


def _runs_with_truth(runs: Sequence[OdometryLog], truths: Sequence[Truth], margin: float) -> list[_Run]:
    if len(runs) != len(truths):
        raise InputError(f"give one truth per run: {len(runs)} run(s), {len(truths)} truth(s)")
    out = []
    for log, truth in zip(runs, truths, strict=True):
        t = np.asarray(log.t, dtype=float)
        inside = compared_fixes(t, truth.t, margin)
        tau = truth.t[inside]
        if tau.size < 4:
            within = f" (less {margin:g} s at each end, the largest clock offset fitted)" if margin else ""
            raise InputError(f"only {tau.size} truth fixes lie inside the log's time span "
                             f"({t[0]:.6g}..{t[-1]:.6g} s{within}; the truth covers {truth.t[0]:.6g}.."
                             f"{truth.t[-1]:.6g} s): check the clocks (--truth-time-unit, "
                             "--truth-time-offset)", source=truth.source)
        beyond = int(np.count_nonzero(~compared_fixes(t, truth.t)))
        out.append(_Run(t, truth.xy[inside], tau, beyond, int(np.count_nonzero(~inside)) - beyond, margin))
    return out


class _Problem:
    """Position residuals of all runs over their first ``horizon`` fraction, for
    q = (free robot parameters, the truth's clock offset δ if fitted, then x₀, y₀, θ₀ of
    each run)."""

    def __init__(self, model: CalibrationModel, runs: list[_Run], logs: Sequence[OdometryLog],
                 free: NDArray[np.intp], method: Method, fit_time_offset: bool):
        self.model, self.runs, self.free, self.method = model, runs, free, method
        self.p_fixed = model.p0.copy()
        self.t0 = [float(log.t[0]) for log in logs]
        self.t1 = [float(log.t[-1]) for log in logs]
        self.sources = [log.source for log in logs]
        self.horizon = 1.0
        self.n_global = free.size + int(fit_time_offset)  # parameters shared by every run
        self.fit_time_offset = fit_time_offset

    def split(self, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, NDArray[np.float64]]:
        """(robot parameters, clock offset δ [s], start poses (runs, 3))."""
        p = self.p_fixed.copy()
        p[self.free] = q[: self.free.size]
        delta = float(q[self.free.size]) if self.fit_time_offset else 0.0
        return p, delta, q[self.n_global:].reshape(-1, 3)

    def used(self, i: int) -> NDArray[np.bool_]:
        run = self.runs[i]
        return run.t <= self.t0[i] + self.horizon * (self.t1[i] - self.t0[i])


    def residuals_and_jacobian(self, q: NDArray[np.float64]
                               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        p, delta, starts = self.split(q)
        n_free = self.free.size
        res, jac = [], []
        for i, run in enumerate(self.runs):
            dd, dth, ddd, ddt = self.model.steps(p, i)
            poses, dposes = integrate_with_sensitivity(dd, dth, ddd[:, self.free], ddt[:, self.free],
                                                       starts[i], self.method)
            keep = self.used(i)
            fixes = run.at(delta, keep)
            pos = fixes.interpolate(poses[:, :2])
            r = pos - run.xy[keep]
            j = np.zeros((pos.shape[0], 2, q.size))
            j[:, :, :n_free] = fixes.interpolate(dposes[:, :2])
            if self.fit_time_offset:
                # a later δ compares each fix with the odometry earlier: −velocity there
                j[:, :, n_free] = -fixes.rate(poses[:, :2])
            col = self.n_global + 3 * i
            j[:, 0, col] = 1.0
            j[:, 1, col + 1] = 1.0
            # a turn of the start by dθ₀ swings every position about the start
            j[:, 0, col + 2] = -(pos[:, 1] - starts[i][1])
            j[:, 1, col + 2] = pos[:, 0] - starts[i][0]
            res.append(r.reshape(-1))
            jac.append(j.reshape(-1, q.size))
        return np.concatenate(res), np.concatenate(jac)

    def align_starts(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each run's start pose by SE(2) alignment of its odometry (parameters ``p``, from
        the origin) to the truth over the current horizon (Umeyama, closed form)."""
        starts = []
        for i, run in enumerate(self.runs):
            dd, dth = self.model.steps(p, i)[:2]
            zero = np.zeros((dd.size, 0))
            poses, _ = integrate_with_sensitivity(dd, dth, zero, zero, np.zeros(3), self.method)
            keep = self.used(i)
            try:
                phi, shift = umeyama_se2(run.at(0.0, keep).interpolate(poses[:, :2]), run.xy[keep])
            except ModelError:
                raise InputError("the odometry does not move over the run's first "
                                 f"{self.horizon * (self.t1[i] - self.t0[i]):.3g} s while the truth does: "
                                 "check the log's channels and --columns", source=self.sources[i]) from None
            starts.append([shift[0], shift[1], phi])
        return np.asarray(starts, dtype=float).reshape(-1)


#: [rad] a steering offset beyond this from the robot file's is a wrong steering channel, not an
#: offset (the calibration's plausible range; :func:`odomkit.calibrate.stability.weakly_pinned`).
MAX_STEERING_OFFSET = 0.5


def scale_range(value: float) -> tuple[float, float]:
    """The plausible range of a scale or a length from the robot file's ``value``: half to
    twice it (a factor 2 is a wrong robot file, not a calibration)."""
    return value / 2, value * 2


def _bounds(model: CalibrationModel, free: NDArray[np.intp], n_runs: int, fit_time_offset: bool
            ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Plausible ranges of q = (free robot parameters, clock offset, start poses): a scale
    or length within half to twice the robot file's value (a factor 2 is a wrong robot
    file, not a calibration), a steering offset within ±0.5 rad, a car's steering_cubic
    within ±1/s² for the largest steering angle s driven, the clock offset within
    ±:data:`MAX_TIME_OFFSET`; start poses free."""
    n = free.size + int(fit_time_offset) + 3 * n_runs
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    if fit_time_offset:
        lower[free.size], upper[free.size] = -MAX_TIME_OFFSET, MAX_TIME_OFFSET
    for j, k in enumerate(free):
        value = float(model.p0[k])
        if model.names[k] == "steering_offset":
            lower[j], upper[j] = value - MAX_STEERING_OFFSET, value + MAX_STEERING_OFFSET
        elif model.names[k] == "steering_cubic" and isinstance(model, CarCalibrationModel):
            # k s³ at most the angle s itself at the largest angle driven: a ratio that
            # varies by more than a factor 2 over the logs' range is no rack's.
            largest = max((float(np.max(np.abs(steer))) for _, steer in model.raw if len(steer)), default=0.0)
            if largest > 0:
                lower[j], upper[j] = -1 / largest**2, 1 / largest**2
        elif model.positive[k]:  # a scale or a length (an offset or bias may be any sign)
            lower[j], upper[j] = scale_range(value)
    return lower, upper


def _first_horizon(problem: _Problem, min_fixes: int, min_spread: Sequence[float],
                   sources: Sequence[str]) -> float:
    """The shortest power-of-two fraction of every run holding at least ``min_fixes`` fixes
    that spread (RMS distance from their centroid) at least ``min_spread`` [m] of that run:
    the first stage aligns each run's odometry to them, which a robot standing or turning
    on the spot at its start cannot give. A run whose fixes never spread so far is refused."""

    def enough(i: int) -> bool:
        xy = problem.runs[i].xy[problem.used(i)]
        spread = float(np.sqrt(np.mean(np.sum((xy - xy.mean(axis=0)) ** 2, axis=1)))) if len(xy) else 0.0
        return len(xy) >= min_fixes and spread >= min_spread[i]

    problem.horizon = 1.0
    for i in range(len(problem.runs)):
        if not enough(i):
            raise InputError(f"the run's truth fixes do not spread {min_spread[i]:.3g} m or more (three "
                             "times the truth's σ, at least 1 cm) over the whole run: it does not move "
                             "enough to calibrate from", source=sources[i])
    horizon = 1.0
    while horizon > 1 / 64:
        problem.horizon = horizon / 2
        if not all(enough(i) for i in range(len(problem.runs))):
            break
        horizon /= 2
    problem.horizon = horizon
    return horizon


def calibrate_positions(
    runs: Sequence[OdometryLog],
    truths: Sequence[Truth],
    robot: CalibratedRobot,
    *,
    fixed: Collection[str] = (),
    min_first_fixes: int = MIN_FIRST_FIXES,
    method: Method = "exact",
    fit_time_offset: bool = False,
    steering_cubic: bool = False,
) -> ExactCalibration:
    """Fit a robot's systematic parameters to truth positions on the truth's own clock.

    Parameters
    ----------
    runs : sequence of OdometryLog
        The logs (their own ground truth, if any, is not used).
    truths : sequence of Truth
        One per run (:class:`odomkit.truth.Truth`; heading, if any, is not used).
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        Nominal parameters, the starting point: diff (c_left, c_right, c_wheel_base),
        tricycle (c_scale, steering_offset, wheel_to_axle), unicycle (c_scale,
        yaw_rate_bias, yaw_rate_scale), gyro (m_per_tick, held where no log has ticks;
        gyro_bias, gyro_scale), car (c_scale,
        steering_offset, wheel_base).
    fixed : collection of str
        Parameter names held at the robot's values.
    min_first_fixes : int
        Fewest fixes per run in the first stage of the growing horizon.
    method : {"exact", "midpoint", "euler"}
    fit_time_offset : bool
        Fit the truth's clock offset δ [s] too, one for all runs (a fix stamped t is the pose
        at log time t − δ), within ±:data:`MAX_TIME_OFFSET`; fixes within that of either
        end of a log are left out.
    steering_cubic : bool
        A car's ``steering_cubic`` [rad⁻²] is fitted too, as a fourth parameter (a steering
        ratio that varies with the angle; only large steering angles identify it).

    Returns
    -------
    ExactCalibration
        ``source = "positions"``; ``values``, ``std_errors``, ``cov`` of all the robot's
        parameters (a fixed one has zero variance); ``time_offset`` and
        ``time_offset_std_error`` [s] when fitted; ``notes`` list the stages and each run's
        fitted start pose.
    """
    if len(runs) < 1:
        raise InputError("calibration needs at least one run")
    if not isinstance(robot, CALIBRATED_ROBOTS):
        raise ModelError(f"calibration from truth positions supports DiffDrive, Tricycle, Car, Unicycle "
                         f"and GyroOdometry robots, got {type(robot).__name__}")
    min_first_fixes = validate.positive_int(min_first_fixes, "min_first_fixes")
    model = calibration_model(robot, runs, steering_cubic=steering_cubic)
    unknown = sorted(set(fixed) - set(model.names))
    if unknown:
        raise ModelError(f"fixed names {', '.join(unknown)}; the parameters are {', '.join(model.names)}")
    notes: list[str] = [f"{name} held at the robot file's value: {why}"
                        for name, why in model.unobservable.items() if name not in fixed]
    fixed = set(fixed) | set(model.unobservable)
    free = np.array([k for k, n in enumerate(model.names) if n not in fixed], dtype=np.intp)
    with_truth = _runs_with_truth(runs, truths, MAX_TIME_OFFSET if fit_time_offset else 0.0)
    problem = _Problem(model, with_truth, runs, free, method, fit_time_offset)

    horizon = _first_horizon(problem, min_first_fixes, [max(3.0 * t.sigma, 0.01) for t in truths],
                             [log.source for log in runs])
    q = np.concatenate([model.p0[free], [0.0] if fit_time_offset else [], problem.align_starts(model.p0)])
    lower, upper = _bounds(model, free, len(with_truth), fit_time_offset)
    while True:
        n_res = sum(2 * int(np.count_nonzero(problem.used(i))) for i in range(len(with_truth)))
        if n_res > q.size:
            # Bounded (trust-region reflective): over a short first horizon a parameter the
            # path does not yet excite (the wheel base before the first turn) is free to run
            # off to ±1e185 under plain Levenberg–Marquardt, and no later stage brings it back.
            sol = least_squares(lambda x: problem.residuals_and_jacobian(x)[0], q,
                                jac=lambda x: problem.residuals_and_jacobian(x)[1], method="trf",
                                bounds=(lower, upper), x_scale="jac", xtol=1e-12, ftol=1e-12,
                                gtol=1e-12, max_nfev=200)
            if not np.all(np.isfinite(sol.x)):
                raise ModelError("the calibration diverged to non-finite parameters; check the "
                                 "truth's clock and the robot file's units")
            q = sol.x
            notes.append(f"horizon {horizon:.4g} of each run: {n_res // 2} fixes, residual rms "
                         f"{float(np.sqrt(np.mean(sol.fun**2))):.4g} m")
        if horizon >= 1.0:
            break
        horizon = min(1.0, 2 * horizon)
        problem.horizon = horizon
    names = [*(model.names[k] for k in free), *(["truth time offset"] if fit_time_offset else [])]
    at_bound = [name for j, name in enumerate(names)
                if np.isclose(q[j], lower[j], rtol=1e-6, atol=0.0)
                or np.isclose(q[j], upper[j], rtol=1e-6, atol=0.0)]
    if at_bound:
        ranges = {"steering_offset": f"steering offset ±{MAX_STEERING_OFFSET} rad",
                  "steering_cubic": "steering_cubic ±1/s² for the largest angle s driven (a ratio that "
                  "varies at most 2× over it: a drive that hardly turns cannot pin it)",
                  "truth time offset": f"clock offset ±{MAX_TIME_OFFSET:g} s"}
        scale = "a scale or length: half to twice the robot file's value"
        said = "; ".join(dict.fromkeys(ranges.get(name, scale) for name in at_bound))
        raise ModelError(f"the calibration ran to the edge of the plausible range for "
                         f"{', '.join(at_bound)} ({said}): check the channel signs, the robot file and the "
                         "truth's clock, and that the runs turn both ways")
    res, jac = problem.residuals_and_jacobian(q)
    dof = res.size - q.size
    if dof <= 0:
        raise InputError(f"{res.size} position residuals cannot determine {q.size} parameters "
                         "(the robot's and each run's start pose): give longer runs or more truth")
    var_res = float(res @ res) / dof
    warn_if_drifting(var_res, res.size, truths)
    cov_q = var_res * np.linalg.pinv(jac.T @ jac)
    p, delta, starts = problem.split(q)
    cov = np.zeros((len(model.names), len(model.names)))
    cov[np.ix_(free, free)] = cov_q[: free.size, : free.size]
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, np.where(std > 0, 1.0, 0.0))
    if np.any(p[np.asarray(model.positive)] <= 0):
        raise ModelError(f"calibration diverged to non-positive parameters {p.tolist()}; check the "
                         "channel signs and the robot file")
    for log, start, run in zip(runs, starts, with_truth, strict=True):
        left = ([f"{run.outside} outside the log's span"] if run.outside else []) + (
            [f"{run.near_ends} within {run.margin:g} s of its ends (where a fitted clock offset could "
             "move them out)"] if run.near_ends else [])
        left_out = f"; truth fixes left out: {' and '.join(left)}" if left else ""
        notes.append(f"{log.source}: start pose fitted at ({start[0]:.4g} m, {start[1]:.4g} m, "
                     f"{start[2]:.4g} rad){left_out}")
    if any(truth.theta is not None for truth in truths):
        # The fit is on positions so that any truth, GPS included, enters it alike; a truth
        # that measures heading still pins the start heading better than positions alone.
        notes.append("the truth's heading is not compared (every fix is compared as a position); "
                     "it is used where the track starts from the truth (evaluate, track)")
    between = None
    if len(runs) > 1:
        between = _between_runs_of_positions(problem, res, jac, len(model.names))
        if between is None:
            notes.append("no standard errors between runs: a run's own start pose leaves a parameter "
                         "undetermined without it")
        elif scattered := between_runs_warning(model.names, p, std, between, len(runs)):
            warnings.warn(scattered, UserWarning, stacklevel=2)
    travelled = [float(np.sum(np.abs(model.steps(p, i)[0]))) for i in range(len(runs))]
    spread = [float(np.sqrt(np.mean(np.sum((r.xy - r.xy.mean(axis=0)) ** 2, axis=1)))) for r in with_truth]
    sensitivity = float(np.mean([s / d if d > 0 else 0.0 for s, d in zip(spread, travelled, strict=True)]))
    return ExactCalibration(
        robot=model.make_robot(p), names=model.names, values=p, std_errors=std, cov=cov, corr=corr,
        residual_variance=var_res, n_residuals=int(res.size), n_runs=len(runs), source="positions",
        scale_fixed=bool({"c_scale", "m_per_tick"} & fixed) or {"c_left", "c_right"} <= fixed,
        scale_sensitivity=sensitivity, notes=tuple(notes),
        time_offset=delta if fit_time_offset else None,
        time_offset_std_error=(float(np.sqrt(max(cov_q[free.size, free.size], 0.0))) if fit_time_offset
                               else None),
        std_errors_between_runs=between,
    )


def _between_runs_of_positions(problem: _Problem, res: NDArray[np.float64], jac: NDArray[np.float64],
                               n_params: int) -> NDArray[np.float64] | None:
    """The robot parameters' standard errors between runs (:func:`odomkit.calibrate.exact.between_runs`)
    for a fit with a start pose per run.

    Each run's start pose is its own (a nuisance parameter of one cluster): by the
    Frisch–Waugh–Lovell theorem the shared parameters' estimate is the one from the rows of
    each run made orthogonal to that run's own start-pose columns, so the runs' spread is
    taken there (the residuals at the solution are orthogonal to those columns already)."""
    n_global = problem.n_global
    blocks, sizes = [], []
    start = 0
    for i in range(len(problem.runs)):
        size = 2 * int(np.count_nonzero(problem.used(i)))
        rows = slice(start, start + size)
        start += size
        own = jac[rows, n_global + 3 * i:n_global + 3 * i + 3]
        shared = jac[rows, :n_global]
        coef, *_ = np.linalg.lstsq(own, shared, rcond=None)
        blocks.append(shared - own @ coef)
        sizes.append(size)
    # Map the shared q (free robot parameters, then the clock offset) onto every robot parameter.
    T = np.zeros((n_params, n_global))
    T[problem.free, np.arange(problem.free.size)] = 1.0
    between, _ = between_runs(np.concatenate(blocks), res, sizes, T)
    return between


def runs_disagree(joint: ExactCalibration, alone: Sequence[ExactCalibration | None],
                  sources: Sequence[str]) -> str | None:
    """A warning where a fit of several runs together is no compromise of their own fits.

    Runs of one robot give parameters that scatter about one value, and their joint fit
    lies among them. Runs that no one robot fits (logs of different robots, or a channel
    spoilt in one) can drive the joint fit far outside them all: a wandering robot whose
    heading the compromise gets wrong fits its fixes best with its path shrunk (two
    simulated commanded-velocity robots, each fitted alone to c_scale 1.003 and 0.973, gave
    0.714 together). A parameter is named where the joint value lies outside the runs'
    range by more than that range and five of their standard errors.

    Parameters
    ----------
    joint : the fit of every run together
    alone : each run's own fit (None where it could not be fitted alone)
    sources : each run's name, for the message
    """
    fitted = [(c, name) for c, name in zip(alone, sources, strict=True) if c is not None]
    if len(fitted) < 2:
        return None
    off = []
    for k, name in enumerate(joint.names):
        values = np.array([c.values[k] for c, _ in fitted])
        slack = max(float(np.ptp(values)), 5.0 * max(float(c.std_errors[k]) for c, _ in fitted))
        if not (values.min() - slack <= joint.values[k] <= values.max() + slack):
            each = ", ".join(f"{v:.4g} ({source})" for v, (_, source) in zip(values, fitted, strict=True))
            off.append(f"{name} {joint.values[k]:.4g} together, {each} alone")
    if not off:
        return None
    return ("the runs disagree: fitted together they give what none of them gives alone ("
            + "; ".join(off) + "): no one robot fits these logs (logs of different robots: calibrate "
            "each; or a run whose channels or truth are wrong); the joint parameters are not to be used")
