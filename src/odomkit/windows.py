"""Windows over a log with ground truth: how long each is, where it starts and ends.

Long logs say little about odometry as a whole (the error of one 10-minute run is one
sample); cut into non-overlapping windows that each restart from the truth pose, they give
one error sample per window. :func:`split_windows` cuts a log by time (``30s``) or by
odometry travel (``5m``) over the rows with truth (:func:`truth_stretches`), and
:func:`why_no_windows` says why it found none; :func:`run_start` is the one rule for where a
run with truth starts (the whole run of ``odomkit evaluate``, its whole-log window and
``fit-noise``'s, ``odomkit track --truth``), and :func:`standing_start` the start heading of a
window that starts while the robot stands, against position-only truth. What a window's
end is scored against, its error and predicted covariance, is :mod:`odomkit.window_errors`'s
(:func:`odomkit.window_errors.window_errors`, the honesty test of ``odomkit evaluate
--window``; :func:`odomkit.window_errors.window_covariance_basis`, ``odomkit fit-noise``).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import InputError
from odomkit.kinematics import BodySteps
from odomkit.log import clock_text

if TYPE_CHECKING:
    from odomkit.truth import Truth

__all__ = [
    "REST_TRAVEL",
    "SPARSE_TRUTH",
    "START_STRIDE",
    "Window",
    "WindowSpec",
    "cumulative_travel",
    "is_late_start_note",
    "late_start_note",
    "parse_window",
    "parse_windows",
    "rows_at_fixes",
    "run_start",
    "split_windows",
    "standing_start",
    "stands_at",
    "truth_stretches",
    "why_no_windows",
]


@dataclass(frozen=True)
class WindowSpec:
    """How long each window is: ``length`` seconds (unit ``"s"``) or metres of odometry
    travel (unit ``"m"``)."""

    length: float
    unit: Literal["s", "m"]

    def __post_init__(self) -> None:
        validate.positive(self.length, "window length", unit=self.unit, error=InputError)
        if self.unit not in ("s", "m"):
            raise InputError(f"window unit must be 's' or 'm', got {self.unit!r}")

    def __str__(self) -> str:
        return f"{self.length:g} {self.unit}"


_WINDOW_UNITS = {"s": ("s", 1.0), "min": ("s", 60.0), "h": ("s", 3600.0), "m": ("m", 1.0)}


def parse_window(text: str) -> WindowSpec:
    """A window length from text: ``30s``, ``2min``, ``1h`` (time) or ``5m`` (metres of
    odometry travel).

    Examples
    --------
    >>> parse_window("30s"), parse_window("2.5 min"), parse_window("5m")
    (WindowSpec(length=30.0, unit='s'), WindowSpec(length=150.0, unit='s'), WindowSpec(length=5.0, unit='m'))
    """
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(s|min|h|m)\s*", str(text))
    if match is None:
        raise InputError(f"--window must be a length such as 30s (seconds), 2min or 5m (metres "
                         f"of travel), got {text!r}")
    unit, factor = _WINDOW_UNITS[match.group(2)]
    value = float(match.group(1)) * factor
    if value <= 0:
        raise InputError(f"--window must be longer than zero, got {text!r}")
    return WindowSpec(value, unit)  # type: ignore[arg-type]


def parse_windows(texts: str | Sequence[str] | None) -> tuple[WindowSpec | None, ...]:
    """Every ``--window`` given, in order (``(None,)``: none given, one window per log).

    One length given twice (``10s`` and ``10 s``, or ``60s`` and ``1min``) is an error: a
    fit would count its windows twice, an evaluation would score them twice.

    Examples
    --------
    >>> parse_windows(["10s", "30s"])
    (WindowSpec(length=10.0, unit='s'), WindowSpec(length=30.0, unit='s'))
    >>> parse_windows(None)
    (None,)
    """
    given = [texts] if isinstance(texts, str) else list(texts or [])
    specs = [parse_window(text) for text in given]
    for i, spec in enumerate(specs):
        if spec in specs[:i]:
            raise InputError(f"--window {given[i]} is the same length as --window {given[specs.index(spec)]} "
                             f"({spec}): give each length once")
    return tuple(specs) or (None,)


@dataclass(frozen=True)
class Window:
    """One window: dead reckoning runs from log row ``start`` to row ``end``.

    ``duration`` [s] and ``travel`` [m] (odometry path length, reversing included) of
    the window.
    """

    start: int
    end: int
    duration: float
    travel: float


def cumulative_travel(steps: BodySteps) -> NDArray[np.float64]:
    """Odometry path length from row 0 to each row, shape (M + 1,) [m] (|Δd| summed)."""
    return np.concatenate(([0.0], np.cumsum(np.abs(np.asarray(steps.dd, dtype=float)))))


def split_windows(
    t: ArrayLike,
    travel: ArrayLike,
    spec: WindowSpec | None,
    min_travel: float = 0.05,
    *,
    valid: ArrayLike | None = None,
    ends: ArrayLike | None = None,
) -> tuple[list[Window], int]:
    """Non-overlapping windows over the rows where the truth is valid.

    A window needs truth at its two ends only: the odometry runs on through a truth gap
    inside it. So the rows with valid truth are cut into stretches only where the gap
    between two of them is as long as a window (:func:`truth_stretches`), and each stretch
    is cut greedily from its first row: a window ends at the first valid row at least
    ``spec.length`` seconds (or metres of travel) after its start, and the next window
    starts there. A stretch's tail shorter than a window is left out. ``spec`` None gives
    one window from the first to the last valid row.

    Parameters
    ----------
    t : array_like, shape (N,)
        Time of each row [s], non-decreasing.
    travel : array_like, shape (N,)
        Odometry path length from row 0 to each row [m] (:func:`cumulative_travel`).
    spec : WindowSpec or None
    min_travel : float
        Windows travelling less than this [m] are left out and counted: a robot standing
        still says nothing about its odometry.
    valid : array_like of bool, shape (N,), optional
        Rows where the truth is valid (default: all).
    ends : array_like of bool, shape (N,), optional
        Rows of ``valid`` a window may start and end at (default: every valid row; a sparse
        truth: the rows next to its fixes, :func:`rows_at_fixes`). The stretches and gaps
        are the truth's (``valid``), so a window shorter than the fixes' spacing is cut
        from fix to fix, not refused as longer than a stretch.

    Returns
    -------
    windows : list of Window
    skipped : int
        Windows left out for travelling less than ``min_travel``.

    Examples
    --------
    >>> t = np.arange(0.0, 10.01, 0.5)
    >>> w, skipped = split_windows(t, t, WindowSpec(3.0, "s"))
    >>> [(x.start, x.end) for x in w], skipped
    ([(0, 6), (6, 12), (12, 18)], 0)
    """
    t = validate.shape(t, "time", ("N",), error=InputError)
    s = validate.shape(travel, "travel", (t.size,), error=InputError)
    ok = np.ones(t.size, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    if ok.shape != t.shape:
        raise InputError(f"valid must have shape {t.shape}, got {ok.shape}")
    min_travel = validate.non_negative(min_travel, "min_travel", unit="m", error=InputError)
    windows: list[Window] = []
    skipped = 0

    def add(a: int, b: int) -> None:
        nonlocal skipped
        w = Window(a, b, float(t[b] - t[a]), float(s[b] - s[a]))
        if w.travel < min_travel:
            skipped += 1
        else:
            windows.append(w)

    at = ok if ends is None else ok & np.asarray(ends, dtype=bool)
    rows = np.flatnonzero(ok)
    if rows.size == 0:
        return windows, 0
    if spec is None:
        usable = np.flatnonzero(at)
        if usable.size and usable[-1] > usable[0]:
            add(int(usable[0]), int(usable[-1]))
        return windows, skipped
    along = t if spec.unit == "s" else s
    for first, last in truth_stretches(along[rows], spec.length):
        cand = rows[first] + np.flatnonzero(at[rows[first]:rows[last] + 1])  # the stretch's end rows
        if cand.size < 2:
            continue
        axis = along[cand]
        i = 0  # positions in ``cand``
        while True:
            j = int(np.searchsorted(axis, axis[i] + spec.length, side="left"))
            # searchsorted may land on a repeated value below the target; never before i+1.
            j = max(j, i + 1)
            if j >= cand.size or axis[j] < axis[i] + spec.length:
                break
            add(int(cand[i]), int(cand[j]))
            i = j
    return windows, skipped


#: A truth whose fixes come this many times farther apart than the log's rows (median
#: spacings) is sparse: a window starts and ends only at the row next to one of its fixes
#: (:func:`rows_at_fixes`).
SPARSE_TRUTH = 1.5


def rows_at_fixes(t: ArrayLike, truth_t: ArrayLike, valid: ArrayLike) -> NDArray[np.bool_]:
    """The rows of ``valid`` a window may start or end at, shape (N,).

    Where the truth's fixes are about as dense as the log's rows, every valid row: the
    truth interpolated to a row moves it by a fraction of a fix's step. Where they are
    sparser (:data:`SPARSE_TRUTH`: a 1 Hz GPS under a 10 Hz log, a reference every 2 s),
    only the row nearest each fix, within half the log's median row spacing: between two
    fixes the truth is a chord of the path, off it by the path's curvature (a robot turning
    90° between fixes 2 s apart is 0.25 m off the chord midway, and its interpolated heading
    lags), and a window ending there would score that as the odometry's error. The row is at
    most half a row spacing from its fix, over which the interpolation moves the truth by
    the speed times that time, along the path.

    Parameters
    ----------
    t : array_like, shape (N,)
        Time of each log row [s], non-decreasing.
    truth_t : array_like, shape (K,)
        Times of the truth's fixes [s] on the log's clock, increasing.
    valid : array_like of bool, shape (N,)
        Rows with valid truth (:func:`odomkit.truth.truth_at`).

    Examples
    --------
    >>> t = np.round(np.arange(0.0, 3.01, 0.1), 10)
    >>> rows = rows_at_fixes(t, [0.0, 1.02, 2.0, 2.96], np.ones(t.size, dtype=bool))
    >>> t[rows].tolist()
    [0.0, 1.0, 2.0, 3.0]
    """
    t = np.asarray(t, dtype=float)
    fixes = np.asarray(truth_t, dtype=float)
    ok = np.asarray(valid, dtype=bool)
    if t.size < 2 or fixes.size < 2:
        return ok
    row_step = float(np.median(np.diff(t)))
    if not float(np.median(np.diff(fixes))) > SPARSE_TRUTH * row_step:
        return ok
    inside = fixes[(fixes >= t[0] - row_step / 2) & (fixes <= t[-1] + row_step / 2)]
    after = np.searchsorted(t, inside).clip(1, t.size - 1)
    nearest = np.where(np.abs(t[after - 1] - inside) <= np.abs(t[after] - inside), after - 1, after)
    near = np.abs(t[nearest] - inside) <= row_step / 2
    at_fix = np.zeros(t.size, dtype=bool)
    at_fix[nearest[near]] = True
    return ok & at_fix


def truth_stretches(axis: NDArray[np.float64], length: float) -> list[tuple[int, int]]:
    """[first, last] positions (inclusive) of the stretches of valid-truth rows that
    windows of ``length`` may span: ``axis`` (n,) holds each valid row's time [s] or
    travel [m], and a jump of ``length`` or more between two of them (a truth gap as long
    as a window) ends a stretch."""
    breaks = np.flatnonzero(np.diff(axis) >= length)
    firsts = np.concatenate(([0], breaks + 1)).tolist()
    lasts = np.concatenate((breaks, [axis.size - 1])).tolist()
    return list(zip(firsts, lasts, strict=True))


def why_no_windows(t: ArrayLike, travel: ArrayLike, valid: ArrayLike, spec: WindowSpec | None,
                   min_travel: float, skipped: int) -> str:
    """One line on why :func:`split_windows` found no window in a log (same arguments, and
    the ``skipped`` it returned): the window is longer than the longest stretch of truth
    between gaps (the log inside the truth when there is no gap), or no window moves."""
    unit = "s" if spec is None or spec.unit == "s" else "m of travel"
    along = np.asarray(t if unit == "s" else travel, dtype=float)
    # The longest stretch of rows with truth, as split_windows cuts them.
    rows = np.flatnonzero(np.asarray(valid, dtype=bool))
    if rows.size < 2:
        return "fewer than two of the log's rows have truth (odomkit.truth.no_overlap says why)"
    if spec is not None and not skipped:
        stretches = truth_stretches(along[rows], spec.length)
        longest = max(float(along[rows[b]] - along[rows[a]]) for a, b in stretches)
        within = "the log inside the truth" if len(stretches) == 1 else (
            f"the longest of the log's {len(stretches)} stretches of truth between gaps as long as a window")
        return (f"the window ({spec.length:g} {unit}) is longer than {within} ({longest:.4g} {unit}); "
                "shorten --window")
    return (f"no window travels --min-travel {min_travel:g} m or more: the log shows no motion along a "
            "path (standing still, or turning on the spot), and windows without travel are not scored")


#: How far apart [s] :func:`run_start` first tries rows for a start heading (then it looks
#: back row by row): trying every row of a long log that stands still costs a heading fit a row.
START_STRIDE = 0.5


def run_start(t: ArrayLike, truth: Truth, valid: ArrayLike, odometry: ArrayLike | None = None,
              max_gap: float | None = 0.5, *, hint: str = ""
              ) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:
    """The first row from which a run can start from the truth: the row, its truth pose and
    that pose's covariance (:func:`odomkit.truth.start_pose`).

    The whole run of ``odomkit evaluate``, the whole-log window (``--window`` not given) of
    ``evaluate`` and ``fit-noise``, and ``odomkit track --truth`` all start here. It is the
    first row with valid truth, unless the truth has no heading and its positions give none
    there (:func:`odomkit.truth.start_heading`: a GPS that starts with the log has fixes on
    one side of its first rows only; or the fixes stray from a smooth path, or the robot
    stands still); then it is the first row after it where they give one. Rows are tried
    :data:`START_STRIDE` apart, then the rows between the last tried row that gave no
    heading and the first that gave one, in order: so the row found is the first that gives
    a heading, unless a heading could be had for less than :data:`START_STRIDE` between two
    tried rows that gave none.

    Parameters
    ----------
    t : array_like, shape (N,)
        Time of each log row [s], non-decreasing.
    truth : Truth
    valid : array_like of bool, shape (N,)
        Rows with valid truth (:func:`odomkit.truth.truth_at`).
    odometry : array_like, shape (N, 3), optional
        The odometry's own path at ``t`` (dead-reckoned from the origin, any frame), which a
        start heading fitted to position-only truth aligns to the fixes; None for truth with
        heading (or a heading fitted to the fixes alone).
    max_gap : float or None
        As in :func:`odomkit.truth.truth_at`.
    hint : str
        Appended to the error when no row gives a heading (``"give --initial-pose"``).

    Returns
    -------
    (row, pose (3,), cov (3, 3)): the row, and :func:`odomkit.truth.start_pose`'s pose and
    covariance there; InputError when no row has valid truth, or the position-only truth
    gives a heading at none.
    """
    from odomkit.truth import no_overlap, start_pose

    t = np.asarray(t, dtype=float)
    rows = np.flatnonzero(np.asarray(valid, dtype=bool))
    if rows.size == 0:
        raise InputError(no_overlap(truth, t), source=truth.source)
    along = None if odometry is None else (t, np.asarray(odometry, dtype=float))

    def at(row: int) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        try:
            return start_pose(truth, float(t[row]), max_gap, odometry=along)
        except InputError:
            if truth.has_heading:  # nothing to fit: a real error
                raise
            return None

    tried, failed = -np.inf, -1  # time of the last row tried; its position in ``rows`` if it failed
    for i, row in enumerate(rows.tolist()):
        if t[row] < tried + START_STRIDE:
            continue
        tried = float(t[row])
        found = at(row)
        if found is None:
            failed = i
            continue
        for back in rows[failed + 1:i].tolist():  # the rows skipped since the last failure
            earlier = at(back)
            if earlier is not None:
                return back, *earlier
        return row, *found
    end = "" if not hint else f"; {hint}"
    raise InputError(f"the truth has no heading, and its positions give none at any of the log's rows with "
                     f"truth ({clock_text(t[rows[0]])}..{clock_text(t[rows[-1]])} s; the fixes are too few, "
                     "stray from a "
                     "smooth path by more than 3 --truth-sigma, or the robot hardly moves), so there is no "
                     f"pose to start from{end}", source=truth.source)


#: Odometry travel [m] below which the robot is taken to stand (:func:`standing_start`): a
#: millimetre, more than rounding and less than any drive (a turn on the spot travels none).
REST_TRAVEL = 1e-3


def stands_at(travel: ArrayLike, row: int) -> bool:
    """Whether the robot stands at log row ``row``: its odometry travels at most
    :data:`REST_TRAVEL` over the step after it (``travel``: :func:`cumulative_travel`, (N,));
    False at the last row."""
    s = np.asarray(travel, dtype=float)
    return row + 1 < s.size and float(s[row + 1] - s[row]) <= REST_TRAVEL


def standing_start(t: ArrayLike, truth: Truth, valid: ArrayLike, odometry: ArrayLike, travel: ArrayLike,
                   start: int, end: int) -> tuple[float, float, int] | None:
    """The start heading of a run from log row ``start`` where the robot stands still, taken
    from the first fixes after it moves: (heading [rad], its variance [rad²], the row ``r`` it
    was fitted at), or None where the robot does not stand at ``start`` or no heading is had
    in reach.

    Fixes of a robot standing still give no heading (:func:`odomkit.truth.start_heading`),
    but a robot leaves with the heading it stood at. So where the odometry travels less than
    :data:`REST_TRAVEL` over the first step from ``start``, the heading is fitted as
    :func:`run_start` fits a run's (the odometry's own path aligned to the fixes), at the
    first row ``r`` after ``start`` where the fixes give one, and turned back by the
    odometry's own turn from ``start`` to ``r`` (a turn on the spot while standing): the
    heading at ``start`` is θ_r − (θ_odo[r] − θ_odo[start]), with θ_r's variance. Rows are
    tried up to :data:`odomkit.truth.WIDEST_HEADING_SPAN` / 2 seconds after the robot
    moves (the widest fit centred there holds only fixes after it: past that, a heading
    that cannot be had is not for want of motion) and before ``end``.

    The odometry's turn from ``start`` to ``r`` has the odometry's error, which the run's own
    covariance from ``start`` then counts once more: conservative, and nothing while the
    robot stands (no motion, no noise).

    Parameters
    ----------
    t : array_like, shape (N,)
        Time of each log row [s], non-decreasing.
    truth : Truth
        Position-only truth.
    valid : array_like of bool, shape (N,)
        Rows with valid truth (:func:`odomkit.truth.truth_at`).
    odometry : array_like, shape (N, 3)
        The odometry's own path at ``t`` (dead-reckoned from the origin, any frame).
    travel : array_like, shape (N,)
        Odometry path length from row 0 to each row [m] (:func:`cumulative_travel`).
    start, end : int
        The run's first and last rows (a window's).
    """
    from odomkit.truth import WIDEST_HEADING_SPAN

    t = np.asarray(t, dtype=float)
    moved = np.asarray(travel, dtype=float)[start:end + 1] - float(np.asarray(travel, dtype=float)[start])
    if moved.size < 2 or not stands_at(travel, start):
        return None
    stands = int(np.argmax(moved > REST_TRAVEL)) - 1 if np.any(moved > REST_TRAVEL) else moved.size - 1
    reach = int(np.searchsorted(t, t[start + stands] + WIDEST_HEADING_SPAN / 2, side="right")) - 1
    rows = np.zeros(t.size, dtype=bool)
    rows[start + 1:min(reach, end - 1) + 1] = True
    rows &= np.asarray(valid, dtype=bool)
    if not rows.any():
        return None
    poses = np.asarray(odometry, dtype=float)
    try:
        row, pose, cov = run_start(t, truth, rows, poses, None)
    except InputError:
        return None
    return float(pose[2] - (poses[row, 2] - poses[start, 2])), float(cov[2, 2]), row


_LATE_START = " starts at "
_LATE_REASONS = ("the first log time inside the truth", "the first time the position-only truth gives")


def is_late_start_note(text: str) -> bool:
    """Whether ``text`` is a :func:`late_start_note` (a report shows the track's own once, not
    again for each scoring of the same log)."""
    return _LATE_START in text and any(reason in text for reason in _LATE_REASONS)


def late_start_note(source: str, what: str, t: ArrayLike, row: int, first_valid: int) -> str:
    """One line on a run (``what``: "the track", "the whole-log window") that starts at log
    row ``row`` (:func:`run_start`) rather than at row 0: why (``first_valid``, the first
    row with truth, tells), and how many rows and seconds before it are left out."""
    t = np.asarray(t, dtype=float)
    why = (_LATE_REASONS[0] if row == first_valid else
           f"{_LATE_REASONS[1]} a heading (before it the fixes around the start "
           "are too few or on one side only, stray from a smooth path, or the robot stands still)")
    return (f"{source}: {what}{_LATE_START}{clock_text(t[row])} s, {why}; the {row} row(s) before it "
            f"({t[row] - t[0]:.4g} s) are left out")
