"""The identifiability check before calibrating (part of ``odomkit check``): how well each
calibration parameter of every robot ``odomkit calibrate`` calibrates is pinned by a log's
motion.

:func:`check_identifiable` takes the calibration model's own Jacobian
(:mod:`odomkit.calibrate.residuals`) at the robot's values, finds the part of each
parameter's effect on the track that no other parameter can mimic, and turns it into a
standard error with the position noise :func:`identifiability_sigma` assumes (an
:class:`AssumedSigma`, which every message states with where it came from: the figure is a
lower bound, the odometry's drift being correlated along the run); each parameter's label,
thresholds and advice are kept here with it.
:func:`odomkit.calibrate.check.check_log` runs it with the other checks.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.check_finding import Finding
from odomkit.log import OdometryLog
from odomkit.robot import Robot
from odomkit.truth import Truth, scatter_sigma

if TYPE_CHECKING:
    from odomkit.calibrate.residuals import CalibratedRobot

__all__ = ["AssumedSigma", "check_identifiable", "drift_sigma", "identifiability_sigma"]

# Position noise assumed for the identifiability figures when the truth states none [m]:
# motion-capture noise plus the odometry's own random drift between samples.
_DEFAULT_SIGMA = 0.005


@dataclass(frozen=True)
class _Parameter:
    """How one calibration parameter's standard error is shown and judged.

    ``kind``: ``ratio`` a dimensionless correction near 1 (its standard error, shown in %),
    ``relative`` a length (its standard error over its value, in %), ``angle`` [rad],
    ``rate`` [rad/s]; ``_LIMITS`` gives each kind's thresholds. ``name``: the calibration
    parameter it is, as ``calibrate --fix`` names it (None for a differential drive's E_s
    and E_d, each a combination of both wheels' scales).
    """

    label: str
    kind: Literal["ratio", "relative", "angle", "rate"]
    advice: str
    name: str | None = None


# (unit shown, weak above, not identifiable above) of each kind of parameter. Scales and
# lengths: 0.2 % and 1 % of their value. A steering offset: 0.002 and 0.01 rad, the same
# fractions of a 1 rad steering lock. A yaw-rate bias: 2e-4 and 1e-3 rad/s, the heading a
# 0.2 % or 1 % yaw-rate scale error loses over a full turn (2π rad) lost to the bias in a
# minute (1e-3 rad/s is 0.06 rad, 3.4°, a minute; 2e-4 rad/s, about 40 °/h, is of the order
# of a low-cost MEMS gyro's own bias drift, which no calibration pins more closely).
_LIMITS: dict[str, tuple[str, float, float]] = {
    "ratio": ("%", 0.002, 0.01),
    "relative": ("%", 0.002, 0.01),
    "angle": ("rad", 0.002, 0.01),
    "rate": ("rad/s", 2e-4, 1e-3),
}

_SCALE_ADVICE = "drive longer straight runs away from the start (a closed loop's end says nothing of scale)"
_BIAS_ADVICE = ("drive straight stretches (or stand still) between turns, or turn both ways: a bias acts "
                "with time, and on a steady turn one way, where turning grows just as time does, a yaw-rate "
                "scale error mimics it")
_YAW_SCALE_ADVICE = ("turn more, both ways: spins in place or a square each way (a yaw-rate scale error acts "
                     "only while turning)")

# The calibration model's parameters (odomkit.calibrate.residuals), in its order; a
# differential drive's (c_left, c_right) recombined as (E_s, E_d).
_PARAMETERS: dict[str, tuple[_Parameter, _Parameter, _Parameter]] = {
    "diff": (_Parameter("wheel scale E_s", "ratio", _SCALE_ADVICE),
             _Parameter("wheel-diameter ratio E_d", "ratio", "drive straight runs, and turns both ways"),
             _Parameter("wheel base E_b", "ratio", "turn more: spins in place or a square driven both ways",
                        "c_wheel_base")),
    "tricycle": (_Parameter("traction scale c_scale", "ratio",
                            "drive longer straight runs away from the start", "c_scale"),
                 _Parameter("steering offset", "angle", "drive straight and gentle curves both ways",
                            "steering_offset"),
                 _Parameter("wheel-to-axle distance", "relative", "drive tight curves both ways",
                            "wheel_to_axle")),
    "car": (_Parameter("wheel scale c_scale", "ratio", _SCALE_ADVICE, "c_scale"),
            _Parameter("steering offset", "angle", "drive straight and gentle curves both ways",
                       "steering_offset"),
            _Parameter("wheel base L", "relative", "drive tight curves both ways", "wheel_base")),
    "unicycle": (_Parameter("speed scale c_scale", "ratio", _SCALE_ADVICE, "c_scale"),
                 _Parameter("yaw-rate bias", "rate", _BIAS_ADVICE, "yaw_rate_bias"),
                 _Parameter("yaw-rate scale", "ratio", _YAW_SCALE_ADVICE, "yaw_rate_scale")),
    "gyro": (_Parameter("metres per tick m_per_tick", "relative", _SCALE_ADVICE, "m_per_tick"),
             _Parameter("gyro bias", "rate", _BIAS_ADVICE, "gyro_bias"),
             _Parameter("gyro scale", "ratio", _YAW_SCALE_ADVICE, "gyro_scale")),
}


def _plausible_reach(kind: str) -> float:
    """How large a parameter's standard error may be, in the units its figure is shown in,
    before ±1 standard error covers the whole range calibrate fits it in
    (:func:`odomkit.calibrate.positions.scale_range` and
    :data:`~odomkit.calibrate.positions.MAX_STEERING_OFFSET`, the fit's bounds): a scale or a
    length may lie from half to twice the robot file's value, so its figure (relative to that
    value) reaches 100 %; a steering offset ±0.5 rad about it. A bias has no range (inf)."""
    from odomkit.calibrate.positions import MAX_STEERING_OFFSET, scale_range

    if kind in ("ratio", "relative"):
        low, high = scale_range(1.0)
        return max(1.0 - low, high - 1.0)
    if kind == "angle":
        return MAX_STEERING_OFFSET
    return math.inf


def _range_text(kind: str) -> str:
    """The range :func:`_plausible_reach` covers, as a message says it."""
    from odomkit.calibrate.positions import MAX_STEERING_OFFSET

    if kind == "angle":
        return f"the robot file's value ±{MAX_STEERING_OFFSET:g} rad"
    return "half to twice the robot file's value"


def _design(log: OdometryLog, robot: CalibratedRobot
            ) -> tuple[NDArray[np.float64], list[tuple[_Parameter, float]], dict[str, str],
                       NDArray[np.intp], NDArray[np.float64]]:
    """The sensitivity of the positions to the calibration parameters, (2n, P).

    The calibration model's own Jacobian (:func:`odomkit.calibrate.residuals.calibration_model`,
    the one :func:`~odomkit.calibrate.exact.calibrate_exact` fits with) at the robot's
    values, integrated from a known start pose; x and y (as the default calibration fits) of
    rows k, 2k, ... with k rows about 1 s, interleaved. A differential drive's columns of
    (c_left, c_right) become E_s (both wheels) and E_d (right against left). Returned with
    the parameters the columns stand for, each with the value its standard error is
    relative to (a length's own value, else 1), {label: why} of the parameters the
    log's channels do not use (left out: the calibration holds them), the rows used (n,) and
    the nominal track's positions there (n, 2) [m].
    """
    from odomkit.calibrate.residuals import (
        DiffCalibrationModel,
        calibration_model,
        integrate_with_sensitivity,
    )

    model = calibration_model(robot, [log])
    dd, dth, ddd, ddt = model.steps(model.p0, 0)
    poses, dposes = integrate_with_sensitivity(dd, dth, ddd, ddt, np.zeros(3))
    dt = np.diff(log.t)
    period = float(np.median(dt[dt > 0])) if np.any(dt > 0) else 1.0
    rows = np.arange(0, len(log), max(1, int(round(1.0 / period))))[1:]
    J = dposes[rows, :2, :]  # (n, 2, 3)
    if isinstance(model, DiffCalibrationModel):
        J = np.stack([J[..., 0] + J[..., 1], 0.5 * (J[..., 1] - J[..., 0]), J[..., 2]], axis=-1)
    params = _PARAMETERS[robot.type_name]
    keep, unused = [], {}
    for k, (name, par) in enumerate(zip(model.names, params, strict=True)):
        if name in model.unobservable:
            unused[par.label] = model.unobservable[name]
        else:
            keep.append(k)
    per = [(params[k], float(model.p0[k]) if params[k].kind == "relative" else 1.0) for k in keep]
    # C order: the figures of a degenerate log are round-off, which depends on the layout.
    return (np.ascontiguousarray(J[..., keep]).reshape(-1, len(keep)), per, unused, rows,
            poses[rows, :2])


#: Windows of a run fitted alone for the spread of their parameters.
_WINDOWS = 4
#: Where an assumed σ came from, as the messages say it.
_SOURCES = {
    "stated": "the truth's --truth-sigma",
    "scatter": "the fixes' scatter",
    "default": "the default",
    "given": "as given",
    "drift": "the residuals of a quick fit to the truth",
    "windows": f"the spread of {_WINDOWS} windows' own fits to the truth",
}
#: The drift's σ replaces the truth's own where it is this many times larger.
_DRIFT_OVER_NOISE = 1.5
#: Gauss–Newton steps of the quick fit behind the drift's σ.
_FIT_STEPS = 8


@dataclass(frozen=True)
class AssumedSigma:
    """The position noise the identifiability figures assume, and where it came from.

    ``value`` [m per axis]; ``source``: ``"stated"`` the truth's own σ (``--truth-sigma``),
    ``"scatter"`` its fixes' scatter about a smooth path (:func:`odomkit.truth.scatter_sigma`),
    ``"default"`` the 5 mm default (no truth, or one that states no σ and scatters less),
    ``"given"`` a number the caller passed, ``"drift"`` the odometry's drift against the
    truth (:func:`identifiability_sigma` with a log: ``rms`` [m] the residuals' RMS per axis
    of a quick fit to the truth, ``correlation`` [s] the time over which they are
    correlated, ``value`` = ``rms`` · √(``correlation`` / 1 s)); ``"windows"`` the spread of
    the fits of :data:`_WINDOWS` windows of the run (``windows``: the σ [m per axis] per free
    parameter that matches it, empty where it was not measured). ``fitted`` windows gave that
    spread; ``still`` were left out, their truth or odometry not spreading (a robot standing
    or turning on the spot: no start pose to fit).
    """

    value: float
    source: Literal["stated", "scatter", "default", "given", "drift", "windows"]
    rms: float = math.nan
    correlation: float = math.nan
    windows: tuple[float, ...] = ()
    fitted: int = 0
    still: int = 0

    def for_parameter(self, k: int) -> AssumedSigma:
        """The σ of the ``k``-th free parameter: the spread of the windows' fits where it is
        larger (``windows``), else this one."""
        if k < len(self.windows) and self.windows[k] > self.value:
            return AssumedSigma(self.windows[k], "windows", self.rms, self.correlation, (), self.fitted,
                                self.still)
        return self

    @property
    def lower_bound(self) -> bool:
        """Whether the figures at this σ are lower bounds (every σ but the drift's, which
        counts the odometry's correlated drift)."""
        return self.source not in ("drift", "windows")

    def describe(self) -> str:
        """``"σ = 26.5 mm per axis (the fixes' scatter)"``: the σ and its source."""
        def shown(x: float) -> str:
            return f"{1000 * x:.3g} mm" if x < 1 else f"{x:.3g} m"
        if self.source == "windows":  # an equivalent σ of metres would only puzzle
            return (f"the spread of {self.fitted or _WINDOWS} windows' own fits to the truth, each from its "
                    "own start pose" + (f" ({self.still} of {self.fitted + self.still} left out: standing "
                                        "or turning on the spot)" if self.still else ""))
        if self.source == "drift":
            return (f"σ = {shown(self.value)} per axis ({_SOURCES['drift']}: {shown(self.rms)} RMS, "
                    f"correlated over {self.correlation:.3g} s)")
        return f"σ = {shown(self.value)} per axis ({_SOURCES[self.source]})"


def identifiability_sigma(truth: Truth | None, log: OdometryLog | None = None, robot: Robot | None = None,
                          max_gap: float | None = 0.5, fixed: Collection[str] = ()) -> AssumedSigma:
    """The position noise the identifiability figures assume: the truth's stated σ, else the
    larger of the default and the fixes' own scatter (a 1 m GPS must not be taken for 5 mm),
    else (no truth) the default.

    With the ``log`` and its ``robot`` as well, the odometry's drift against the truth where
    it is :data:`_DRIFT_OVER_NOISE` times larger (:func:`drift_sigma`): the figures at the
    truth's own noise treat every second's position error as independent, while the
    odometry's drift is correlated along the run, and came out 1000–10000 times below the
    spread of calibrations of a drive's two halves (TUC SLAM and smartLoc studies).
    ``fixed`` names the calibration parameters held at the robot's values (as ``calibrate
    --fix`` holds them; :func:`drift_sigma`): the windows' spread is then that of the
    others' fits, in their order.
    """
    if truth is None:
        return AssumedSigma(_DEFAULT_SIGMA, "default")
    if truth.sigma > 0:
        base = AssumedSigma(float(truth.sigma), "stated")
    else:
        scatter = scatter_sigma(truth) or 0.0
        base = AssumedSigma(scatter, "scatter") if scatter > _DEFAULT_SIGMA else AssumedSigma(
            _DEFAULT_SIGMA, "default")
    if log is None or robot is None:
        return base
    drift = drift_sigma(log, robot, truth, max_gap, fixed)
    if drift is not None and drift.value > _DRIFT_OVER_NOISE * base.value:
        return drift
    return base


def drift_sigma(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None = 0.5,
                fixed: Collection[str] = ()) -> AssumedSigma | None:
    """The position noise, correlated drift included, of the odometry against the truth.

    A quick trajectory fit of the kind the identifiability figures describe: the nominal
    track (about one position a second, as :func:`check_identifiable` uses) turned and
    shifted onto the truth (Umeyama), then the calibration parameters and the start pose
    fitted to what is left by up to :data:`_FIT_STEPS` Gauss–Newton steps, each kept only
    where it lowers the misfit. Its residuals' RMS per axis, σ, would be the figures'
    σ for independent errors; they are correlated over τ (the integrated autocorrelation
    time of each axis' residual series, its positive lags summed, averaged over the axes), so
    the σ returned is σ·√(τ / 1 s): a least-squares fit's standard error to first order for
    errors correlated over τ (n/τ independent ones). None for a robot ``calibrate`` does not
    calibrate, or fewer than 10 positions with truth. The parameters ``fixed`` names
    (``calibrate --fix``) are held at the robot's values in every fit: the windows' σ is
    then one per other parameter, in their order.
    """
    from odomkit.calibrate.positions import truth_spreads
    from odomkit.calibrate.residuals import CALIBRATED_ROBOTS, calibration_model, integrate_with_sensitivity
    from odomkit.errors import ModelError
    from odomkit.evaluate import umeyama_se2
    from odomkit.truth import truth_at

    if not isinstance(robot, CALIBRATED_ROBOTS):
        return None
    with np.errstate(all="ignore"):
        _, _, _, rows, _ = _design(log, robot)
        samples = truth_at(truth, log.t[rows], max_gap)
        if np.count_nonzero(samples.valid) < 10:
            return None
        model = calibration_model(robot, [log])
        free = [k for k, name in enumerate(model.names)
                if name not in model.unobservable and name not in fixed]
        if not free:
            return None
        fixes = samples.poses[samples.valid, :2]

        def misfit(p: NDArray[np.float64], keep: NDArray[np.bool_] | None = None
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
            """The residuals (2n,) of the track at ``p`` turned onto the truth, and their
            design (2n, P + 3): the free parameters and the start pose (over the positions
            ``keep`` only, where given)."""
            dd, dth, ddd, ddt = model.steps(p, 0)
            poses, dposes = integrate_with_sensitivity(dd, dth, ddd, ddt, np.zeros(3))
            odo = poses[rows, :2][samples.valid]
            J = dposes[rows, :2, :][samples.valid][..., free]
            target = fixes
            if keep is not None:
                odo, J, target = odo[keep], J[keep], fixes[keep]
            if not (np.isfinite(odo).all() and np.isfinite(J).all()):
                return None
            phi, shift = umeyama_se2(odo, target)
            c, s_ = math.cos(phi), math.sin(phi)
            turn = np.array([[c, -s_], [s_, c]])
            placed = odo @ turn.T
            n = odo.shape[0]
            start = np.zeros((n, 2, 3))
            start[:, 0, 0] = start[:, 1, 1] = 1.0
            start[:, :, 2] = np.column_stack((-placed[:, 1], placed[:, 0]))  # ∂(R(φ)·p)/∂φ
            D = np.concatenate((np.einsum("ij,njp->nip", turn, J), start), axis=2).reshape(2 * n, -1)
            return (target - placed - shift).reshape(-1), D

        def whole(p: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
            """:func:`misfit` over the whole run; None where its track does not spread (a
            robot that never drives: no rotation aligns it to the truth)."""
            try:
                return misfit(p)
            except ModelError:
                return None

        # Gauss–Newton from the robot's values, each step kept only where it lowers the misfit
        # (halved otherwise): a long drive's nominal track is far from the truth, and one
        # linear step from it leaves metres that a fit does not.
        p = np.array(model.p0, dtype=float)
        got = whole(p)
        if got is None:
            return None
        error, D = got
        for _ in range(_FIT_STEPS):
            step, *_ = np.linalg.lstsq(D, error, rcond=None)
            for _ in range(10):
                trial = p.copy()
                trial[free] += step[: len(free)]
                again = whole(trial)
                if again is not None and again[0] @ again[0] < error @ error:
                    break
                step = 0.5 * step
            else:
                break
            done = error @ error - again[0] @ again[0] < 1e-6 * (error @ error)
            p, (error, D) = trial, again
            if done:
                break
        step, *_ = np.linalg.lstsq(D, error, rcond=None)
        n = error.size // 2
        resid = (error - D @ step).reshape(n, 2)
        best = p.copy()
        best[free] += step[: len(free)]
        batch, fitted, still = _between_windows(misfit, best, free, n, float(np.sqrt(np.mean(resid**2))),
                                                D[:, : len(free)],
                                                lambda keep: truth_spreads(fixes[keep], truth))
        dof = 2 * n - D.shape[1]
        if dof <= 0:
            return None
        rms = float(np.sqrt(np.sum(resid**2) / dof))
        if not math.isfinite(rms) or rms == 0:
            return None
        period = float(np.median(np.diff(log.t[rows])))
        taus = []
        for axis in range(2):
            r = resid[:, axis] - np.mean(resid[:, axis])
            var = float(r @ r)
            if var <= 0:
                continue
            tau = 1.0
            for lag in range(1, n // 2):
                rho = float(r[:-lag] @ r[lag:]) / var
                if rho <= 0:
                    break
                tau += 2.0 * rho
            taus.append(tau)
        tau_rows = float(np.mean(taus)) if taus else 1.0
        value = rms * math.sqrt(tau_rows)
        # The drift of a heading's random walk grows along the run: its correlation time
        # understates it; the spread of the windows' own fits does not.
        windows: tuple[float, ...] = ()
        if batch is not None:
            if robot.type_name == "diff" and not {"c_left", "c_right"} & set(fixed):
                batch[:2] = [max(batch[:2])] * 2  # (c_left, c_right) shown as (E_s, E_d): either's
            windows = tuple(max(value, x) for x in batch)
    return AssumedSigma(value, "drift", rms, tau_rows * period, windows, fitted, still)


def _between_windows(misfit: Callable[..., Any], start: NDArray[np.float64], free: list[int], n: int,
                     rms: float, design: NDArray[np.float64], spreads: Callable[[NDArray[np.bool_]], bool]
                     ) -> tuple[list[float] | None, int, int]:
    """Per free parameter, the σ [m per axis] at which its figure (σ over the part of its
    column, in ``design`` (2n, P), that the others cannot mimic) matches the spread of its fits
    to :data:`_WINDOWS` consecutive windows of the run, each fitted alone from its own start
    pose; ``rms`` (the whole fit's residuals') where that spread is no more than 1.5 times
    what each window's own fit claims at its residuals' RMS (the windows' own geometry, not
    drift: a window of an S-curve pins a steering offset far less than the whole curve does).
    None where a window's fit fails, or fewer than two windows are fitted.

    A window whose truth does not spread (``spreads(keep)`` False for its rows ``keep``: a
    robot standing or turning on the spot, :func:`odomkit.calibrate.positions.truth_spreads`)
    or whose odometry does not (no rotation aligns it to the truth) has no start pose to fit:
    it is left out and counted. Returned with the windows fitted and those left out.

    The spread is taken over windows^¼, not √windows: drift builds along a run (a heading's
    random walk), so the whole run pins a parameter little better than one window does
    (simulated unicycles with a gyro's white noise: the whole runs' fits spread 1.2-3.6x the
    windows' spread over √4; within a factor 3 of it over 4^¼)."""
    from odomkit.errors import ModelError

    # misfit(p, keep) is the residuals and design over the kept rows only.
    fits: list[NDArray[np.float64]] = []
    claimed: list[NDArray[np.float64]] = []
    still = 0
    edges = np.linspace(0, n, _WINDOWS + 1).astype(int)
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        keep = np.zeros(n, dtype=bool)
        keep[lo:hi] = True
        if not spreads(keep):
            still += 1
            continue
        p = start.copy()
        try:
            for _ in range(3):
                got = misfit(p, keep)
                if got is None:
                    return None, len(fits), still
                step, *_ = np.linalg.lstsq(got[1], got[0], rcond=None)
                p[free] += step[: len(free)]
        except ModelError:  # the odometry stands while the truth moves (a stuck encoder's finding)
            still += 1
            continue
        error, D = got
        dof = D.shape[0] - D.shape[1]
        if dof <= 0:
            return None, len(fits), still
        left = error - D @ step
        claimed.append(np.diag(float(left @ left) / dof * np.linalg.pinv(D.T @ D))[: len(free)])
        fits.append(p[free])
    if len(fits) < 2:
        return None, len(fits), still
    spread = np.std(np.array(fits), axis=0, ddof=1)
    own = np.sqrt(np.mean(np.array(claimed), axis=0))
    sigmas = []
    for i in range(len(free)):
        if not spread[i] > _DRIFT_OVER_NOISE * own[i]:
            sigmas.append(rms)
            continue
        others = np.delete(design, i, axis=1)
        coef, *_ = np.linalg.lstsq(others, design[:, i], rcond=None)
        unique = float(np.linalg.norm(design[:, i] - others @ coef))
        sigmas.append(float(spread[i] / len(fits)**0.25 * unique))
    return (sigmas if all(math.isfinite(x) for x in sigmas) else None), len(fits), still


def _unique(A: NDArray[np.float64], i: int) -> float:
    """‖r_i‖: the part of column ``i`` of ``A`` (2n, P) that the other columns cannot reproduce
    (the residual of its least-squares projection on them)."""
    others = np.delete(A, i, axis=1)
    coef, *_ = np.linalg.lstsq(others, A[:, i], rcond=None)
    return float(np.linalg.norm(A[:, i] - others @ coef))


def _standard_error(unique: float, sigma: float, value: float) -> float:
    """σ/‖r_i‖/value: a marginal standard error at σ per axis, relative to ``value`` (inf
    where the other columns mimic the parameter's wholly: ``unique`` 0)."""
    return math.inf if unique == 0 else sigma / unique / value


def _shown(par: _Parameter, se: float) -> str:
    """``±0.25 %`` or ``±3e-05 rad``: a standard error in its parameter's unit."""
    unit = _LIMITS[par.kind][0]
    return f"±{100 * se:.2g} %" if unit == "%" else f"±{se:.2g} {unit}"


def _pinning_fixes(A: NDArray[np.float64], params: list[tuple[_Parameter, float]], beyond: list[int],
                   assumed: AssumedSigma, held_sigma: Callable[[str], AssumedSigma] | None
                   ) -> list[tuple[str, str]]:
    """The parameters beyond their plausible range whose holding (``calibrate --fix NAME``)
    leaves every other one pinned inside its own, each with those others' standard errors
    (``"steering offset ±5e-06 rad, ..."``): its column left out of ``A``, each other's σ
    from ``held_sigma(NAME)`` (the windows refitted with it held) where given, else its own."""
    out = []
    for i in beyond:
        name = params[i][0].name
        if name is None or len(params) < 2:
            continue
        held = held_sigma(name) if held_sigma is not None else None
        reduced = np.delete(A, i, axis=1)
        rest = [j for j in range(len(params)) if j != i]
        said = []
        for k, j in enumerate(rest):
            par, value = params[j]
            sigma = (held.for_parameter(k) if held is not None else assumed.for_parameter(j)).value
            se = _standard_error(_unique(reduced, k), sigma, value)
            if not se <= _plausible_reach(par.kind):
                break
            said.append(f"{par.label} {_shown(par, se)}")
        else:
            out.append((name, ", ".join(said)))
    return out


def check_identifiable(log: OdometryLog, robot: Robot, sigma: float | AssumedSigma | None = None, *,
                       held_sigma: Callable[[str], AssumedSigma] | None = None) -> list[Finding]:
    """How well this log's motion pins each calibration parameter (trajectory fit).

    With J the sensitivity of the positions (about one a second) to the parameters, the
    part of parameter i's column that the others cannot reproduce, r_i (the residual of its
    least-squares projection on them), gives its standard error σ/‖r_i‖ for independent
    position errors of σ per axis (``sigma``, default 5 mm: the truth's noise and the
    odometry's own drift). That is the marginal standard error, σ·√((JᵀJ)⁻¹)ᵢᵢ, of a
    least-squares fit of every parameter at once to those positions from a known start
    pose: the fit :func:`~odomkit.calibrate.exact.calibrate_exact` makes with
    ``source="trajectory"``, ``heading_weight=0`` and ``fix_scale=False``, whose ``every``
    = k (the rows in a second) compares as many positions a second (the same ones for a
    log of one row a second). Position errors correlated from second to second, as the
    odometry's drift is, make the true scatter larger: the figure is a lower bound, and each
    message says so, with the σ it assumed and where that came from (``sigma``: an
    :class:`AssumedSigma`, from :func:`identifiability_sigma`; a number is taken as given;
    None is the default). A finding's ``value`` is the standard error alone.

    Parameters, and when a standard error counts as "weak" / "not identifiable": scales
    and lengths, relative, above 0.2 % / 1 %; a steering offset above 0.002 / 0.01 rad
    (the same fractions of a 1 rad steering lock); a yaw-rate or gyro bias above
    2e-4 / 1e-3 rad/s (the heading a 0.2 % / 1 % yaw-rate scale error loses over a full
    turn, lost in a minute). Differential drive: E_s (both wheels), E_d (their ratio), E_b
    (wheel base); tricycle: c_scale, steering offset, L (wheel to axle); car: c_scale,
    steering offset, L (wheel base); unicycle: c_scale, yaw-rate bias, yaw-rate scale;
    gyro: m_per_tick (only with a ``ticks`` channel), gyro bias, gyro scale. A bias acts
    with time and a yaw-rate scale with turning: straight driving pins a bias and not the
    scale, a steady turn one way (turning in step with time) neither. A compass robot is
    not calibrated, so not checked.

    A standard error so large that ±1 of it covers the whole range calibrate fits the
    parameter in (:func:`_plausible_reach`: half to twice the robot file's value for a scale
    or a length, ±:data:`~odomkit.calibrate.positions.MAX_STEERING_OFFSET` for a steering
    offset) is "not identifiable from this drive", whatever σ it rests on (a calibration
    runs it to the edge of that range, or anywhere in it): its advice names each ``calibrate
    --fix NAME`` that holds one such parameter at the robot file's value and leaves every
    other one inside its range, their standard errors recomputed without it at the σ
    ``held_sigma(NAME)`` gives (:func:`identifiability_sigma` with ``fixed``: the windows'
    spread with it held), or at their own σ where it is None. A comma2k19 RAV4's minute on a
    highway pinned its steering offset to ±7e+02 rad and its wheel base to ±6.1e+07 % by the
    windows' spread, said as weakly identified, while ``calibrate`` ran the wheel base to its
    edge; with the wheel base held, the offset is pinned.
    """
    from odomkit.calibrate.residuals import CALIBRATED_ROBOTS

    if not isinstance(robot, CALIBRATED_ROBOTS):
        return [Finding("identifiable", "ok", f"a {robot.type_name} robot's calibration is not checked here: "
                        "odomkit calibrate does not calibrate it")]
    if isinstance(sigma, AssumedSigma):
        assumed = sigma
    else:
        assumed = AssumedSigma(float(sigma), "given") if sigma else identifiability_sigma(None)
    A, params, unused, _, _ = _design(log, robot)
    if A.shape[0] < 6:
        return [Finding("identifiable", "fail", "the log is shorter than a few seconds",
                        "record a longer log")]
    if not np.isfinite(A).all():
        # Times of 1e200 s overflow the sensitivities; LAPACK's SVD would fail on them (and
        # print its own complaints), so this is a finding, not a least-squares fit.
        return [Finding("identifiable", "fail", "the sensitivities to the calibration parameters "
                        "are not finite: a value that is not a number, or times or motion so far out of "
                        "range that they overflow", "check the log's values, its time unit and its columns")]
    found = [Finding("identifiable", "ok", f"{label}: not calibrated from this log ({why}): calibrate "
                     "holds it at the robot file's value") for label, why in unused.items()]
    if assumed.source == "drift" and assumed.still and not assumed.windows:
        # MRCLAM user study: a robot standing 140 s stopped check ("SE(2) alignment is
        # undetermined") with every other finding lost.
        found.append(Finding(
            "identifiable", "warn", f"the spread of {_WINDOWS} windows' own fits to the truth is not "
            f"measured: {assumed.still} of them hold no motion to fit (standing or turning on the spot), "
            f"{assumed.fitted} left and two needed; the figures below count the drift by its correlation "
            "time alone, which understates a heading's random walk",
            "check a --span where the robot drives throughout, or record a drive that keeps moving"))
    norms = np.linalg.norm(A, axis=0)
    uniques = [_unique(A, i) for i in range(len(params))]
    ses = [_standard_error(uniques[i], assumed.for_parameter(i).value, value)
           for i, (_, value) in enumerate(params)]
    beyond = [i for i, (par, _) in enumerate(params) if ses[i] > _plausible_reach(par.kind)]
    fixes = _pinning_fixes(A, params, beyond, assumed, held_sigma) if beyond else []
    for i, (par, _) in enumerate(params):
        used = assumed.for_parameter(i)
        se = ses[i]
        _, weak, unidentified = _LIMITS[par.kind]
        shown = _shown(par, se)
        # The σ behind the figure, and whether it is a lower bound (BMW user study: ±8.9e-09
        # rad at the fixes' 26.5 mm scatter, beside an odometry that drifts metres): it is,
        # unless it counts the odometry's drift against a truth (TUC SLAM and smartLoc studies:
        # 1000-10000x below calibrate's own spread, at the truth's noise alone).
        bound = ", a lower bound" if used.lower_bound else ""
        shown = (f"{shown} at {used.describe()}{bound}" if math.isfinite(se)
                 else f"unbounded at {used.describe()}")
        if math.isnan(se):
            found.append(Finding("identifiable", "warn", f"{par.label}: its standard error could not be "
                                 "computed (not a number): not checked", "check the log's values"))
            continue
        ratio = uniques[i] / norms[i] if norms[i] > 0 else 0.0
        why = (" (its effect on the track is almost all one that the other parameters can mimic)"
               if ratio < 0.1 and norms[i] > 0 else "")
        if i in beyond:
            # Beyond the range calibrate fits it in: no figure of precision, drift or not (a RAV4's
            # highway minute: "weakly identified (±6.1e+07 %)", and calibrate ran it to the edge).
            hold = "".join(f"; or odomkit calibrate --fix {name}: it holds {name} at the robot file's value "
                           f"and fits the rest, which this drive then pins ({rest})" for name, rest in fixes)
            found.append(Finding("identifiable", "warn" if not used.lower_bound else "fail",
                                 f"{par.label}: not identifiable from this drive (standard error {shown}: "
                                 f"wider than the whole range calibrate fits it in, {_range_text(par.kind)})"
                                 f"{why}", par.advice + hold, se))
        elif se > unidentified and not used.lower_bound:
            # A realistic figure, drift and all: the motion may pin it where a better odometry
            # or a shorter drive would; weak, not a failure of the log's motion.
            found.append(Finding("identifiable", "warn", f"{par.label}: weakly identified (standard error "
                                 f"{shown}: the odometry's drift limits it){why}", par.advice, se))
        elif se > unidentified:
            found.append(Finding("identifiable", "fail", f"{par.label}: not identifiable from this log "
                                 f"(standard error {shown}){why}",
                                 par.advice, se))
        elif se > weak:
            found.append(Finding("identifiable", "warn", f"{par.label}: weakly identified (standard error "
                                 f"{shown}){why}", par.advice, se))
        else:
            found.append(Finding("identifiable", "ok", f"{par.label}: identified (standard error {shown})",
                                 value=se))
    return found
