"""The errors and covariances at the ends of windows that restart from the truth.

The windows themselves (their length, where they start and end, where a run with truth
starts) are :mod:`odomkit.windows`'s. This module dead-reckons each window from the truth
at its start and predicts the covariance of its end's error: :func:`window_errors` scores
the ends against it (the honesty test of ``odomkit evaluate --window``), and
:func:`window_covariance_basis` (:func:`log_window_basis` for a whole log) gives the same
windows' covariance per unit variance of each noise parameter, the columns of ``odomkit
fit-noise``'s likelihood (:mod:`odomkit.calibrate.window_likelihood`). It is apart from
:mod:`odomkit.windows` because it needs the noise models and the covariance engines, which
cutting a log into windows does not.

The covariance of a window end
------------------------------
With e = truth − odometry at the window end, to first order

    Cov(e) = Φ P_start Φᵀ + R_end + Σ_j v_j B_j,

where P_start is the start pose's covariance (the truth's own noise ``truth.sigma``² on
x and y and ``truth.heading_sigma``² on θ; where the truth has no heading, the variance of
the heading fitted to the truth positions, :func:`odomkit.truth.heading_by_alignment`, at
the window's start or, where the robot stands there, once it moves:
:func:`odomkit.windows.standing_start`),
Φ its transition to the window end (the engines carry it), R_end = diag(σ², σ², σθ²) the
truth's noise at the end (σθ where the truth has heading), and
B_j the covariance that unit variance in noise parameter j alone gives
(:meth:`odomkit.noise.NoiseModel.variance_parameters`). The recursion
P_{k+1} = F P Fᵀ + G Q Gᵀ is linear in (P_0, Q) and a bias adds S diag(σ²) Sᵀ, so the
sum is exact to rounding (Chong–Kleeman eq. 2; Kelly eq. 11).

The truth's clock
-----------------
A truth fix δ seconds off the log's clock is off by the pose's rate times δ; the rate is
taken from the window's own dead reckoning over its first and last 0.2 s (the heading's at
the row its heading was fitted at, where the robot stood at its start). Its heading share
(ω·δ) is kept only at a start whose heading was fitted to position-only truth: there the
fixes' clock turns the fitted heading by ω·δ, which swings the whole window (a 1 Hz GPS
0.2 s late on a car turning at 0.3 rad/s: 0.06 rad, 14 m across 240 m), and θ is never
compared at the end. Elsewhere it is left out on purpose: with the truth's heading compared
at window ends it would give θ variance to the windows that turn at an end and none to
those that do not, a per-log bias could then absorb the latter's θ errors exactly, and the
likelihood had a spurious spike there (seen on commanded-velocity logs: every white θ
variance fitted to zero and the truth's σ to 0.8 m).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.errors import InputError, ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, body_steps
from odomkit.log import OdometryLog, clock_text
from odomkit.noise import NoiseModel, NoiseSet
from odomkit.robot import Robot
from odomkit.truth import WIDEST_HEADING_SPAN
from odomkit.windows import (
    Window,
    WindowSpec,
    cumulative_travel,
    late_start_note,
    rows_at_fixes,
    run_start,
    split_windows,
    standing_start,
    stands_at,
)

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg
    from odomkit.truth import Truth

__all__ = [
    "HEADLESS",
    "NO_FIT",
    "STANDS",
    "TRUTH_NOISE",
    "WindowBasis",
    "WindowErrors",
    "headless_note",
    "log_window_basis",
    "window_covariance_basis",
    "window_errors",
]

#: The white columns of the truth's own noise in a :class:`WindowBasis` fitted with
#: ``truth_columns``: (model index −1, field), the truth's position σ [m], heading σ [rad]
#: and time σ [s] (its fixes' disagreement with the log's clock).
TRUTH_NOISE: tuple[tuple[int, str], ...] = ((-1, "truth_sigma"), (-1, "truth_heading_sigma"),
                                            (-1, "truth_time_sigma"))


@dataclass(frozen=True)
class WindowErrors:
    """Window-end errors and their predicted covariance (:func:`window_errors`).

    Parameters
    ----------
    windows : list of Window
        The windows scored (W), those whose start heading could be had.
    error : ndarray, shape (W, 3)
        Truth − odometry at each window end [m, m, rad], θ wrapped; θ NaN where the
        truth has no heading (the opposite sign of :func:`odomkit.evaluate.pose_errors`,
        estimate − truth).
    cov : ndarray, shape (W, 3, 3)
        Predicted covariance of ``error``: start covariance carried to the end, the
        truth's noise at the end and the odometry noise.
    start_cov : ndarray, shape (W, 3, 3)
        Covariance of each start pose (truth noise, fitted heading).
    end_rows : ndarray of int, shape (W,)
        Log row of each window end.
    dropped : int
        Windows left out because no start heading could be fitted to the truth positions.
    start : ndarray, shape (W, 3)
        The pose each window starts from [m, m, rad]: the truth's, with its heading fitted
        where the truth has none.
    left_out : tuple of (Window, str)
        The windows dropped (``dropped`` of them) and why (:data:`STANDS` or :data:`NO_FIT`;
        :func:`headless_note` says it).
    """

    windows: list[Window]
    error: NDArray[np.float64]
    cov: NDArray[np.float64]
    start_cov: NDArray[np.float64]
    end_rows: NDArray[np.int64]
    dropped: int
    start: NDArray[np.float64] = field(default_factory=lambda: np.empty((0, 3)))
    left_out: tuple[tuple[Window, str], ...] = ()


#: Why windows are left out for want of a start heading (after their count, and the log's name).
HEADLESS = "window(s) left out: no start heading could be fitted to the position-only truth"
#: Why one such window is left out (:attr:`WindowErrors.left_out`): the robot stands at its start
#: and the fixes give no heading soon after it moves (:func:`odomkit.windows.standing_start`), ...
STANDS = ("the robot stands at its start, and the fixes give no heading within "
          f"{WIDEST_HEADING_SPAN / 2:g} s of its moving off")
#: ... or the robot moves there and the fixes around it give none
#: (:func:`odomkit.truth.start_heading`).
NO_FIT = ("the fixes around its start are too few or on one side only, stray from a smooth path by more "
          "than 3 --truth-sigma, or barely move")


def headless_note(t: ArrayLike, left_out: Sequence[tuple[Window, str]], length: WindowSpec | None = None,
                  limit: int = 3) -> str:
    """:data:`HEADLESS` naming the windows left out (at most ``limit``, by their log times ``t``
    (N,) [s] and ``length``) and why, to follow their count (and a log's name before it):
    ``"window(s) left out: no start heading could be fitted to the position-only truth: the
    10 s window 20..30 s (the fixes around its start are too few ...)"``."""
    times = np.asarray(t, dtype=float)
    what = "window" if length is None else f"{length} window"
    named = [f"the {what} {clock_text(times[w.start])}..{clock_text(times[w.end])} s ({why})"
             for w, why in left_out[:limit]]
    more = f"; and {len(left_out) - limit} more" if len(left_out) > limit else ""
    return f"{HEADLESS}: " + "; ".join(named) + more


@dataclass(frozen=True)
class _Prepared:
    """Each kept window's steps, dead-reckoned track, start covariance and end error."""

    windows: list[Window]
    steps: list[BodySteps]
    poses: list[NDArray[np.float64]]
    start_cov: NDArray[np.float64]
    error: NDArray[np.float64]
    end_cov: NDArray[np.float64]  # (W, 3, 3): the truth's own noise at each window end
    heading_from_truth: NDArray[np.bool_]  # (W,): the start heading is the truth's own
    start_rate: NDArray[np.float64]  # (W, 3): d(pose)/dt where the window starts (_pose_rates)
    end_rate: NDArray[np.float64]  # (W, 3): and where it ends
    left_out: tuple[tuple[Window, str], ...]  # the windows dropped for want of a start heading, and why
    method: str

    @property
    def dropped(self) -> int:
        return len(self.left_out)


#: Span [s] over which a window's start and end pose rates are taken from its own dead
#: reckoning (at least one step): long enough to average encoder quantisation, short
#: enough to follow a stop.
RATE_SPAN = 0.2


def _pose_rates(part: BodySteps, poses: NDArray[np.float64], fitted_heading: bool
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """d(x, y, θ)/dt at a window's start and end, (3,) each, from its dead-reckoned poses
    over :data:`RATE_SPAN`: a truth fix δ seconds off the log's clock is off by rate·δ.

    The heading's share (ω·δ) is kept only at a start whose heading was fitted to
    position-only truth (``fitted_heading``): there the fixes' clock turns the fitted
    heading by ω·δ, which swings the whole window (a 1 Hz GPS 0.2 s late on a car turning at
    0.3 rad/s: 0.06 rad, 14 m across 240 m), and θ is never compared at the end. Elsewhere
    it is left out on purpose: with the truth's heading compared at window ends it would
    give θ variance to the windows that turn at an end and none to those that do not, a
    per-log bias could then absorb the latter's θ errors exactly, and the likelihood had a
    spurious spike there (seen on commanded-velocity logs: every white θ variance fitted to
    zero and the truth's σ to 0.8 m).
    """
    dt = np.asarray(part.dt, dtype=float)
    # The steps within RATE_SPAN (less a rounding margin: 4 × 0.05 s may sum to 0.19999...).
    m = max(1, min(len(dt), int(np.searchsorted(np.cumsum(dt), RATE_SPAN * (1 - 1e-9))) + 1))
    head, tail = float(np.sum(dt[:m])), float(np.sum(dt[-m:]))
    start = (poses[m] - poses[0]) / head if head > 0 else np.zeros(3)
    end = (poses[-1] - poses[-1 - m]) / tail if tail > 0 else np.zeros(3)
    end[2] = 0.0
    if not fitted_heading:
        start[2] = 0.0
    return start, end


def _slice_steps(steps: BodySteps, a: int, b: int) -> BodySteps:
    """Steps a … b−1 (rows a … b); per-row inputs (a compass heading, M + 1) keep rows a … b."""
    m = len(steps)
    inputs = {k: (v[a:b + 1] if np.shape(v)[0] == m + 1 else v[a:b]) for k, v in steps.inputs.items()}
    return BodySteps(steps.dd[a:b], steps.dtheta[a:b], steps.dt[a:b], inputs, steps.robot)


def _prepare(log: OdometryLog, robot: Robot, truth_poses: ArrayLike, truth_valid: ArrayLike,
             windows: list[Window], truth: Truth | None, method: str,
             steps: BodySteps | None = None, own_noise: bool = True) -> _Prepared:
    """The kept windows; ``own_noise`` False leaves the truth's own noise (``sigma``,
    ``heading_sigma``, ``time_sigma``) out of the start covariances and ``end_cov`` (a fit
    of it)."""
    n = len(log)
    gt = validate.shape(truth_poses, "truth poses", (n, 3), error=InputError)
    ok = np.asarray(truth_valid, dtype=bool)
    if ok.shape != (n,):
        raise InputError(f"truth_valid must have shape ({n},), got {ok.shape}")
    steps = body_steps(robot, log) if steps is None else steps
    sigma2 = 0.0 if truth is None or not own_noise else float(truth.sigma) ** 2
    heading2 = (0.0 if truth is None or not own_noise or not truth.has_heading
                else float(truth.heading_sigma) ** 2)
    time2 = 0.0 if truth is None or not own_noise else float(truth.time_sigma) ** 2
    kept: list[Window] = []
    parts: list[BodySteps] = []
    tracks: list[NDArray[np.float64]] = []
    starts, errors, from_truth, rates = [], [], [], []
    left_out: list[tuple[Window, str]] = []
    odometry: NDArray[np.float64] | None = None
    travel: NDArray[np.float64] | None = None
    log_t = np.asarray(log.t, dtype=float)
    for w in windows:
        a, b = w.start, w.end
        later = a  # the row whose fixes gave the start heading (a later one where the robot stood)
        if not (0 <= a < b < n) or not (ok[a] and ok[b]):
            raise ModelError(f"window rows {a}..{b} need valid truth at both ends of a "
                             f"{n}-row log")
        if not np.all(np.isfinite(gt[[a, b], :2])):
            raise InputError(f"the truth position at row {a if not np.isfinite(gt[a, 0]) else b} "
                             "is NaN; expected finite numbers", source=log.source)
        part = _slice_steps(steps, a, b)
        cov0 = np.zeros((3, 3))
        cov0[0, 0] = cov0[1, 1] = sigma2
        pose0 = gt[a].copy()
        own_heading = False
        if robot.measures_heading:
            pose0[2] = part.inputs["heading"][0]  # the measured heading (see dead_reckon_log)
        elif np.isfinite(pose0[2]):
            cov0[2, 2], own_heading = heading2, True
        else:
            if odometry is None:  # the whole log from the origin: its shape around each start
                odometry = dead_reckon(steps.dd, steps.dtheta, np.zeros(3), method)  # type: ignore[arg-type]
            if truth is None:
                raise InputError("the truth has no heading at a window start; pass the Truth so that "
                                 "one can be fitted to its positions", source=log.source)
            from odomkit.truth import start_heading

            fitted = start_heading(truth, float(log.t[a]), log_t, odometry)
            if fitted is None:  # a robot standing at the window's start: the heading it leaves with
                travel = cumulative_travel(steps) if travel is None else travel
                standing = standing_start(log_t, truth, ok, odometry, travel, a, b)
                if standing is None:
                    left_out.append((w, STANDS if stands_at(travel, a) else NO_FIT))
                    continue
                fitted, later = standing[:2], standing[2]
            pose0[2], cov0[2, 2] = fitted
        poses = dead_reckon(part.dd, part.dtheta, pose0, method)  # type: ignore[arg-type]
        err = gt[b] - poses[-1]
        err[2] = wrap_angle(err[2])
        fitted_heading = not (own_heading or robot.measures_heading)
        rate_a, rate_b = _pose_rates(part, poses, fitted_heading)
        if later > a:  # the heading was fitted where the robot had left: its clock turns it there
            rate_a[2] = _pose_rates(_slice_steps(part, later - a, b - a), poses[later - a:], True)[0][2]
        cov0 += time2 * np.outer(rate_a, rate_a)
        kept.append(w)
        parts.append(part)
        tracks.append(poses)
        starts.append(cov0)
        errors.append(err)
        from_truth.append(own_heading)
        rates.append((rate_a, rate_b))
    start = np.array(starts).reshape(-1, 3, 3)
    error = np.array(errors).reshape(-1, 3)
    rate = np.array(rates).reshape(-1, 2, 3)
    end_cov = np.diag([sigma2, sigma2, heading2])[None] + time2 * np.einsum("wa,wb->wab", rate[:, 1],
                                                                              rate[:, 1])
    return _Prepared(kept, parts, tracks, start, error, end_cov, np.array(from_truth, dtype=bool),
                     rate[:, 0], rate[:, 1], tuple(left_out), method)


def _end_covariance(part: BodySteps, poses: NDArray[np.float64], noise: NoiseArg,
                    cov0: NDArray[np.float64], method: str) -> NDArray[np.float64]:
    """Covariance at a window's last row from the engines (recursion)."""
    from odomkit.propagate.recursion import iter_track_covariance

    last = cov0
    for _, chunk in iter_track_covariance(part, poses, noise, cov0, method):
        last = chunk[-1]
    return np.array(last)


def window_errors(
    log: OdometryLog,
    robot: Robot,
    noise: NoiseArg,
    truth_poses: ArrayLike,
    truth_valid: ArrayLike,
    windows: list[Window],
    *,
    truth: Truth | None = None,
    method: str = "exact",
) -> WindowErrors:
    """Dead-reckon each window from the truth at its start and score its end.

    Each window starts at the truth pose of its first row with covariance
    diag(σ², σ², σθ²), σ = ``truth.sigma`` and σθ = ``truth.heading_sigma`` (zero without
    ``truth``), and its end gets the same truth noise; where the truth has no
    heading (θ NaN in ``truth_poses``), the start heading is fitted to the truth positions
    (the odometry's own path aligned to them, :func:`odomkit.truth.heading_by_alignment`) and its
    variance enters the start covariance; a window that starts while the robot stands takes
    the heading it leaves with (:func:`odomkit.windows.standing_start`: fitted once it moves,
    turned back by the odometry's own turn since the start), and a window where neither
    gives one is dropped, counted and named (``left_out``, :func:`headless_note`). A compass
    robot starts from its measured heading, as ``odomkit track`` does.

    Parameters
    ----------
    log : OdometryLog, N rows
    robot : Robot
    noise : noise model, sequence of models or NoiseSet
    truth_poses : array_like, shape (N, 3)
        Truth at each log row (e.g. :func:`odomkit.truth.truth_at` at ``log.t``); θ NaN
        for position-only truth.
    truth_valid : array_like of bool, shape (N,)
    windows : list of Window
        From :func:`odomkit.windows.split_windows`; both ends must have valid truth.
    truth : Truth, optional
        The truth itself: its ``sigma``, and its positions for fitted start headings.
    method : {"exact", "midpoint", "euler"}

    Returns
    -------
    WindowErrors

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.robot import DiffDrive
    >>> t = np.arange(0.0, 20.01, 0.1)
    >>> log = OdometryLog(t, {"dist_left": np.full(t.size, 0.01), "dist_right": np.full(t.size, 0.01)})
    >>> truth = np.column_stack((0.1 * t, 0 * t, 0 * t))
    >>> w, _ = split_windows(t, 0.1 * t, WindowSpec(10.0, "s"))
    >>> out = window_errors(log, DiffDrive(0.4), WheelNoise(0.01, 0.01), truth,
    ...                     np.ones(t.size, bool), w)
    >>> bool(np.abs(out.error).max() < 1e-12), round(float(out.cov[0, 0, 0]), 12)  # (k²+k²)·1 m/4
    (True, 5e-05)
    """
    prep = _prepare(log, robot, truth_poses, truth_valid, windows, truth, method)
    NoiseSet.of(noise).check_robot(robot)
    covs = np.empty((len(prep.windows), 3, 3))
    for i, (part, poses) in enumerate(zip(prep.steps, prep.poses, strict=True)):
        covs[i] = _end_covariance(part, poses, noise, prep.start_cov[i], method) + prep.end_cov[i]
    ends = np.array([w.end for w in prep.windows], dtype=np.int64)
    start = np.array([poses[0] for poses in prep.poses]).reshape(-1, 3)
    return WindowErrors(prep.windows, prep.error, covs, prep.start_cov, ends, prep.dropped, start,
                        prep.left_out)


@dataclass(frozen=True)
class WindowBasis:
    """Window-end errors and their covariance per unit variance of each noise parameter
    (:func:`window_covariance_basis`).

    With v_j the variance parameters (:meth:`odomkit.noise.NoiseModel.variance_parameters`)
    the covariance of window w's end error is

        ``fixed[w] + Σ_j v_j white[w, j] + sens[w] diag(bias_weights.T @ v_bias) sens[w]ᵀ``

    and windows of one log share the bias: their errors are correlated through ``sens``.

    Parameters
    ----------
    windows : list of Window (W)
    error : ndarray, shape (W, 3)
        Truth − odometry at each window end; θ NaN where the truth has no heading.
    fixed : ndarray, shape (W, 3, 3)
        The part that no parameter scales: start covariance carried to the end plus the
        truth's noise at the end.
    white : ndarray, shape (W, q, 3, 3)
        Covariance per unit variance of each white parameter (``white_names``; the last three
        are the truth's own noise, :data:`TRUTH_NOISE`, when it is fitted).
    sens : ndarray, shape (W, 3, c)
        Sensitivity of each window end to the c bias columns (each model's bias
        parameters, :meth:`odomkit.noise.NoiseModel.bias_jacobian`).
    bias_weights : ndarray, shape (p, c)
        Variance each bias column gets per unit of each bias parameter (``bias_names``).
    white_names, bias_names : tuple of (model index, field name)
    turning : ndarray, shape (W,)
        Odometry heading change of each window, Σ|Δθ| [rad] (turning identifies the
        heading-related parameters).
    dropped : int
        Windows left out for lack of a fitted start heading.
    notes : tuple of str
        Warnings about these windows (:func:`log_window_basis`: where the whole-log window
        starts later than the log's first row with truth, and why).
    per_spec : tuple of int
        How many of the windows each window length given to :func:`log_window_basis` cut,
        in its order (empty for a basis made otherwise).
    left_out : tuple of (Window, str)
        The windows dropped for want of a start heading, and why (:attr:`WindowErrors.left_out`).
    """

    windows: list[Window]
    error: NDArray[np.float64]
    fixed: NDArray[np.float64]
    white: NDArray[np.float64]
    sens: NDArray[np.float64]
    bias_weights: NDArray[np.float64]
    white_names: tuple[tuple[int, str], ...]
    bias_names: tuple[tuple[int, str], ...]
    turning: NDArray[np.float64]
    dropped: int
    notes: tuple[str, ...] = ()
    per_spec: tuple[int, ...] = ()
    left_out: tuple[tuple[Window, str], ...] = ()

    def select(self, keep: ArrayLike) -> WindowBasis:
        """The windows where ``keep`` (bool, shape (W,)) is true, as a basis of their own."""
        idx = np.flatnonzero(np.asarray(keep, dtype=bool))
        return WindowBasis([self.windows[i] for i in idx], self.error[idx], self.fixed[idx],
                           self.white[idx], self.sens[idx], self.bias_weights, self.white_names,
                           self.bias_names, self.turning[idx], self.dropped, self.notes,
                           left_out=self.left_out)

    @staticmethod
    def merge(bases: list[WindowBasis]) -> WindowBasis:
        """One log's bases of several window lengths as one basis (windows in order given).

        The windows share the log's bias draw, as they should; windows of different lengths
        overlap in time, so their white errors are correlated and a fit on the merged basis
        is a *composite* likelihood (each length's windows are independent among
        themselves, not across lengths): its estimates are consistent but its intervals
        are too narrow by up to the square root of the number of lengths.
        """
        if not bases:
            raise ModelError("no window bases to merge")
        first = bases[0]
        for b in bases[1:]:
            if b.white_names != first.white_names or b.bias_names != first.bias_names:
                raise ModelError("window bases to merge must come from the same noise models")
        return WindowBasis([w for b in bases for w in b.windows],
                           np.concatenate([b.error for b in bases]),
                           np.concatenate([b.fixed for b in bases]),
                           np.concatenate([b.white for b in bases]),
                           np.concatenate([b.sens for b in bases]), first.bias_weights,
                           first.white_names, first.bias_names,
                           np.concatenate([b.turning for b in bases]),
                           sum(b.dropped for b in bases),
                           tuple(dict.fromkeys(n for b in bases for n in b.notes)),
                           left_out=tuple(x for b in bases for x in b.left_out))

    def covariance(self, variances: ArrayLike) -> NDArray[np.float64]:
        """Each window end's covariance (W, 3, 3) at variance parameters ``variances``
        (q white then p bias, in the order of ``white_names`` + ``bias_names``)."""
        v = np.asarray(variances, dtype=float)
        q = len(self.white_names)
        cov = self.fixed + np.einsum("j,wjab->wab", v[:q], self.white)
        col = self.bias_weights.T @ v[q:]
        return cov + np.einsum("wac,c,wbc->wab", self.sens, col, self.sens)


def window_covariance_basis(
    log: OdometryLog,
    robot: Robot,
    models: NoiseArg,
    truth_poses: ArrayLike,
    truth_valid: ArrayLike,
    windows: list[Window],
    *,
    truth: Truth | None = None,
    method: str = "exact",
    truth_columns: bool = False,
) -> WindowBasis:
    """Per-parameter covariance bases of the window ends, for fitting variances.

    White parameter j's basis is the engines' covariance (:func:`window_errors`' engine)
    with unit variance in j alone and zero start covariance; a bias model's columns are
    the sensitivities S = ∂(window-end pose)/∂β, accumulated from each window's start
    (:func:`odomkit.propagate.transition.sensitivity_chunk`), so that its covariance
    S diag(σ²) Sᵀ is the engines' and windows of one log can share β.

    Parameters
    ----------
    log, robot, truth_poses, truth_valid, windows, truth, method
        As for :func:`window_errors`.
    models : noise model, sequence of models or NoiseSet
        Every variance parameter of every model that applies to ``robot`` gets a basis
        (their current values do not matter).
    truth_columns : bool
        Fit the truth's own noise too: the truth's ``sigma``, ``heading_sigma`` and
        ``time_sigma`` leave ``fixed`` and become the last three white columns, named
        :data:`TRUTH_NOISE`. A window's truth noise enters at its start (carried to the
        end: a start position error moves the end by the same amount, since dead
        reckoning's increments do not depend on the position, so that column is exactly
        diag(2, 2, 0); a start heading error swings the end about the start) and at its
        end. The heading column is zero where the start heading is not the truth's
        (position-only truth, a compass robot's measured heading) and the end heading is
        not compared. A fix δ seconds off the log's clock is off by the pose rate times δ
        (u from the window's own dead reckoning, :data:`RATE_SPAN`; its heading share only
        at a start heading fitted to position-only truth; the module docstring, "The
        truth's clock", says why):
        the time column is Φ u_a u_aᵀ Φᵀ + u_b u_bᵀ, zero where the robot stands.

    Returns
    -------
    WindowBasis
    """
    from odomkit.propagate.inputs import step_terms
    from odomkit.propagate.transition import bias_sensitivity_chunk

    noise = NoiseSet.of(models)
    noise.check_robot(robot)
    prep = _prepare(log, robot, truth_poses, truth_valid, windows, truth, method, own_noise=not truth_columns)
    step_map = noise.step_map(method)
    white_units: list[tuple[tuple[int, str], NoiseModel]] = []
    bias_names: list[tuple[int, str]] = []
    bias_models: list[NoiseModel] = []
    weight_blocks: list[NDArray[np.float64]] = []
    for i, model in enumerate(noise.models):
        params = model.variance_parameters(robot)
        zero = dict.fromkeys(params, 0.0)
        units = [(name, model.from_variances({**zero, name: 1.0})) for name in params]
        if model.kind == "white":
            white_units += [((i, name), unit) for name, unit in units]
        else:
            bias_models.append(model)
            bias_names += [(i, name) for name, _ in units]
            weight_blocks.append(np.array([unit.bias_variances(robot) for _, unit in units])
                                 .reshape(len(units), -1))
    n_cols = sum(b.shape[1] for b in weight_blocks)
    weights = np.zeros((len(bias_names), n_cols))
    r = c = 0
    for block in weight_blocks:
        weights[r:r + block.shape[0], c:c + block.shape[1]] = block
        r, c = r + block.shape[0], c + block.shape[1]
    n_win = len(prep.windows)
    n_truth = len(TRUTH_NOISE) if truth_columns else 0
    fixed = np.zeros((n_win, 3, 3))
    white = np.zeros((n_win, len(white_units) + n_truth, 3, 3))
    sens = np.zeros((n_win, 3, n_cols))
    for w, (part, poses) in enumerate(zip(prep.steps, prep.poses, strict=True)):
        if np.any(prep.start_cov[w]):
            fixed[w] = _end_covariance(part, poses, (), prep.start_cov[w], method)
        fixed[w] += prep.end_cov[w]
        for j, (_, unit) in enumerate(white_units):
            white[w, j] = _end_covariance(part, poses, unit, np.zeros((3, 3)), method)
        if truth_columns:
            white[w, -3] = np.diag([2.0, 2.0, 0.0])
            if prep.heading_from_truth[w]:
                white[w, -2] = _end_covariance(part, poses, (), np.diag([0.0, 0.0, 1.0]), method)
            if np.isfinite(prep.error[w, 2]):  # the end heading is compared
                white[w, -2, 2, 2] += 1.0
            rate_a, rate_b = prep.start_rate[w], prep.end_rate[w]
            white[w, -1] = (_end_covariance(part, poses, (), np.outer(rate_a, rate_a), method)
                            + np.outer(rate_b, rate_b))
        if n_cols and len(part):
            K = np.concatenate([m.bias_jacobian(part, 0, len(part)) for m in bias_models], axis=-1)
            start = np.zeros((3, n_cols))
            if robot.measures_heading:  # a heading offset moves the measured start heading too
                start[2] = np.concatenate([m.bias_heading(robot) for m in bias_models])
            sens[w] = bias_sensitivity_chunk(step_terms(poses[:-1, 2], part.dd, part.dtheta, step_map),
                                             K, start, robot.measures_heading)[-1]
    turning = np.array([float(np.sum(np.abs(part.dtheta))) for part in prep.steps])
    names = tuple(name for name, _ in white_units) + (TRUTH_NOISE if truth_columns else ())
    return WindowBasis(prep.windows, prep.error, fixed, white, sens, weights, names, tuple(bias_names),
                       turning, prep.dropped, left_out=prep.left_out)


def log_window_basis(
    log: OdometryLog,
    robot: Robot,
    models: NoiseArg,
    truth: Truth,
    specs: Sequence[WindowSpec | None],
    *,
    min_travel: float = 0.05,
    max_gap: float | None = 0.5,
    method: str = "exact",
    truth_columns: bool = False,
) -> tuple[WindowBasis | None, int]:
    """One log's windows of every length in ``specs`` as one basis, for fitting variances.

    The truth is sampled at the log's rows (:func:`odomkit.truth.truth_at`), each length's
    windows are cut over the rows where it is valid
    (:func:`odomkit.windows.split_windows`) and turned into bases
    (:func:`window_covariance_basis`, with ``truth_columns``), and the lengths are merged
    (:meth:`WindowBasis.merge`: they share the log's bias draw). The whole-log window (a
    ``spec`` None) starts where a run can start from the truth
    (:func:`odomkit.windows.run_start`, as ``odomkit evaluate``'s whole run does): with
    position-only truth, at the first row where its fixes give a heading, said in the
    basis's ``notes``; where they give none at any row, the window is dropped and the note
    says so.

    A building block, with a building block's defaults: no truth-noise columns
    (``truth_columns=False``: the truth's noise is the fixed ``sigma``, ``heading_sigma`` and
    ``time_sigma`` of ``truth``, zero unless given). ``odomkit fit-noise`` fits the truth's
    noise (``truth_columns=True``) and trims the fit; its defaults, in one call for logs in
    memory: :func:`odomkit.workflows.fit_noise.fit_noise_in_memory`.

    Returns
    -------
    basis : WindowBasis or None
        None when no length has a window in this log.
    skipped : int
        Windows left out for travelling less than ``min_travel`` [m], all lengths.
    """
    from odomkit.truth import truth_at

    samples = truth_at(truth, log.t, max_gap)
    steps = body_steps(robot, log)
    travel = cumulative_travel(steps)
    parts, skipped, notes, counts = [], 0, [], []
    valid = samples.valid
    at_fixes = rows_at_fixes(log.t, truth.t, valid)  # a sparse truth: ends only next to its fixes
    for spec in specs:
        windows, left = split_windows(log.t, travel, spec, min_travel, valid=valid, ends=at_fixes)
        if spec is None and windows and not truth.has_heading:
            starts, note = _whole_log_rows(log, steps, truth, at_fixes, max_gap, method)
            windows, left = split_windows(log.t, travel, spec, min_travel, valid=valid, ends=starts)
            notes += [note] if note else []
        skipped += left
        if windows:
            parts.append(window_covariance_basis(log, robot, models, samples.poses, valid, windows,
                                                 truth=truth, method=method, truth_columns=truth_columns))
            if spec is not None and parts[-1].left_out:  # (the whole-log window's: _whole_log_rows)
                gone = parts[-1].left_out
                notes.append(f"{log.source}: {len(gone)} {headless_note(log.t, gone, spec)}")
        counts.append(len(parts[-1].windows) if windows else 0)  # less the windows dropped
    if not parts:
        return None, skipped
    return replace(WindowBasis.merge(parts), notes=tuple(notes), per_spec=tuple(counts)), skipped


def _whole_log_rows(log: OdometryLog, steps: BodySteps, truth: Truth, valid: NDArray[np.bool_],
                    max_gap: float | None, method: str) -> tuple[NDArray[np.bool_], str | None]:
    """The rows with truth from which the whole-log window may start
    (:func:`odomkit.windows.run_start`: from the first where position-only truth gives a
    heading), and a note when that is not the first row with truth. Where no row gives one,
    ``valid`` as it is (the window is then dropped, as one whose start heading cannot be
    fitted) and the note says so."""
    first_valid = int(np.argmax(valid))
    odometry = dead_reckon(steps.dd, steps.dtheta, np.zeros(3), method)  # type: ignore[arg-type]
    try:
        row, _, _ = run_start(log.t, truth, valid, odometry, max_gap)
    except InputError as exc:
        return valid, f"{log.source}: no start for the whole-log window: {exc}"
    if row == first_valid:
        return valid, None
    later = valid.copy()
    later[:row] = False
    return later, late_start_note(log.source, "the whole-log window", log.t, row, first_valid)
