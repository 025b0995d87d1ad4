"""A truth interpolated between sparse knots: detected, measured and said.

Some datasets give as "ground truth" a reference computed at sparse keyframes (a SLAM
back end's optimised poses, a survey's marks) and interpolated linearly to every row of
the log: its positions then lie exactly on straight, equally timed lines between the
knots, and its heading is held between them and steps at each (the TUC SLAM dataset's
5 Hz truth: 83–84 % of its moving fixes on such lines between knots 2.2–2.4 s apart, its
heading stepping by up to 1.7–1.9 rad; at 1265–1268 s the odometry turns smoothly by
1.56 rad while the truth's heading sits at −0.19 rad, then jumps to −1.63). Such a reference
cuts the corners with chords and turns late. A window that ends between two knots is
scored against that interpolation, and its error is taken for the odometry's: on TUC,
10 s windows came out inside their 95 % ellipse only 71 % of the time. Nothing else
says why.

No measuring truth (GPS, motion capture, a total station) puts three consecutive fixes
on one line, equally timed, to rounding while the vehicle moves: its noise alone (a
millimetre, or a unit in the last written digit) moves the middle fix off the line by
far more than :data:`STEP_TOLERANCE` of a step. A noise-free simulated truth can: a
straight drive at constant speed is such a line throughout. So a line alone proves
nothing; what no moving vehicle does is change its direction at a point, and the
interpolated truth does so at each knot. :func:`truth_knots` therefore counts the straight
runs, their span (the knots' spacing), and the turns taken within one or two fixes
between two runs while moving; :attr:`TruthKnots.interpolated` needs all three.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from odomkit.truth import Truth

__all__ = ["INTERPOLATED_ADVICE", "interpolated_note", "KNOT_FIXES", "MIN_MOVING", "MIN_RUN_FIXES",
           "MIN_SHARE", "MIN_TURNS", "MOVING", "ROUNDING_ULPS", "STEP_TOLERANCE", "TURN", "TruthKnots",
           "truth_knots", "written_resolution"]

#: A middle fix counts as on the line through its neighbours (at the place their times
#: give it) when it is off it by at most this share of its longer step. An interpolation
#: written with 14 significant digits (TUC) is off by 1e-11 of its 5 cm steps, one written
#: with 10 digits by up to about 2e-7 of a 10 cm step 10 m from the origin; a millimetre's
#: noise on a 5 cm step moves it 1e-2 off, a 0.1 mm motion capture on a 1 cm step 1e-2:
#: three orders beyond. A noise-free arc passes only where its radius exceeds 50 000 steps.
STEP_TOLERANCE = 1e-5
#: ... or by at most this many units in the last place of the largest coordinate (rounding
#: of float64 arithmetic; the step's share covers text written with fewer digits).
ROUNDING_ULPS = 64
#: A step counts as moving where it exceeds this share of the largest coordinate (at least
#: 1 m): a truth standing on one keyframe repeats its fix exactly and tells nothing.
MOVING = 1e-9
#: Interpolated only where at least this share of the moving fix triples lie on lines...
MIN_SHARE = 0.5
#: ... two knots joined by a line lie at least this many fix intervals apart (median): three
#: fixes or more on the line between them, where a noisy truth's chance line is one triple,
#: its knots two intervals apart...
MIN_RUN_FIXES = 4
#: ... and the path turns by more than :data:`TURN` [rad] within one or two fixes between
#: two runs, while moving, at least this many times: a straight drive at constant speed
#: (one run, no turn) or a square driven with stops at its corners (runs cut by standing
#: still) is a noise-free simulation, not an interpolation.
MIN_TURNS = 3
TURN = 0.01
#: Knots at most this many fixes long join two runs (a knot off the fixes' grid leaves two
#: fixes off both lines, as on TUC); a longer bend is a smooth turn, not a knot.
KNOT_FIXES = 2
#: Fewer moving fix triples than this tell nothing.
MIN_MOVING = 20
#: What to do about an interpolated truth (``odomkit check``'s advice, the warnings' end).
INTERPOLATED_ADVICE = ("score with windows much longer than the knots' spacing, or give the keyframes alone "
                       "as the truth (window ends then fall next to them)")


@dataclass(frozen=True)
class TruthKnots:
    """How much of a truth lies on straight lines between knots (:func:`truth_knots`).

    Parameters
    ----------
    share : float
        Of the fix triples where the truth moves (both steps), the share whose middle fix
        lies on the line through its neighbours, where their times put it; NaN where fewer
        than :data:`MIN_MOVING` triples move.
    spacing : float
        The median time [s] between two knots joined by a straight run (NaN without one).
    turns : int
        Turns by more than :data:`TURN` rad within :data:`KNOT_FIXES` fixes between two
        straight runs, the truth moving throughout.
    largest_turn : float
        The largest of those turns [rad] (0 without one).
    moving : int
        Fix triples where the truth moves.
    fix_interval : float
        The median time between fixes [s].
    step : float
        The median length of a moving step [m] (NaN without one).
    resolution : float
        The coordinates' written resolution [m]: 10⁻ᵈ where every one is written with d
        decimals or fewer (``1e-4`` for a file of 0.1 mm), 0 where they carry more digits
        than that tells (:func:`written_resolution`). A truth written coarser than
        :data:`STEP_TOLERANCE` of its step cannot show an interpolation: its rounding puts
        three fixes on one line by chance (a noise-free arc written with 3 decimals, 86 %
        of its fixes), and moves an interpolated one off it.
    heading_held : float or None
        Of the steps where the truth moves, the share whose heading is exactly that of the
        fix before (None without heading, NaN without a moving step).
    heading_interval : float or None
        The median time [s] between two changes of the heading, the truth moving from one
        to the other (NaN where it never changes twice so).
    heading_step : float or None
        The largest change of the heading between two fixes while moving [rad].
    """

    share: float
    spacing: float
    turns: int
    largest_turn: float
    moving: int
    fix_interval: float
    step: float
    resolution: float
    heading_held: float | None = None
    heading_interval: float | None = None
    heading_step: float | None = None

    @property
    def interpolated(self) -> bool:
        """Whether the truth is interpolated between knots: :data:`MIN_SHARE` of its moving
        triples on lines, runs of :data:`MIN_RUN_FIXES` fix intervals, :data:`MIN_TURNS`
        turns at knots, in fixes written finely enough to tell (``resolution``)."""
        return (self.moving >= MIN_MOVING and self.share >= MIN_SHARE and self.turns >= MIN_TURNS
                and self.spacing >= MIN_RUN_FIXES * self.fix_interval * (1 - 1e-9)
                and self.resolution <= STEP_TOLERANCE * self.step)

    def describe(self) -> str:
        """What the truth is, in its numbers: the finding's message and the warnings' text
        (without :data:`INTERPOLATED_ADVICE`)."""
        said = (f"the truth's fixes lie on straight lines between knots about {self.spacing:.2g} s apart "
                f"({100 * self.share:.0f} % of its moving fixes; it turns at the knots, by up to "
                f"{self.largest_turn:.2g} rad at one)")
        held, interval = self.heading_held, self.heading_interval
        if held is not None and held >= MIN_SHARE and interval is not None and math.isfinite(interval):
            step = self.heading_step or 0.0
            said += f" and its heading holds for {interval:.2g} s then steps (up to {step:.2g} rad)"
        return (said + ": a reference interpolated between keyframes; window ends between its knots carry "
                "its interpolation error (corners cut, heading late) as odometry error")


def truth_knots(truth: Truth) -> TruthKnots:
    """Measure how far ``truth`` is a straight-line interpolation between sparse knots.

    For each three consecutive fixes where the truth moves (both steps longer than
    :data:`MOVING` of its largest coordinate), the middle fix is compared with the point
    its time gives on the line through the other two, x₀ + (x₂ − x₀)·(t₁ − t₀)/(t₂ − t₀):
    on the line to within :data:`STEP_TOLERANCE` of the longer step (or
    :data:`ROUNDING_ULPS` ulps) is collinear and equally timed, as linear interpolation
    leaves it. Consecutive collinear triples make a straight run; the fixes between runs
    are knots. A knot of at most :data:`KNOT_FIXES` fixes between two runs is a turn
    where the runs' directions differ by more than :data:`TURN`.

    Parameters
    ----------
    truth : Truth, K fixes

    Returns
    -------
    TruthKnots

    Examples
    --------
    A truth interpolated at 5 Hz between knots 2 s apart on a zigzag:

    >>> knots_t = 2.0 * np.arange(12)
    >>> knots_xy = np.column_stack((np.sqrt(2) * knots_t, np.where(np.arange(12) % 2 == 0, 0.0, np.pi)))
    >>> t = np.arange(0.0, 22.0 + 1e-9, 0.2)
    >>> xy = np.column_stack([np.interp(t, knots_t, knots_xy[:, k]) for k in (0, 1)])
    >>> found = truth_knots(Truth(t, xy))
    >>> found.interpolated, round(found.spacing, 6), found.turns, round(found.share, 3)
    (True, 2.0, 10, 0.908)
    """
    t = np.asarray(truth.t, dtype=float)
    xy = np.asarray(truth.xy, dtype=float)
    fix_interval = float(np.median(np.diff(t))) if t.size > 1 else math.nan
    theta = truth.theta
    if t.size < 3:
        none = None if theta is None else math.nan
        return TruthKnots(math.nan, math.nan, 0, 0.0, 0, fix_interval, math.nan, written_resolution(xy),
                          none, none, none)
    scale = max(1.0, float(np.max(np.abs(xy))))
    step_xy = np.diff(xy, axis=0)
    step = np.hypot(step_xy[:, 0], step_xy[:, 1])
    moves = step > MOVING * scale  # (K-1,) per step
    moving = moves[:-1] & moves[1:]  # (K-2,) per triple, centred on fixes 1..K-2
    frac = (t[1:-1] - t[:-2]) / (t[2:] - t[:-2])
    off_line = xy[1:-1] - (xy[:-2] + (xy[2:] - xy[:-2]) * frac[:, None])
    tolerance = np.maximum(STEP_TOLERANCE * np.maximum(step[:-1], step[1:]),
                           ROUNDING_ULPS * float(np.finfo(float).eps) * scale)
    on_line = moving & (np.hypot(off_line[:, 0], off_line[:, 1]) <= tolerance)
    n_moving = int(np.count_nonzero(moving))
    share = float(np.count_nonzero(on_line)) / n_moving if n_moving else math.nan
    starts, ends = _runs(on_line)  # triples a..b: fixes a..b+2 on one line
    spacing = _spacing(t, moving, on_line)
    turns, largest = _turns(xy, moving, starts, ends)
    held = interval = largest_step = None
    if theta is not None:
        held, interval, largest_step = _heading_holds(t, np.asarray(theta, dtype=float), moves)
    typical = float(np.median(step[moves])) if moves.any() else math.nan
    return TruthKnots(share, spacing, turns, largest, n_moving, fix_interval, typical, written_resolution(xy),
                      held, interval, largest_step)


def written_resolution(values: NDArray[np.float64]) -> float:
    """The decimal resolution the ``values`` were written with: the largest 10⁻ᵈ
    (d = 0, 1, ...) of which every one is a whole multiple (to 1 % of it), or 0 where none
    is up to the digits a float64 holds (about 13 significant: a truth written in full).

    Examples
    --------
    >>> written_resolution(np.array([[1.25, -3.5], [0.125, 2.0]])), written_resolution(np.array([0.1, 1 / 3]))
    (0.001, 0.0)
    """
    v = np.asarray(values, dtype=float).reshape(-1)
    largest = float(np.max(np.abs(v))) if v.size else 0.0
    for d in range(16):
        scaled = v * 10.0**d
        if largest * 10.0**d > 1e13:
            break  # float64 rounding reaches 1 % of the unit here
        if np.all(np.abs(scaled - np.round(scaled)) <= 0.01):
            return 10.0**-d
    return 0.0


def _runs(flags: NDArray[np.bool_]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """First and last index of each maximal run of True in ``flags``."""
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1


def _spacing(t: NDArray[np.float64], moving: NDArray[np.bool_], on_line: NDArray[np.bool_]) -> float:
    """The median time [s] between the centres of two knots (maximal runs of moving triples
    off the line) joined by one straight run. A knot's centre is halfway between its first
    and last fix: a knot between two fixes of the grid leaves both off the lines, and lies
    between them."""
    first, last = _runs(moving & ~on_line)
    if first.size < 2:
        return math.nan
    centre = 0.5 * (t[first + 1] + t[last + 1])
    lined = np.concatenate(([0], np.cumsum(on_line)))
    between = first[1:] - last[:-1] - 1  # triples between two knots: all on the line, none standing
    joined = (between >= 1) & (lined[first[1:]] - lined[last[:-1] + 1] == between)
    return float(np.median(np.diff(centre)[joined])) if joined.any() else math.nan


def _turns(xy: NDArray[np.float64], moving: NDArray[np.bool_], starts: NDArray[np.intp],
           ends: NDArray[np.intp]) -> tuple[int, float]:
    """How many times, and by how much at most [rad], the direction changes by more than
    :data:`TURN` between two straight runs joined by at most :data:`KNOT_FIXES` moving
    triples off both lines."""
    if starts.size < 2:
        return 0, 0.0
    chord = xy[ends + 2] - xy[starts]
    direction = np.arctan2(chord[:, 1], chord[:, 0])
    gap = starts[1:] - ends[:-1] - 1  # triples between two runs
    moving_count = np.concatenate(([0], np.cumsum(moving)))
    all_moving = moving_count[starts[1:]] - moving_count[ends[:-1] + 1] == gap
    joined = (gap >= 1) & (gap <= KNOT_FIXES) & all_moving
    turn = np.abs(np.angle(np.exp(1j * np.diff(direction))))[joined]
    turned = turn > TURN
    return int(np.count_nonzero(turned)), float(np.max(turn[turned])) if turned.any() else 0.0


def _heading_holds(t: NDArray[np.float64], theta: NDArray[np.float64], moves: NDArray[np.bool_]
                   ) -> tuple[float, float, float]:
    """Of the moving steps: the share with the heading exactly held, the median time between
    consecutive changes with the truth moving between them, and the largest change."""
    change = np.abs(np.diff(theta))
    held = change <= ROUNDING_ULPS * float(np.finfo(float).eps) * max(1.0, float(np.max(np.abs(theta))))
    n = int(np.count_nonzero(moves))
    if n == 0:
        return math.nan, math.nan, math.nan
    share = float(np.count_nonzero(held & moves)) / n
    changes = np.flatnonzero(moves & ~held)
    largest = float(np.max(change[changes])) if changes.size else 0.0
    if changes.size < 2:
        return share, math.nan, largest
    standing = np.concatenate(([0], np.cumsum(~moves)))
    between = standing[changes[1:]] - standing[changes[:-1]] == 0  # no standing step in between
    gaps = (t[changes[1:] + 1] - t[changes[:-1] + 1])[between]
    return share, float(np.median(gaps)) if gaps.size else math.nan, largest


def interpolated_note(truth: Truth) -> str | None:
    """The warning of a command that scores window ends against ``truth`` (``evaluate
    --window``, ``fit-noise``) where it is interpolated between knots: what
    :meth:`TruthKnots.describe` says and :data:`INTERPOLATED_ADVICE`; None otherwise."""
    knots = truth_knots(truth)
    if not knots.interpolated:
        return None
    return f"{knots.describe()}: {INTERPOLATED_ADVICE}"
