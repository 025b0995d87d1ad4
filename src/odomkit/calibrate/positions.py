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
  (the residual is piecewise linear in δ). δ is fitted within :func:`clock_range`
  (:data:`MAX_TIME_OFFSET`, or a quarter of the shortest run), and fixes within that of
  either end of the log are left out, so the same fixes are compared at every δ;
* a long run whose dead-reckoned heading wanders (metres of drift in a small arena) biases
  the fit of the whole run, which shrinks the track to shorten its residuals
  (:func:`drift_bias` says so); with ``window`` each run is cut into windows, each fitted
  from a start pose of its own, the robot's parameters and δ shared. There each window's
  start pose is eliminated for the parameters tried (variable projection: its SE(2)
  alignment to the fixes), so no column per window is held: the windows are
  the clusters of the between-run standard errors;
* with ``heading_weight`` W > 0 [m/rad] and a truth that measures heading (a TUM file, text
  t,x,y,theta, a motion capture), each fix adds a third residual W·wrap(θ(t) + θ₀ − θ_truth(t))
  [m] beside its two position residuals (:func:`~odomkit.calibrate.residuals.heading_residual`,
  as the exact calibration compares the log's own gt_θ), θ(t) the dead-reckoned heading
  from the origin interpolated at the fix as the positions are, in a fit of whole runs and of
  windows alike. A commanded-velocity robot that slows in its turns fits its path from
  positions alone with the yaw-rate scale pulled towards the path's curvature (ω/v: the
  speed lost in the turns reads as turning), while the heading's change is ∫ω dt whatever
  the speed: it pins the turning gain. The start pose a window's variable projection
  eliminates is then the optimum of all three residuals: the positions' SE(2) alignment
  refined by Gauss–Newton steps in (x₀, y₀, θ₀) (:meth:`_Problem._refine`).

The parameter-to-body-step maps are :mod:`odomkit.calibrate.residuals`' (diff, tricycle,
car) and the integration with sensitivities its
:func:`~odomkit.calibrate.residuals.integrate_with_sensitivity`.
"""

from __future__ import annotations

import warnings
from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from odomkit import validate
from odomkit.calibrate.exact import (
    ExactCalibration,
    between_runs,
    between_runs_warning,
    held_note,
    truth_noise,
    warn_if_drifting,
)
from odomkit.calibrate.residuals import (
    CALIBRATED_ROBOTS,
    CalibratedRobot,
    CalibrationModel,
    CarCalibrationModel,
    calibration_model,
    heading_residual,
    integrate_with_sensitivity,
)
from odomkit.errors import InputError, ModelError
from odomkit.evaluate import umeyama_se2
from odomkit.kinematics import Method, body_steps
from odomkit.log import OdometryLog, clock_text
from odomkit.robot import Car, Tricycle
from odomkit.truth import Truth, clock_unit_hint
from odomkit.windows import WindowSpec, cumulative_travel, parse_window, split_windows, why_no_windows

__all__ = ["CLOCK_SHARE", "clock_range", "DRIFT_GIST", "DRIFT_SHARE", "DRIFT_WINDOW", "MAX_STEERING_OFFSET",
           "MAX_TIME_OFFSET",
           "MIN_FIRST_FIXES", "MIN_WINDOW_FIXES", "calibrate_positions", "compared_fixes", "drift_bias",
           "drift_shares", "runs_disagree", "scale_range", "truth_spreads", "windows_drift"]

#: Fewest truth fixes in the first (shortest) stage of the growing horizon.
MIN_FIRST_FIXES = 30
#: The largest truth clock offset [s] the calibration fits: a GPS's latency or a
#: command's lag is a fraction of a second; beyond this the clocks differ, and the truth
#: file's times need shifting (``--truth-time-offset``).
MAX_TIME_OFFSET = 2.0
#: ... and at most this share of the shortest run: fixes within the range of either end of a
#: run are left out (a fitted offset could move them out of the log), and a run of 3.3 s (an
#: F1TENTH car's slalom, a user study) kept none at 2 s, refused with "check the clocks".
CLOCK_SHARE = 0.25


def clock_range(runs: Sequence[OdometryLog]) -> float:
    """The largest truth clock offset [s] :func:`calibrate_positions` fits for these runs:
    :data:`MAX_TIME_OFFSET`, or :data:`CLOCK_SHARE` of the shortest run where that is less.
    Fixes within it of either end of a run are left out of the fit."""
    shortest = min((float(log.t[-1] - log.t[0]) for log in runs if len(log) > 1), default=0.0)
    return min(MAX_TIME_OFFSET, CLOCK_SHARE * shortest) if shortest > 0 else MAX_TIME_OFFSET


@dataclass(frozen=True)
class _Run:
    """The truth fixes of one run inside its log's span (less ``margin`` [s] at each end)."""

    log_t: NDArray[np.float64]  # (N,) the log's times [s]
    xy: NDArray[np.float64]  # (n, 2) truth positions [m]
    t: NDArray[np.float64]  # (n,) fix times [s]
    outside: int  # fixes outside the log's span
    near_ends: int = 0  # fixes inside it but within the margin of its ends
    margin: float = 0.0  # [s]
    theta: NDArray[np.float64] | None = None  # (n,) truth headings [rad], continuous; None: positions only

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
        """d/dt of that interpolation of ``values`` (N, ...) at the fixes (zero inside a
        segment of zero length)."""
        step = values[self.row + 1] - values[self.row]
        inverse = np.divide(1.0, self.span, out=np.zeros_like(self.span), where=self.span > 0)
        return step * inverse.reshape(inverse.shape + (1,) * (step.ndim - 1))


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
            within = f" (less {margin:.3g} s at each end, the largest clock offset fitted)" if margin else ""
            # A log in ms against a truth in s wants --time-unit ms, not the truth's flags (the
            # log's span before --span cut it: a cut log spans less by design).
            uncut = log.meta.get("uncut_clock")
            start, end = uncut if isinstance(uncut, tuple) else (t[0], t[-1])
            hint = clock_unit_hint(float(end - start), float(truth.t[-1] - truth.t[0]))
            raise InputError(f"only {tau.size} truth fixes lie inside the log's time span "
                             f"({clock_text(t[0])}..{clock_text(t[-1])} s{within}; the truth covers "
                             f"{clock_text(truth.t[0])}..{clock_text(truth.t[-1])} s): " + (
                                 hint if hint is not None else
                                 "check the clocks (--truth-time-unit, --truth-time-offset)"),
                             source=truth.source)
        beyond = int(np.count_nonzero(~compared_fixes(t, truth.t)))
        out.append(_Run(t, truth.xy[inside], tau, beyond, int(np.count_nonzero(~inside)) - beyond, margin,
                        None if truth.theta is None else truth.theta[inside]))
    return out


#: Most Gauss–Newton steps that refine a start pose with the heading compared (:meth:`_Problem._refine`):
#: three unknowns, from the positions' alignment; a few steps reach round-off.
_START_STEPS = 20


class _Problem:
    """Position residuals of all runs over their first ``horizon`` fraction, for
    q = (free robot parameters, the truth's clock offset δ if fitted, then x₀, y₀, θ₀ of
    each run); with ``heading_weight`` W > 0 each fix's heading residual W·wrap(θ − θ_truth)
    [m] third (:attr:`per_fix` residuals a fix).

    :meth:`residuals_and_jacobian` is the full problem in q. :meth:`reduced` is the same
    problem with every run's start pose at its best for the shared parameters g (the first
    ``n_global`` entries of q): a start pose moves the run's dead-reckoned track rigidly, so
    for given g it is the SE(2) alignment of the track to the fixes (Umeyama 1991, closed
    form), and the shared parameters are fitted on their own (variable projection, Golub &
    Pereyra 1973). Its Jacobian is each run's block of shared columns made orthogonal to the
    run's own start-pose columns (Kaufman 1975), the Frisch–Waugh–Lovell form whose
    ``JᵀJ`` is the shared block of the full problem's information with the start poses
    marginalised. The two have the same minima; the reduced one holds a dense Jacobian of
    residuals × shared parameters only, so many runs (windows) cost no memory per run. With
    the heading compared the best start pose is no longer the positions' alignment alone: it
    is refined to the optimum of every residual (:meth:`_refine`), where the start-pose
    columns are orthogonal to the residuals, so the reduced gradient Jᵀr is still the
    reduced cost's."""

    def __init__(self, model: CalibrationModel, runs: list[_Run], logs: Sequence[OdometryLog],
                 free: NDArray[np.intp], method: Method, fit_time_offset: bool, heading_weight: float = 0.0):
        self.model, self.runs, self.free, self.method = model, runs, free, method
        self.w = heading_weight  # [m/rad]; 0: positions only
        self.per_fix = 3 if heading_weight > 0 else 2  # residuals a fix
        self.p_fixed = model.p0.copy()
        self.t0 = [float(log.t[0]) for log in logs]
        self.t1 = [float(log.t[-1]) for log in logs]
        self.sources = [log.source for log in logs]
        self.horizon = 1.0
        self.n_global = free.size + int(fit_time_offset)  # parameters shared by every run
        self.fit_time_offset = fit_time_offset
        self._last: tuple[bytes, float, tuple[NDArray[np.float64], NDArray[np.float64],
                                               NDArray[np.float64], list[int]]] | None = None

    def split(self, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, NDArray[np.float64]]:
        """(robot parameters, clock offset δ [s], start poses (runs, 3); none for g alone)."""
        p = self.p_fixed.copy()
        p[self.free] = q[: self.free.size]
        delta = float(q[self.free.size]) if self.fit_time_offset else 0.0
        return p, delta, q[self.n_global:].reshape(-1, 3)

    def used(self, i: int) -> NDArray[np.bool_]:
        run = self.runs[i]
        return run.t <= self.t0[i] + self.horizon * (self.t1[i] - self.t0[i])

    def _block(self, i: int, p: NDArray[np.float64], delta: float, start: NDArray[np.float64] | None
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Run ``i`` over the current horizon from ``start`` (x₀, y₀, θ₀), or from the start
        that fits its fixes best (None): residuals (n, k) [m] (k = :attr:`per_fix`: x, y and
        with the heading compared W·wrap(θ − θ_truth)), their derivatives in the shared
        parameters (n, k, n_global) and in the start pose (n, k, 3), and the start pose (3,)."""
        dd, dth, ddd, ddt = self.model.steps(p, i)
        # From the origin, then moved rigidly: dead reckoning from a start pose is the track
        # from the origin rotated by θ₀ and shifted (the parameters' derivatives rotate alike).
        poses, dposes = integrate_with_sensitivity(dd, dth, ddd[:, self.free], ddt[:, self.free],
                                                   np.zeros(3), self.method)
        keep = self.used(i)
        run = self.runs[i]
        fixes = run.at(delta, keep)
        track = _Track(fixes.interpolate(poses[:, :2]), fixes.interpolate(dposes[:, :2]),
                       fixes.rate(poses[:, :2]) if self.fit_time_offset else None, run.xy[keep])
        if self.w > 0:
            assert run.theta is not None  # calibrate_positions refuses a truth without heading
            # The heading from the origin, interpolated at the fixes as the positions are.
            track = replace(track, theta=fixes.interpolate(poses[:, 2]),
                            dtheta=fixes.interpolate(dposes[:, 2]),
                            theta_rate=fixes.rate(poses[:, 2]) if self.fit_time_offset else None,
                            truth_theta=run.theta[keep])
        if start is None:
            try:
                phi, shift = umeyama_se2(track.xy0, track.xy)
            except ModelError:
                raise InputError("the odometry does not move over the run's first "
                                 f"{self.horizon * (self.t1[i] - self.t0[i]):.3g} s while the truth does: "
                                 "check the log's channels and --columns", source=self.sources[i]) from None
            start = np.array([shift[0], shift[1], phi])
            if self.w > 0:
                start = self._refine(start, track)
        r, jg, js = self._at(start, track)
        return r, jg, js, np.asarray(start, dtype=float)

    def _at(self, start: NDArray[np.float64], track: _Track
            ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """One run's residuals (n, k) [m] from ``start`` (x₀, y₀, θ₀) and their derivatives in
        the shared parameters (n, k, n_global) and in the start pose (n, k, 3)."""
        c, s = np.cos(start[2]), np.sin(start[2])
        rot = np.array([[c, -s], [s, c]])
        pos = track.xy0 @ rot.T + start[:2]
        n_free = self.free.size
        jg = np.zeros((pos.shape[0], self.per_fix, self.n_global))
        jg[:, :2, :n_free] = np.einsum("ab,nbk->nak", rot, track.dxy0)
        if track.velocity is not None:
            # a later δ compares each fix with the odometry earlier: −velocity there
            jg[:, :2, n_free] = -(track.velocity @ rot.T)
        js = np.zeros((pos.shape[0], self.per_fix, 3))
        js[:, 0, 0] = 1.0
        js[:, 1, 1] = 1.0
        # a turn of the start by dθ₀ swings every position about the start
        js[:, 0, 2] = -(pos[:, 1] - start[1])
        js[:, 1, 2] = pos[:, 0] - start[0]
        res = pos - track.xy
        if self.per_fix == 3:
            assert track.theta is not None and track.dtheta is not None and track.truth_theta is not None
            # θ(t) + θ₀ against the truth's, as the exact calibration compares gt_θ
            res = np.column_stack([res, heading_residual(track.theta + start[2], track.truth_theta, self.w)])
            jg[:, 2, :n_free] = self.w * track.dtheta
            if track.theta_rate is not None:
                jg[:, 2, n_free] = -self.w * track.theta_rate
            js[:, 2, 2] = self.w
        return res, jg, js

    def _refine(self, start: NDArray[np.float64], track: _Track) -> NDArray[np.float64]:
        """The start pose that minimises all of one run's residuals, positions and heading,
        from ``start`` (the positions' SE(2) alignment): Gauss–Newton steps in (x₀, y₀, θ₀),
        each halved until it lowers the sum of squares, until θ₀ moves less than 1e-12 rad
        (at most :data:`_START_STEPS`). There the start-pose columns are orthogonal to the
        residuals, as variable projection's reduced Jacobian takes them to be."""
        r, _, js = self._at(start, track)
        cost = float(np.sum(r**2))
        for _ in range(_START_STEPS):
            step = np.linalg.lstsq(js.reshape(-1, 3), -r.reshape(-1), rcond=None)[0]
            for _ in range(40):
                trial = start + step
                r_trial, _, js_trial = self._at(trial, track)
                cost_trial = float(np.sum(r_trial**2))
                if cost_trial <= cost:
                    break
                step = step / 2
            else:
                break  # no step lowers the sum of squares: at its minimum to round-off
            start, r, js, cost = trial, r_trial, js_trial, cost_trial
            if abs(step[2]) < 1e-12:
                break
        return start

    def residuals_and_jacobian(self, q: NDArray[np.float64]
                               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The full problem: residuals (m,) [m] and the dense Jacobian (m, q.size)."""
        p, delta, starts = self.split(q)
        res, jac = [], []
        for i in range(len(self.runs)):
            r, jg, js, _ = self._block(i, p, delta, starts[i])
            j = np.zeros((r.shape[0], r.shape[1], q.size))
            j[:, :, : self.n_global] = jg
            col = self.n_global + 3 * i
            j[:, :, col:col + 3] = js
            res.append(r.reshape(-1))
            jac.append(j.reshape(-1, q.size))
        return np.concatenate(res), np.concatenate(jac)

    def reduced(self, g: NDArray[np.float64], starts: NDArray[np.float64] | None = None
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], list[int]]:
        """The problem in the shared parameters g alone, each run from its best start pose
        (or from ``starts`` (runs, 3) given): residuals (m,) [m], the Jacobian (m, n_global)
        with each run's rows made orthogonal to its start-pose columns, the start poses
        (runs, 3) and each run's row count. The last answer without ``starts`` is kept
        (least_squares asks for the residuals and the Jacobian at the same g one after the
        other)."""
        key = np.asarray(g, dtype=float).tobytes()
        last = self._last
        if starts is None and last is not None and last[0] == key and last[1] == self.horizon:
            return last[2]
        p, delta, _ = self.split(g)
        res, jac, found, sizes = [], [], [], []
        for i in range(len(self.runs)):
            r, jg, js, start = self._block(i, p, delta, None if starts is None else starts[i])
            jg2, js2 = jg.reshape(-1, self.n_global), js.reshape(-1, 3)
            coef = np.linalg.lstsq(js2, jg2, rcond=None)[0]
            res.append(r.reshape(-1))
            jac.append(jg2 - js2 @ coef)
            found.append(start)
            sizes.append(r.size)
        out = (np.concatenate(res), np.concatenate(jac), np.asarray(found).reshape(-1, 3), sizes)
        if starts is None:
            self._last = (key, self.horizon, out)
        return out

    def positions(self, res: NDArray[np.float64], sizes: Sequence[int]
                  ) -> tuple[NDArray[np.float64], list[int]]:
        """The position residuals (x, y of each fix) [m] of ``res`` (m,), run after run in
        blocks of ``sizes``, and each run's count of them: ``res`` itself where the heading is
        not compared."""
        if self.per_fix == 2:
            return res, list(sizes)
        return res.reshape(-1, 3)[:, :2].reshape(-1), [2 * (size // 3) for size in sizes]


@dataclass(frozen=True)
class _Track:
    """One run's dead-reckoned track from the origin at its fixes, for :meth:`_Problem._at`:
    positions (n, 2) [m], their derivatives in the free parameters (n, 2, n_free), its
    velocity there (n, 2) [m/s] (None without the clock offset), the truth's positions
    (n, 2); with the heading compared the heading (n,) [rad], its derivatives (n, n_free),
    its rate (n,) [rad/s] (None without the clock offset) and the truth's heading (n,)."""

    xy0: NDArray[np.float64]
    dxy0: NDArray[np.float64]
    velocity: NDArray[np.float64] | None
    xy: NDArray[np.float64]
    theta: NDArray[np.float64] | None = None
    dtheta: NDArray[np.float64] | None = None
    theta_rate: NDArray[np.float64] | None = None
    truth_theta: NDArray[np.float64] | None = None


#: [rad] a steering offset beyond this from the robot file's is a wrong steering channel, not an
#: offset (the calibration's plausible range; :func:`odomkit.calibrate.stability.weakly_pinned`).
MAX_STEERING_OFFSET = 0.5


def scale_range(value: float) -> tuple[float, float]:
    """The plausible range of a scale or a length from the robot file's ``value``: half to
    twice it (a factor 2 is a wrong robot file, not a calibration)."""
    return value / 2, value * 2


def _bounds(model: CalibrationModel, free: NDArray[np.intp], n_runs: int, fit_time_offset: bool,
            clock: float = MAX_TIME_OFFSET) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Plausible ranges of q = (free robot parameters, clock offset, start poses): a scale
    or length within half to twice the robot file's value (a factor 2 is a wrong robot
    file, not a calibration), a steering offset within ±0.5 rad, a car's steering_cubic
    within ±1/s² for the largest steering angle s driven, the clock offset within ±``clock``
    [s] (:func:`clock_range`); start poses free."""
    n = free.size + int(fit_time_offset) + 3 * n_runs
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    if fit_time_offset:
        lower[free.size], upper[free.size] = -clock, clock
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


#: The length whose calibrated value stands for a steered vehicle's turning gain: the turning
#: per metre is tan(steer)/wheel_base (a car), sin(steer)/wheel_to_axle (a tricycle).
_TURNING_LENGTHS = {"wheel_base": "tan(steer)", "wheel_to_axle": "sin(steer)"}
#: The parameters that are lengths [m] (the others at a range's edge are shown without a unit).
_LENGTH_NAMES = ("wheel_base", "wheel_to_axle", "m_per_tick")


def _edge_said(model: CalibrationModel, free: NDArray[np.intp], g: NDArray[np.float64],
               lower: NDArray[np.float64], upper: NDArray[np.float64], at_bound: Sequence[str]) -> str:
    """What a fit run to the edge of its range says after the names (``at_bound``, of
    ``model.names[free]`` and ``"truth time offset"``; ``g`` the fitted global parameters
    within ``lower`` .. ``upper``): each value reached against the robot file's and the
    range, what a steered vehicle's length there means, and what to check.

    A car's wheel base (a tricycle's wheel-to-axle distance) stands for every gain on the
    steering: the turning per metre is tan(steer)/wheel_base, so its value reached says how
    much the vehicle turns against what the robot file says, a steering ratio or understeer
    (a comma2k19 RAV4's highway minute: the turning pins only tan(steer)/(ratio·L), the car
    turning about half what its steering says at speed), and ``--fix`` holds it (the channel
    signs, and turning both ways, do not help there)."""
    robot = model.robot
    names = [*(model.names[k] for k in free), "truth time offset"]
    parts, meaning, other = [], [], False
    for name in at_bound:
        j = names.index(name)
        value = float(g[j])
        upward = bool(np.isclose(value, upper[j], rtol=1e-6, atol=0.0))
        if name == "truth time offset":
            parts.append(f"the truth's clock offset {value:+.3g} s reached, the range ±{upper[j]:.3g} s"
                         + ("" if upper[j] >= MAX_TIME_OFFSET else
                            f" ({CLOCK_SHARE:g} of the shortest run; give --truth-time-offset if the clocks "
                            "differ by more)"))
            other = True
            continue
        file = float(model.p0[free[j]])
        if name == "steering_offset":
            parts.append(f"steering_offset {value:+.4g} rad reached against the robot file's "
                         f"{file:+.4g} rad, the range ±{MAX_STEERING_OFFSET:g} rad about it")
            other = True
            continue
        if name == "steering_cubic":
            parts.append(f"steering_cubic {value:+.4g} rad⁻² reached, the range ±1/s² for the largest "
                         "angle s driven (a ratio that varies at most 2× over it: a drive that hardly turns "
                         "cannot pin it)")
            other = True
            continue
        unit = " m" if name in _LENGTH_NAMES else ""
        parts.append(f"{name} {value:.4g}{unit} reached against the robot file's {file:.4g}{unit}, the range "
                     "half to twice it")
        if name not in _TURNING_LENGTHS or not isinstance(robot, Car | Tricycle):
            other = True
            continue
        gain = file / value  # the turning per metre against the robot file's
        ratio = float(robot.steering_ratio)
        more, less = ("or less", "or more") if upward else ("or more", "or less")
        why = ("or understeer at speed" if isinstance(robot, Car) else "or the wheels slipping in turns"
               ) if upward else "or a steering angle read in the wrong unit"
        meaning.append(
            f"the turning per metre is {_TURNING_LENGTHS[name]}/{name}, so the steering turns the vehicle "
            f"{gain:.2g}× as much as the robot file says, {more} (a steering_ratio of {ratio / gain:.3g} "
            f"{less} rather than the file's {ratio:.3g}, {why}); if the {name.replace('_', ' ')} is known, "
            f"calibrate --fix {name} holds it at the robot file's value and fits the rest")
    said = "; ".join(parts) + ")"
    if meaning:
        said += ": " + "; ".join(meaning)
    if other or not meaning:
        said += ("; " if meaning else ": ") + (
            "check the channel signs, the robot file and the truth's clock, and that the runs turn both ways")
    return said


def _spread(xy: NDArray[np.float64]) -> float:
    """RMS distance [m] of positions (n, 2) from their centroid (0 for none)."""
    return float(np.sqrt(np.mean(np.sum((xy - xy.mean(axis=0)) ** 2, axis=1)))) if len(xy) else 0.0


def _min_spread(truth: Truth) -> float:
    """How far [m] a run's fixes must spread to be calibrated from: three times the truth's
    σ, at least 1 cm (a robot standing or turning on the spot gives no start pose)."""
    return max(3.0 * truth.sigma, 0.01)


def truth_spreads(xy: NDArray[np.float64], truth: Truth) -> bool:
    """Whether fixes (n, 2) [m] of ``truth`` spread enough to align a track to: their RMS
    distance from their centroid is at least three times the truth's σ, and at least 1 cm (a
    robot standing or turning on the spot gives no rotation to align by). The rule by which
    ``calibrate --window`` and ``check``'s windows leave a window out."""
    return _spread(xy) >= _min_spread(truth)


def _first_horizon(problem: _Problem, min_fixes: int, min_spread: Sequence[float],
                   sources: Sequence[str]) -> float:
    """The shortest power-of-two fraction of every run holding at least ``min_fixes`` fixes
    that spread (RMS distance from their centroid) at least ``min_spread`` [m] of that run:
    the first stage aligns each run's odometry to them, which a robot standing or turning
    on the spot at its start cannot give. A run whose fixes never spread so far is refused."""

    def enough(i: int) -> bool:
        xy = problem.runs[i].xy[problem.used(i)]
        return len(xy) >= min_fixes and _spread(xy) >= min_spread[i]

    problem.horizon = 1.0
    for i in range(len(problem.runs)):
        if not enough(i):
            n = int(np.count_nonzero(problem.used(i)))
            if n < min_fixes:  # not "does not move": a short run of a sparse truth has too few
                raise InputError(f"only {n} truth fixes of the run are compared, fewer than the {min_fixes} "
                                 "a calibration aligns its start to (a run too short for its truth's rate; "
                                 "fixes near its ends are left out where the clock offset is fitted): give "
                                 "longer runs, a denser truth, or --truth-time-offset", source=sources[i])
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


#: A whole run whose residuals beyond the truth's noise (RMS per axis) reach this share of how
#: far its truth spreads (RMS distance from the centroid) is drift-dominated (:func:`drift_bias`).
#: Measured: the ten 15-minute MRCLAM runs (Vicon, commanded velocities) 0.19–0.37 where
#: fitted; the first run of every OptiOdom experiment (motion capture, 19–211 s) at most 0.032;
#: simulated 400–600 s drives against a 0.5–1 m GPS at most 0.014.
DRIFT_SHARE = 0.1
#: The window a drift-dominated run is fitted in instead (named in :func:`drift_bias`'s advice;
#: ``odomkit report``, which calibrates for the user, calibrates such a run in it): short
#: beside the MRCLAM runs' drift, long enough for tens of fixes of a 1 Hz GPS.
DRIFT_WINDOW = "60s"
#: How :func:`drift_bias`'s gist begins, in the error of a whole-run fit that ran to the edge
#: of its range on a drifting run.
DRIFT_GIST = "a whole-run fit of a drifting run is biased"


def drift_shares(res: NDArray[np.float64], sizes: Sequence[int], xy: Sequence[NDArray[np.float64]],
                 sigma: float) -> list[tuple[float, float, float]]:
    """Each run's (or window's) (residual RMS [m], spread [m], drift share): the RMS of its
    residuals ``res`` (its ``sizes[i]`` of them, run after run) beyond the truth's noise
    ``sigma`` [m], over how far its fixes ``xy[i]`` (n_i, 2) spread (:data:`DRIFT_SHARE` is
    the share beyond which a fit from one start pose is drift-dominated; 0 where the fixes do
    not spread)."""
    out, start = [], 0
    for size, fixes in zip(sizes, xy, strict=True):
        r = res[start:start + size]
        start += size
        rms = float(np.sqrt(np.mean(r**2))) if size else 0.0
        drift, spread = float(np.sqrt(max(rms**2 - sigma**2, 0.0))), _spread(fixes)
        out.append((rms, spread, drift / spread if spread > 0 else 0.0))
    return out


def windows_drift(res: NDArray[np.float64], sizes: Sequence[int], xy: Sequence[NDArray[np.float64]],
                  truths: Sequence[Truth], length: str | None) -> str | None:
    """A warning where the windows of a windowed fit are themselves drift-dominated, else None:
    the median window's drift share (:func:`drift_shares`) beyond twice :data:`DRIFT_SHARE`
    (a window is a short run fitted from its own start pose, biased as a whole run is; on the
    MRCLAM runs 60 s windows have a median share of 5–11 %, up to 25 % for single windows)."""
    sigma, _ = truth_noise(truths)
    shares = [share for _, _, share in drift_shares(res, sizes, xy, sigma)]
    if len(shares) < 2 or float(np.median(shares)) <= 2 * DRIFT_SHARE:
        return None
    return (f"the windows ({length}) are themselves drift-dominated: the median window's residual RMS "
            f"beyond the truth's noise is {100 * float(np.median(shares)):.0f} % of how far its fixes spread "
            f"(the largest {100 * max(shares):.0f} %, over {len(shares)} windows), so each window's fit "
            "shrinks its track as a whole run's does and the calibration is biased: shorten --window")


def drift_bias(sources: Sequence[str], res: NDArray[np.float64], sizes: Sequence[int],
               xy: Sequence[NDArray[np.float64]], truths: Sequence[Truth], *,
               short: bool = False) -> str | None:
    """A warning where a fit of whole runs is drift-dominated, else None.

    Each run's start pose is fitted with the parameters. Where the odometry's dead-reckoned
    heading wanders over a run, its track departs from the truth by metres; the fit then
    shortens its residuals by shrinking the track about the fixes' centre (an errors-in-
    variables attenuation, of order the square of the drift's share of the run's extent), and
    the scale comes out too small by far more than its standard error (a real 15-minute
    MRCLAM run: c_scale 0.741 ± 0.0014 whole, 0.90 fitted in 60 s windows). Said where a run's
    residual RMS beyond the truth's noise (:func:`odomkit.calibrate.exact.truth_noise`) is
    more than :data:`DRIFT_SHARE` of how far its fixes spread.

    Parameters
    ----------
    sources : each run's name
    res : ndarray, shape (m,)
        The fit's position residuals [m], run after run.
    sizes : each run's share of ``res`` (2 per fix)
    xy : each run's compared fixes, shape (n_i, 2) [m]
    truths : each run's truth (its noise)
    short : the gist alone, for the end of an error message
    """
    sigma, _ = truth_noise(truths)
    said = [f"{source}: residual RMS {rms:.3g} m against a spread of {spread:.3g} m ({100 * share:.0f} %)"
            for source, (rms, spread, share) in zip(sources, drift_shares(res, sizes, xy, sigma), strict=True)
            if share > DRIFT_SHARE]
    if not said:
        return None
    if short:
        return f"{DRIFT_GIST} (it shrinks the track; " + "; ".join(said) + f"): try --window {DRIFT_WINDOW}"
    return ("the whole-run calibration is drift-dominated and biased: " + "; ".join(said) + " (truth noise "
            f"{sigma:.3g} m): the dead-reckoned heading wanders over the run, and a fit of the whole run "
            "shortens its residuals by shrinking the track (a scale too small, a turning gain off) by far "
            "more than its standard errors; fit windows short beside the drift, each from its own start "
            f"pose: --window {DRIFT_WINDOW} (calibrate_positions(..., window=\"{DRIFT_WINDOW}\"))")


#: Fewest truth fixes a window (``calibrate_positions(window=...)``) is fitted from: each has a
#: start pose of its own (three parameters); a window with fewer is left out and counted.
MIN_WINDOW_FIXES = 10


@dataclass(frozen=True)
class _Windows:
    """The windows cut from every log: the kept ones as runs of their own (``logs``: the log's
    rows over the window and ``margin`` beyond each end, ``runs``: the window's fixes), and
    per log how many were cut, how many left out for too few fixes, for truth that does not
    spread, and the compared fixes that fall in no window given."""

    logs: list[OdometryLog]
    runs: list[_Run]
    min_spread: list[float]
    cut: list[int]
    few: list[int]
    still: list[int]
    between: list[int]
    length: str  # "60 s", "20 m" or "given"


def _window_edges(log: OdometryLog, robot: CalibratedRobot, run: _Run, spec: WindowSpec
                  ) -> list[tuple[float, float]]:
    """Consecutive windows of ``spec`` over the compared fixes of one log, (start, end) [s]:
    cut as ``evaluate --window`` and ``fit-noise`` cut them (:func:`odomkit.windows.split_windows`,
    by time or by the odometry's travel with the robot file's values), over the rows between
    the first and the last compared fix; the tail shorter than a window joins the last one, so
    that every fix is compared."""
    t = np.asarray(log.t, dtype=float)
    valid = (t >= run.t[0]) & (t <= run.t[-1])
    travel = cumulative_travel(body_steps(robot, log))
    found, _ = split_windows(t, travel, spec, 0.0, valid=valid)
    if not found:
        raise InputError(why_no_windows(t, travel, valid, spec, 0.0, 0), source=log.source)
    edges = [float(run.t[0])] + [float(t[w.end]) for w in found[:-1]] + [float(run.t[-1])]
    return list(zip(edges[:-1], edges[1:], strict=True))


def _given_edges(log: OdometryLog, given: Sequence[tuple[float, float]], k: int) -> list[tuple[float, float]]:
    """Windows given as (start, end) log times [s], checked: inside the log, each end after its
    start, in order and not overlapping (a fix is compared once)."""
    t0, t1 = float(log.t[0]), float(log.t[-1])
    out: list[tuple[float, float]] = []
    for j, pair in enumerate(given):
        try:
            a, b = (float(x) for x in pair)
        except (TypeError, ValueError):
            raise InputError(f"window {j + 1} of run {k + 1} must be a (start, end) pair of times in "
                             f"seconds, got {pair!r}", source=log.source) from None
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise InputError(f"window {j + 1} ({clock_text(a)}..{clock_text(b)} s) must end after it starts",
                             source=log.source)
        if a < t0 or b > t1:
            raise InputError(f"window {j + 1} ({clock_text(a)}..{clock_text(b)} s) reaches outside the log "
                             f"({clock_text(t0)}..{clock_text(t1)} s)", source=log.source)
        if out and a < out[-1][1]:
            raise InputError(f"window {j + 1} ({clock_text(a)}..{clock_text(b)} s) starts before window {j} "
                             f"ends ({clock_text(out[-1][1])} s): give the windows in order, not overlapping",
                             source=log.source)
        out.append((a, b))
    if not out:
        raise InputError(f"no window given for run {k + 1}", source=log.source)
    return out


def _cut_windows(runs: Sequence[OdometryLog], truths: Sequence[Truth], with_truth: list[_Run],
                 robot: CalibratedRobot, spec: WindowSpec | None,
                 given: Sequence[Sequence[tuple[float, float]]] | None, margin: float) -> _Windows:
    """Every log cut into windows (``spec``, or the (start, end) times ``given`` per log), each
    window's fixes those stamped inside it; a window with fewer than :data:`MIN_WINDOW_FIXES`
    fixes, or whose fixes do not spread (:func:`_min_spread`), is left out and counted. A
    window's log rows reach ``margin`` [s] beyond its ends (the fitted clock offset's range),
    so that its fixes are compared at any offset tried."""
    if given is not None and len(given) != len(runs):
        raise InputError(f"give the windows of each run: {len(runs)} run(s), windows for {len(given)}")
    out = _Windows([], [], [], [], [], [], [], "given" if spec is None else str(spec))
    for k, (log, truth, run) in enumerate(zip(runs, truths, with_truth, strict=True)):
        t = np.asarray(log.t, dtype=float)
        if spec is not None:
            edges = _window_edges(log, robot, run, spec)
        else:
            assert given is not None
            edges = _given_edges(log, given[k], k)
        taken = np.zeros(run.t.size, dtype=bool)
        few = still = 0
        for j, (a, b) in enumerate(edges):
            last = j == len(edges) - 1 or edges[j + 1][0] > b
            inside = (run.t >= a) & ((run.t <= b) if last else (run.t < b)) & ~taken
            taken |= inside
            if np.count_nonzero(inside) < MIN_WINDOW_FIXES:
                few += 1
                continue
            if not truth_spreads(run.xy[inside], truth):
                still += 1
                continue
            i0 = max(int(np.searchsorted(t, a - margin, side="right")) - 1, 0)
            i1 = min(int(np.searchsorted(t, b + margin, side="left")), t.size - 1)
            piece = log.rows(i0, i1 + 1)
            into = f"{a - t[0]:.4g}..{b - t[0]:.4g} s into the log"
            out.logs.append(replace(piece, source=f"{log.source}, window {j + 1} of {len(edges)} ({into})"))
            out.runs.append(_Run(np.asarray(piece.t, dtype=float), run.xy[inside], run.t[inside], 0, 0,
                                 margin, None if run.theta is None else run.theta[inside]))
            out.min_spread.append(_min_spread(truth))
        out.cut.append(len(edges))
        out.few.append(few)
        out.still.append(still)
        out.between.append(int(np.count_nonzero(~taken)))
    if not out.runs:
        fewest = f"fewer than {MIN_WINDOW_FIXES} fixes"
        raise InputError(f"no window to calibrate from: of {sum(out.cut)} window(s) ({out.length}), "
                         f"{sum(out.still)} hold truth that does not spread (standing or turning on the "
                         f"spot) and {sum(out.few)} hold {fewest}; check the truth's clock, or give longer "
                         "windows",
                         source=runs[0].source if len(runs) == 1 else None)
    return out


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
    window: WindowSpec | str | None = None,
    windows: Sequence[Sequence[tuple[float, float]]] | None = None,
    heading_weight: float = 0.0,
) -> ExactCalibration:
    """Fit a robot's systematic parameters to truth positions on the truth's own clock.

    Parameters
    ----------
    runs : sequence of OdometryLog
        The logs (their own ground truth, if any, is not used).
    truths : sequence of Truth
        One per run (:class:`odomkit.truth.Truth`; its heading, if any, is compared only with
        ``heading_weight``).
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        Nominal parameters, the starting point: diff (c_left, c_right, c_wheel_base),
        tricycle (c_scale, steering_offset, wheel_to_axle), unicycle (c_scale,
        yaw_rate_bias, yaw_rate_scale), gyro (m_per_tick, held where no log has ticks;
        gyro_bias, gyro_scale), car (c_scale,
        steering_offset, wheel_base).
    fixed : collection of str
        Parameter names held at the robot's values (``calibrate --fix``): not fitted, standard
        error 0, named in the result's ``held`` and a note. An unknown name is a ModelError
        naming the parameters.
    min_first_fixes : int
        Fewest fixes per run in the first stage of the growing horizon.
    method : {"exact", "midpoint", "euler"}
    fit_time_offset : bool
        Fit the truth's clock offset δ [s] too, one for all runs (a fix stamped t is the pose
        at log time t − δ), within ±:func:`clock_range` (:data:`MAX_TIME_OFFSET`, or a quarter
        of the shortest run); fixes within that of either
        end of a log are left out.
    steering_cubic : bool
        A car's ``steering_cubic`` [rad⁻²] is fitted too, as a fourth parameter (a steering
        ratio that varies with the angle; only large steering angles identify it).
    window : WindowSpec or str, optional
        Cut each run into consecutive windows of this length (``"60s"``: seconds, ``"20m"``:
        metres of the odometry's travel with the robot's values; :func:`odomkit.windows.parse_window`),
        cut as ``evaluate --window`` cuts them, the tail shorter than a window joined to the last
        one. Each window is fitted from a start pose of its own (three nuisance parameters per
        window), the robot's parameters and the clock offset shared by all: a long run whose
        dead-reckoned heading wanders (metres of drift) biases a fit of the whole run, which can
        shrink the path to shorten the residuals, and windows short beside the drift do not. A
        window with fewer than :data:`MIN_WINDOW_FIXES` fixes, or whose fixes do not spread
        three times the truth's σ (at least 1 cm), is left out and counted (an error if none
        remains); the windows are the clusters of ``std_errors_between_runs``.
    windows : sequence (one per run) of sequences of (start, end) [s], optional
        The windows given instead, as log times (in order, not overlapping, inside the log);
        fixes stamped between them are not compared.
    heading_weight : float
        W [m/rad] ≥ 0 (``--heading-weight``). W > 0 compares the truth's heading too: each fix
        adds W·wrap(θ(t) + θ₀ − θ_truth(t)) [m] beside its position residuals, in runs and in
        windows alike (every truth must have a heading: an InputError names one without).
        The default 0 compares positions only, as before.

    Returns
    -------
    ExactCalibration
        ``source = "positions"``; ``values``, ``std_errors``, ``cov`` of all the robot's
        parameters (a fixed one has zero variance); ``time_offset`` and
        ``time_offset_std_error`` [s] when fitted (and ``time_offset_std_error_between_runs``
        from the runs' or windows' spread); ``notes`` list the stages and each run's
        fitted start pose (with windows: each run's windows fitted and left out);
        ``n_windows``, ``windows_left_out`` and ``window`` with windows. With
        ``heading_weight``, ``residual_variance``, ``n_residuals`` and the standard errors
        are of every residual, the weighted headings [m] with the positions (as
        :func:`~odomkit.calibrate.exact.calibrate_exact`'s are), and a note gives the two
        apart; the drift checks hold the position residuals alone against the truth's noise.
    """
    if len(runs) < 1:
        raise InputError("calibration needs at least one run")
    if not isinstance(robot, CALIBRATED_ROBOTS):
        raise ModelError(f"calibration from truth positions supports DiffDrive, Tricycle, Car, Unicycle "
                         f"and GyroOdometry robots, got {type(robot).__name__}")
    min_first_fixes = validate.positive_int(min_first_fixes, "min_first_fixes")
    heading_weight = validate.non_negative(heading_weight, "heading_weight", unit="m/rad", error=InputError)
    if heading_weight > 0:
        for truth in truths:
            if truth.theta is None:
                raise InputError("the truth has positions only, no heading to compare (the heading weight "
                                 f"{heading_weight:g} m/rad needs a truth with a heading column: TUM, text "
                                 "t,x,y,theta, a motion capture); leave out the heading weight",
                                 source=truth.source)
    if window is not None and windows is not None:
        raise InputError("give window (a length) or windows (the (start, end) times), not both")
    spec = parse_window(window) if isinstance(window, str) else window
    if spec is not None and not isinstance(spec, WindowSpec):
        raise InputError(f"window must be a length such as \"60s\" or \"20m\" (or a WindowSpec), "
                         f"got {window!r}")
    model = calibration_model(robot, runs, steering_cubic=steering_cubic)
    unknown = sorted(set(fixed) - set(model.names))
    if unknown:
        raise ModelError(f"fixed names {', '.join(unknown)}; the parameters are {', '.join(model.names)}")
    notes: list[str] = [f"{name} held at the robot file's value: {why}"
                        for name, why in model.unobservable.items() if name not in fixed]
    held = tuple(name for name in model.names if name in set(fixed))  # asked (--fix), in the model's order
    notes += [held_note(name, float(model.p0[k])) for k, name in enumerate(model.names) if name in held]
    fixed = set(fixed) | set(model.unobservable)
    free = np.array([k for k, n in enumerate(model.names) if n not in fixed], dtype=np.intp)
    margin = clock_range(runs) if fit_time_offset else 0.0
    with_truth = _runs_with_truth(runs, truths, margin)
    cut = None
    fitted_logs, fitted_runs, min_spread = list(runs), with_truth, [_min_spread(t) for t in truths]
    if spec is not None or windows is not None:
        cut = _cut_windows(runs, truths, with_truth, robot, spec, windows, margin)
        fitted_logs, fitted_runs, min_spread = cut.logs, cut.runs, cut.min_spread
        model = calibration_model(robot, fitted_logs, steering_cubic=steering_cubic)
    problem = _Problem(model, fitted_runs, fitted_logs, free, method, fit_time_offset, heading_weight)

    # A window holds fewer fixes than a run: its first stage needs no more than it has.
    first_fixes = min_first_fixes if cut is None else min(min_first_fixes, min(r.t.size for r in fitted_runs))
    sources = [log.source for log in fitted_logs]
    horizon = _first_horizon(problem, first_fixes, min_spread, sources)
    g = np.concatenate([model.p0[free], [0.0] if fit_time_offset else []])
    n_global, n_starts = g.size, 3 * len(fitted_runs)
    # Whole runs: the parameters and the start poses fitted together, from each run's SE(2)
    # alignment over the first horizon. Windows: the parameters alone, each window from its
    # best start pose for them (_Problem.reduced): no dense Jacobian of 3 columns per window.
    joint = cut is None
    starts = problem.reduced(g)[2] if joint else None
    lower, upper = _bounds(model, free, len(fitted_runs) if joint else 0, fit_time_offset, margin)
    while True:
        n_res = sum(problem.per_fix * int(np.count_nonzero(problem.used(i))) for i in range(len(fitted_runs)))
        if n_res > n_global + n_starts and (joint or n_global):
            # Bounded (trust-region reflective): over a short first horizon a parameter the
            # path does not yet excite (the wheel base before the first turn) is free to run
            # off to ±1e185 under plain Levenberg–Marquardt, and no later stage brings it back.
            if joint:
                assert starts is not None
                sol = least_squares(lambda x: problem.residuals_and_jacobian(x)[0],
                                    np.concatenate([g, starts.reshape(-1)]),
                                    jac=lambda x: problem.residuals_and_jacobian(x)[1], method="trf",
                                    bounds=(lower, upper), x_scale="jac", xtol=1e-12, ftol=1e-12,
                                    gtol=1e-12, max_nfev=200)
            else:
                sol = least_squares(lambda x: problem.reduced(x)[0], g,
                                    jac=lambda x: problem.reduced(x)[1], method="trf",
                                    bounds=(lower, upper), x_scale="jac", xtol=1e-12, ftol=1e-12,
                                    gtol=1e-12, max_nfev=200)
            if not np.all(np.isfinite(sol.x)):
                raise ModelError("the calibration diverged to non-finite parameters; check the "
                                 "truth's clock and the robot file's units")
            g = sol.x[:n_global]
            if joint:
                starts = sol.x[n_global:].reshape(-1, 3)
            notes.append(f"horizon {horizon:.4g} of each {'run' if joint else 'window'}: "
                         f"{n_res // problem.per_fix} fixes, "
                         f"residual rms {float(np.sqrt(np.mean(sol.fun**2))):.4g} m")
        if horizon >= 1.0:
            break
        horizon = min(1.0, 2 * horizon)
        problem.horizon = horizon
    # The shared parameters' rows with each run's (window's) start pose marginalised.
    res, jac, starts, sizes = problem.reduced(g, starts)
    # The drift checks hold the positions alone against the truth's noise (the same arrays
    # where the heading is not compared).
    res_xy, sizes_xy = problem.positions(res, sizes)
    # One window is one run from one start pose: judged as a whole run is.
    single = joint or len(fitted_runs) == 1
    fitted_xy = [r.xy for r in fitted_runs]
    biased = drift_bias(sources, res_xy, sizes_xy, fitted_xy, truths) if single else None
    names = [*(model.names[k] for k in free), *(["truth time offset"] if fit_time_offset else [])]
    at_bound = [name for j, name in enumerate(names)
                if np.isclose(g[j], lower[j], rtol=1e-6, atol=0.0)
                or np.isclose(g[j], upper[j], rtol=1e-6, atol=0.0)]
    if at_bound:
        raise ModelError(f"the calibration ran to the edge of the plausible range for {', '.join(at_bound)} ("
                         + _edge_said(model, free, g, lower, upper, at_bound)
                         + ("" if biased is None else
                            "; " + str(drift_bias(sources, res_xy, sizes_xy, fitted_xy, truths, short=True))))
    dof = res.size - g.size - n_starts
    if dof <= 0:
        kind = "position residuals" if problem.per_fix == 2 else "residuals"
        raise InputError(f"{res.size} {kind} cannot determine {g.size + n_starts} parameters "
                         "(the robot's and each run's start pose): give longer runs or more truth")
    var_res = float(res @ res) / dof
    # The positions' variance per axis, for the truth's noise: their share of the degrees of freedom.
    var_xy = var_res if res_xy is res else float(res_xy @ res_xy) / (dof * res_xy.size / res.size)
    warn_if_drifting(var_xy, res_xy.size, truths, windowed=not single)
    if biased is not None:
        warnings.warn(biased, UserWarning, stacklevel=2)
    elif cut is not None and (drifting := windows_drift(res_xy, sizes_xy, fitted_xy, truths, cut.length)):
        warnings.warn(drifting, UserWarning, stacklevel=2)
    # The shared block of σ̂²(JᵀJ)⁻¹ with the start poses marginalised: the reduced Jacobian's.
    cov_q = var_res * np.linalg.pinv(jac.T @ jac)
    p, delta, _ = problem.split(g)
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
    for k, (log, run) in enumerate(zip(runs, with_truth, strict=True)):
        left = ([f"{run.outside} outside the log's span"] if run.outside else []) + (
            [f"{run.near_ends} within {run.margin:.3g} s of its ends (where a fitted clock offset could "
             "move them out)"] if run.near_ends else [])
        if cut is not None and cut.between[k]:
            left.append(f"{cut.between[k]} between the windows given")
        left_out = f"; truth fixes left out: {' and '.join(left)}" if left else ""
        if cut is None:
            start = starts[k]
            notes.append(f"{log.source}: start pose fitted at ({start[0]:.4g} m, {start[1]:.4g} m, "
                         f"{start[2]:.4g} rad){left_out}")
            continue
        out = cut.few[k] + cut.still[k]
        why = " and ".join(
            [f"{cut.still[k]} whose truth does not spread {_min_spread(truths[k]):.3g} m (standing or "
             "turning on the spot)"] * bool(cut.still[k])
            + [f"{cut.few[k]} with fewer than {MIN_WINDOW_FIXES} truth fixes"] * bool(cut.few[k]))
        notes.append(f"{log.source}: {cut.cut[k] - out} of {cut.cut[k]} window(s) ({cut.length}) fitted, "
                     "each from its own start pose" + (f"; left out: {why}" if out else "") + left_out)
    if heading_weight > 0:
        heading = res.reshape(-1, 3)[:, 2] / heading_weight  # [rad]
        rms_xy, rms_heading = float(np.sqrt(np.mean(res_xy**2))), float(np.sqrt(np.mean(heading**2)))
        notes.append(f"the truth's heading compared at every fix, weighted {heading_weight:g} m/rad: "
                     f"residual RMS {rms_xy:.4g} m in position, {rms_heading:.4g} rad in heading (mean "
                     f"{float(np.mean(heading)):+.4g} rad); the residual RMS and the standard errors pool "
                     "both, a heading residual as weight × rad [m]")
    elif any(truth.theta is not None for truth in truths):
        # The fit is on positions so that any truth, GPS included, enters it alike; a truth
        # that measures heading still pins the start heading better than positions alone.
        notes.append("the truth's heading is not compared (every fix is compared as a position; "
                     "heading_weight, --heading-weight, compares it too); it is used where the track starts "
                     "from the truth (evaluate, track)")
    between = offset_between = None
    clusters = "windows" if cut is not None else "runs"
    if len(fitted_runs) > 1:
        # Each run's (window's) rows are already orthogonal to its own start pose (the
        # reduced Jacobian: Frisch–Waugh–Lovell), so the runs' spread is taken there; the
        # clock offset, shared too, is the last row of T.
        n_names = len(model.names)
        T = np.zeros((n_names + int(fit_time_offset), problem.n_global))
        T[problem.free, np.arange(problem.free.size)] = 1.0
        if fit_time_offset:
            T[n_names, free.size] = 1.0
        spread_se, _ = between_runs(jac, res, sizes, T)
        if spread_se is not None:
            between = spread_se[:n_names]
            offset_between = float(spread_se[n_names]) if fit_time_offset else None
        if between is None:
            notes.append(f"no standard errors between {clusters}: a {clusters[:-1]}'s own start pose leaves "
                         "a parameter undetermined without it")
        elif scattered := between_runs_warning(model.names, p, std, between, len(fitted_runs), clusters):
            warnings.warn(scattered, UserWarning, stacklevel=2)
    if fit_time_offset:
        from odomkit.calibrate.check_ratios import speed_clock_note

        own_se = float(np.sqrt(max(cov_q[free.size, free.size], 0.0)))
        se = offset_between if offset_between is not None else own_se
        if clock := speed_clock_note(delta, se, runs, robot, truths):
            warnings.warn(clock, UserWarning, stacklevel=2)
    travelled = [float(np.sum(np.abs(model.steps(p, i)[0]))) for i in range(len(fitted_runs))]
    spread = [_spread(r.xy) for r in fitted_runs]
    sensitivity = float(np.mean([s / d if d > 0 else 0.0 for s, d in zip(spread, travelled, strict=True)]))
    return ExactCalibration(
        robot=model.make_robot(p), names=model.names, values=p, std_errors=std, cov=cov, corr=corr,
        residual_variance=var_res, n_residuals=int(res.size), n_runs=len(runs), source="positions",
        scale_fixed=bool({"c_scale", "m_per_tick"} & fixed) or {"c_left", "c_right"} <= fixed,
        scale_sensitivity=sensitivity, notes=tuple(notes),
        time_offset=delta if fit_time_offset else None,
        time_offset_std_error=(float(np.sqrt(max(cov_q[free.size, free.size], 0.0))) if fit_time_offset
                               else None),
        time_offset_std_error_between_runs=offset_between,
        std_errors_between_runs=between,
        n_windows=len(fitted_runs) if cut is not None else None,
        windows_left_out=sum(cut.few) + sum(cut.still) if cut is not None else 0,
        window=cut.length if cut is not None else None,
        drift_dominated=biased is not None,
        held=held,
    )


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
