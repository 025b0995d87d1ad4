"""Ground truth on its own clock: interpolation at the evaluated times, gaps, headings.

A :class:`Truth` is a sequence of timed fixes (positions, and headings when the truth
system measures them) that need not share the log's clock. :func:`truth_at` interpolates
it at any times, leaving out (and counting) the times outside its span or inside a gap
longer than ``max_gap``. Where the truth has no heading, :func:`heading_from_positions`
fits one to the positions around a time, with its variance, so that a pose that must
start from truth can still be given one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import units, validate
from odomkit.angles import unwrap_angle, wrap_angle
from odomkit.errors import InputError
from odomkit.log import OdometryLog, clock_text

__all__ = ["heading_by_alignment", "heading_from_positions", "heading_span", "heading_spans",
           "HEADING_SIGMA_SOUGHT", "longest_gap", "MAX_HEADING_SIGMA", "WIDEST_HEADING_SPAN",
           "GROSS_HEADING_OFF", "BACKWARDS_SHARE", "heading_backwards", "heading_against_motion",
           "heading_off_motion", "HEADING_OFF_CAUSES",
           "implausible_speed", "latlon_as_metres", "BURST_RATIO", "stamp_bursts", "bursts_note",
           "MAX_RESIDUAL_SIGMAS", "BAG_TIME_HINT", "clock_unit_hint", "no_overlap", "scatter_sigma",
           "start_heading", "start_pose", "Truth",
           "truth_at", "truth_from_log", "truth_noise", "TruthSamples"]

#: A fitted heading whose standard deviation exceeds this [rad] (about 23°) is refused:
#: the fixes do not support it (the robot barely moved, or the fixes are too noisy).
MAX_HEADING_SIGMA = 0.4
#: Where the truth states its noise σ, a heading fit whose residual RMS per axis exceeds
#: this many σ is refused: the fixes do not lie on a smooth path (a glitch, a jump, a turn
#: too sharp for a quadratic). With the 5–7 fixes of a fit the residual has 4–8 degrees of
#: freedom, so honest fixes exceed 3σ with a probability below 1e-6.
MAX_RESIDUAL_SIGMAS = 3.0
#: A heading fit of :func:`heading_from_positions` without a given span widens its span
#: (doubling it, up to :data:`WIDEST_HEADING_SPAN`) until the heading's standard deviation
#: is below this [rad]: dense fixes of a noisy truth (a 10 Hz GPS with 1.5 m noise) give
#: no usable heading over the 1 s a motion capture needs, and over 8 s a good one.
HEADING_SIGMA_SOUGHT = 0.05
#: The widest span [s] a heading fit widens to (a sparse truth's own span may be wider:
#: it is kept, not widened).
WIDEST_HEADING_SPAN = 10.0
#: A start whose odometry travels less than this share of the truth's own displacement over
#: the heading fit's span stood still while the fixes wandered (:func:`start_heading`).
STANDING_SHARE = 0.5


@dataclass(frozen=True)
class Truth:
    """Timed ground-truth fixes.

    Parameters
    ----------
    t : ndarray, shape (K,)
        Time of each fix [s], strictly increasing (the readers sort and drop duplicates).
    xy : ndarray, shape (K, 2)
        Position [m].
    theta : ndarray, shape (K,), optional
        Heading [rad], continuous (unwrapped); None for position-only truth.
    sigma : float
        Standard deviation of each truth position per axis [m] (``--truth-sigma``).
    source : str
        Where the truth came from (used in messages).
    heading_sigma : float
        Standard deviation of each truth heading [rad] (``--truth-heading-sigma``; a motion
        capture's rigid-body orientation noise). A window that starts from the truth
        heading carries it as start variance, and an end compared with the truth heading
        adds it; ignored for position-only truth.
    time_sigma : float
        Standard deviation of each fix's time against the log's clock [s]
        (``--truth-time-sigma``; jitter and latency between two clocks): a fix δ off is off
        by the velocity times δ, so it adds (v·σ)² along the track where the robot moves and
        nothing where it stands; the heading's share ω·δ counts only where a start heading
        is fitted to position-only truth (:mod:`odomkit.window_errors` says why, under "The
        truth's clock").
    stated_sigma : float
        The position σ per axis [m] the truth's own file states (a GPS fix's covariance, a
        bag's NavSatFix) where ``sigma`` was not given (0: none stated). No fit uses it
        unasked (``--truth-sigma`` takes it into ``sigma``); a check may judge against it,
        and says so (:func:`odomkit.calibrate.check_ratios.check_truth_motion`): the
        scatter of a GPS's fixes about a smooth path misses its error correlated in time.
    """

    t: NDArray[np.float64]
    xy: NDArray[np.float64]
    theta: NDArray[np.float64] | None = None
    sigma: float = 0.0
    source: str = "<memory>"
    heading_sigma: float = 0.0
    time_sigma: float = 0.0
    stated_sigma: float = 0.0

    def __post_init__(self) -> None:
        error = partial(InputError, source=self.source)
        t = validate.shape(self.t, "truth time", ("K",), error=error)
        if t.size == 0:
            raise error("the truth has no fixes")
        validate.shape(self.xy, "truth positions", (t.size, 2), error=error)
        if self.theta is not None:
            validate.shape(self.theta, "truth heading", (t.size,), error=error)
        for name, values in (("time", self.t), ("position", self.xy), ("heading", self.theta)):
            if values is not None and not np.all(np.isfinite(values)):
                raise error(f"truth {name} holds NaN or infinite values; expected finite numbers")
        if t.size > 1 and not np.all(np.diff(t) > 0):
            raise error("truth times must be strictly increasing")
        validate.non_negative(self.sigma, "truth sigma", unit="m", error=error)
        validate.non_negative(self.heading_sigma, "truth heading sigma", unit="rad", error=error)
        validate.non_negative(self.time_sigma, "truth time sigma", unit="s", error=error)
        validate.non_negative(self.stated_sigma, "truth stated sigma", unit="m", error=error)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def has_heading(self) -> bool:
        """Whether the truth measures heading (False for position-only truth)."""
        return self.theta is not None


@dataclass(frozen=True)
class TruthSamples:
    """The truth at a set of asked times (see :func:`truth_at`).

    Parameters
    ----------
    poses : ndarray, shape (n, 3)
        ``[x, y, θ]`` at each asked time [m, m, rad]; θ is NaN when the truth has no
        heading, and the whole row is NaN where ``valid`` is False.
    valid : ndarray of bool, shape (n,)
        Inside the truth's span and not inside a gap longer than ``max_gap``.
    outside : int
        How many asked times lie outside the truth's span.
    in_gaps : int
        How many lie inside a gap longer than ``max_gap``.
    """

    poses: NDArray[np.float64]
    valid: NDArray[np.bool_]
    outside: int
    in_gaps: int


def truth_at(truth: Truth, times: ArrayLike, max_gap: float | None = 0.5) -> TruthSamples:
    """Linear interpolation of the truth at ``times``, with gaps left out and counted.

    x, y and the continuous (unwrapped) θ are interpolated linearly between the two fixes
    around each time. A time that falls between two fixes more than ``max_gap`` seconds
    apart is left out (a truth system that lost the robot for a while says nothing about
    where it was); a time equal to a fix is always kept. A gap is never shorter than twice
    the truth's median fix spacing: for 1 Hz GPS the default 0.5 s would otherwise put every
    row in a "gap" and report that the truth does not overlap the log at all.

    Parameters
    ----------
    truth : Truth, K fixes
    times : array_like, shape (n,)
        Times to sample [s], in any order.
    max_gap : float or None
        Longest gap between fixes to interpolate across [s] (at least twice the median
        fix spacing); None for no limit.

    Returns
    -------
    TruthSamples

    Examples
    --------
    >>> tr = Truth(np.array([0.0, 1.0, 2.0, 6.0]), np.array([[0.0, 0], [1, 0], [2, 0], [6, 0]]),
    ...            np.array([0.0, 0.5, 1.0, 1.5]))
    >>> s = truth_at(tr, [0.5, 4.0, 7.0], max_gap=1.5)
    >>> s.poses[0].tolist(), s.valid.tolist(), s.outside, s.in_gaps
    ([0.5, 0.0, 0.25], [True, False, False], 1, 1)
    """
    t = np.asarray(times, dtype=float).reshape(-1)
    if max_gap is not None:
        max_gap = validate.positive(max_gap, "max_gap", unit="s", error=InputError)
    inside = (t >= truth.t[0]) & (t <= truth.t[-1])
    # Interval i holds truth.t[i] <= t < truth.t[i+1]; a time equal to a fix is exact.
    i = np.clip(np.searchsorted(truth.t, t, side="right") - 1, 0, max(len(truth) - 2, 0))
    on_fix = np.isin(t, truth.t)
    gap = np.zeros(t.size, dtype=bool)
    if max_gap is not None and len(truth) > 1:
        gap = inside & ~on_fix & (truth.t[i + 1] - truth.t[i] > longest_gap(truth, max_gap))
    valid = inside & ~gap
    poses = np.full((t.size, 3), np.nan)
    if valid.any():
        tv = t[valid]
        poses[valid, 0] = np.interp(tv, truth.t, truth.xy[:, 0])
        poses[valid, 1] = np.interp(tv, truth.t, truth.xy[:, 1])
        if truth.theta is not None:
            poses[valid, 2] = np.interp(tv, truth.t, truth.theta)
    return TruthSamples(poses, valid, int(np.count_nonzero(~inside)), int(np.count_nonzero(gap)))


def longest_gap(truth: Truth, max_gap: float | None) -> float:
    """The longest gap between fixes [s] that :func:`truth_at` interpolates across:
    ``max_gap`` (None: no limit), but never under twice the truth's median fix spacing."""
    if max_gap is None:
        return math.inf
    spacing = float(np.median(np.diff(truth.t))) if len(truth) > 1 else 0.0
    return max(max_gap, 2.0 * spacing)


def truth_noise(truth: Truth, scatter: float | None = None) -> float:
    """The truth's position noise [m per axis] a check should allow for: its stated σ, or
    its fixes' own scatter about a smooth path (:func:`scatter_sigma`, or ``scatter`` where
    the caller has computed it) where that is larger."""
    return max(truth.sigma, (scatter_sigma(truth) if scatter is None else scatter) or 0.0)


def clock_unit_hint(log_span: float, truth_span: float) -> str | None:
    """Where one clock's span is a time unit's factor times the other's
    (:func:`odomkit.units.time_unit_factor`: within 2x of 1000, 1e6, 1e9), whose time is
    likely in that unit read as seconds, and the flag that reads it: ``"the truth spans 900 s
    and the log 9e+05 s, a factor 1e+03: the log's time is likely in ms read as seconds
    (--time-unit ms)"``; else None. Spans in seconds as read."""
    if not (log_span > 0 and truth_span > 0):
        return None
    for ratio, whose, flag in ((truth_span / log_span, "the truth's", "--truth-time-unit"),
                               (log_span / truth_span, "the log's", "--time-unit")):
        if (unit := units.time_unit_factor(ratio)) is not None:
            return (f"the truth spans {truth_span:.4g} s and the log {log_span:.4g} s, a factor {ratio:.3g}: "
                    f"{whose} time is likely in {unit} read as seconds ({flag} {unit})")
    return None


#: What mends a bag timed by its messages' header stamps that misses its truth's clock
#: (:func:`no_overlap`; a bag's truth topic on another clock: :func:`odomkit.io.bag.read_bag`).
BAG_TIME_HINT = ("--bag-time, which times the bag by when it received its messages: their header stamps "
                 "may run on the robot's own clock")


def no_overlap(truth: Truth, times: ArrayLike, log_clock: object = None) -> str:
    """One line on a truth that covers fewer than two of ``times`` (the log's rows): both
    spans, and the options that move or widen the truth's; where one span is a time unit's
    factor times the other's, the flag that reads the one off (:func:`clock_unit_hint`: a
    log in ms against a truth in s needs ``--time-unit ms``, not ``--truth-time-unit``).
    ``log_clock`` is the log's ``meta["time"]``: ``"header"`` for a bag timed by its
    messages' header stamps, which may run on the robot's own clock (a Pioneer's, 9.5 days
    behind the bag's: user study), so the line names ``--bag-time`` too."""
    t = np.asarray(times, dtype=float).reshape(-1)
    spans = (f"the truth ({clock_text(truth.t[0])}..{clock_text(truth.t[-1])} s) and the log "
             f"({clock_text(t[0])}..{clock_text(t[-1])} s)")
    if truth.t[0] > t[-1] or truth.t[-1] < t[0]:
        hint = clock_unit_hint(float(t[-1] - t[0]), float(truth.t[-1] - truth.t[0]))
        if hint is not None:
            return f"{spans} do not overlap in time; {hint}"
        bag = f"; or {BAG_TIME_HINT}" if log_clock == "header" else ""
        return f"{spans} do not overlap in time; check --truth-time-unit and --truth-time-offset{bag}"
    return (f"{spans} overlap, but the log's rows there fall in gaps between fixes longer than "
            "--max-gap; check --max-gap, --truth-time-unit and --truth-time-offset")


def scatter_sigma(truth: Truth, block: int = 5) -> float | None:
    """The truth's own position noise [m per axis], from how its fixes scatter about a
    smooth path: x(t) and y(t) fitted by a quadratic in time over consecutive blocks of
    ``block`` fixes, the residuals pooled, RSS / Σ(n − 3) per axis.

    An estimate from the truth alone, beside the floor ``fit-noise`` fits from the
    odometry's window errors (``truth_sigma``): for white noise it is unbiased where a
    block's path is a quadratic to within the noise (5 fixes: 50 ms of a 100 Hz motion
    capture, 4 s of a 1 Hz GPS on a car: simulated cars' 0.5–2 m GPS came back within 5 %,
    where 7 fixes read a 1 m GPS at 1 Hz as 1.44 m); a path that bends more within a block
    adds its misfit, and noise correlated over a block (a GPS's slow multipath wander) is
    missed.
    None where fewer than two blocks fit (too few fixes).

    Parameters
    ----------
    truth : Truth
    block : int
        Fixes per block (at least 4: one degree of freedom each).
    """
    block = max(int(block), 4)
    blocks = len(truth) // block
    if blocks < 2:
        return None
    t = truth.t[: blocks * block].reshape(blocks, block)
    xy = truth.xy[: blocks * block].reshape(blocks, block, 2)
    # Per block: τ in [-1, 1] keeps the quadratic's design well conditioned.
    mid = 0.5 * (t[:, :1] + t[:, -1:])
    half = np.maximum(0.5 * (t[:, -1:] - t[:, :1]), 1e-300)
    tau = (t - mid) / half
    design = np.stack((np.ones_like(tau), tau, tau**2), axis=-1)  # (B, n, 3)
    gram = np.einsum("bni,bnj->bij", design, design)
    ok = np.linalg.matrix_rank(gram) == 3  # repeated times would leave a block singular
    if np.count_nonzero(ok) < 2:
        return None
    coef = np.linalg.solve(gram[ok], np.einsum("bni,bnk->bik", design[ok], xy[ok]))  # (B, 3, 2)
    resid = xy[ok] - np.einsum("bni,bik->bnk", design[ok], coef)
    # As an RMS of RMS's: squares of 1e200 m (a fuzzed file) would overflow to inf.
    scale = float(np.max(np.abs(resid)))
    if not math.isfinite(scale):
        return None
    if scale == 0.0:
        return 0.0
    rss = float(np.sum((resid / scale) ** 2))
    return scale * math.sqrt(rss / (2 * np.count_nonzero(ok) * (block - 3)))


#: A truth whose heading is off the direction its positions move in by more than this [rad]
#: (about 29°; the median over its stretches, folded so that driving backwards is not off)
#: has a heading that is no heading of the robot (:func:`heading_against_motion`). A random
#: heading gives π/4 (0.785); a rigid body glued on askew, a crab angle or a skid-steer's
#: slip in turns stay far below it.
GROSS_HEADING_OFF = 0.5
#: The stretches :func:`heading_against_motion` compares: this long [s], and moving at least
#: :data:`_MIN_CHORD` [m] and ten times the truth's noise, so that the chord's direction is
#: good to a tenth of a radian.
_CHORD_SPAN = 1.0
_MIN_CHORD = 0.05
#: Where fewer than :data:`_HEADING_STRETCHES` stretches of one length move that far (a
#: slow robot against a truth of stated noise: a Pioneer at 0.2 m/s against σ = 3.4 cm has
#: none of 1 s), :func:`heading_against_motion` tries the longer ones [s].
_CHORD_SPANS = (_CHORD_SPAN, 2.0, 4.0, 8.0)
_HEADING_STRETCHES = 10


def _chords(truth: Truth, max_gap: float | None, span: float = _CHORD_SPAN
            ) -> tuple[TruthSamples, TruthSamples, NDArray[np.bool_]]:
    """The truth at the two ends of non-overlapping stretches of ``span`` seconds, and which
    stretches lie inside it without a gap."""
    starts = np.arange(truth.t[0], truth.t[-1] - span, span)
    before = truth_at(truth, starts, max_gap)
    after = truth_at(truth, starts + span, max_gap)
    return before, after, before.valid & after.valid


def heading_against_motion(truth: Truth, max_gap: float | None = 0.5) -> tuple[float, int]:
    """How far the truth's heading is off the direction its own positions move in [rad].

    A wheeled robot moves along its heading (forwards or backwards), and on a path of
    constant curvature the chord between two fixes points exactly along the heading half
    way between them; so over non-overlapping stretches of :data:`_CHORD_SPAN` seconds the
    chord's direction is compared with the mean of the two ends' headings. The truth alone
    is used (no odometry: every command that reads a truth can ask). Each stretch's
    difference is folded into [0, π/2] (a robot reversing is not off); stretches that move
    less than :data:`_MIN_CHORD` or ten times the truth's noise (:func:`truth_noise`: a spin in
    place has no direction of motion) or that reach into a gap are left out. Where fewer
    than ten stretches are left, stretches of 2, 4 and then 8 s are tried (the first that
    gives ten, else the one that gives most): a slow robot against a truth of stated noise.

    A median far above a crab angle (:data:`GROSS_HEADING_OFF`) means the heading is not the
    robot's: degrees read as radians, a quaternion read in another order, a motion
    capture's body turned against the robot's axis, or a base that moves sideways.
    ``odomkit check`` measures a small misalignment more finely, on straight stretches
    (:func:`odomkit.calibrate.check_truth.heading_misalignment`).

    Parameters
    ----------
    truth : Truth with heading
    max_gap : stretches reaching into a truth gap longer than this are left out [s]

    Returns
    -------
    (off, stretches) : the median folded difference [rad] and the number of stretches it
        rests on; NaN and 0 where no stretch moves enough.

    Raises
    ------
    ValueError
        For a position-only truth.
    """
    off, stretches, _ = _against_motion(truth, max_gap)
    return off, stretches


def _against_motion(truth: Truth, max_gap: float | None) -> tuple[float, int, float]:
    """:func:`heading_against_motion` and the stretches' length [s] it rests on."""
    off, n, span, _ = _motion_offsets(truth, max_gap)
    return off, n, span


def _motion_offsets(truth: Truth, max_gap: float | None) -> tuple[float, int, float, float]:
    """:func:`_against_motion`, and the share of its stretches whose heading points against
    the motion (more than π/2 off it, unfolded: driving backwards, or a heading π off)."""
    if truth.theta is None:
        raise ValueError("heading_against_motion needs a truth with heading")
    least = max(_MIN_CHORD, 10.0 * truth_noise(truth))
    best = (math.nan, 0, _CHORD_SPAN, math.nan)
    for span in _CHORD_SPANS:
        before, after, use = _chords(truth, max_gap, span)
        chord = after.poses[:, :2] - before.poses[:, :2]
        use &= np.hypot(chord[:, 0], chord[:, 1]) >= least
        if use.sum() > best[1]:
            mid_heading = 0.5 * (before.poses[use, 2] + after.poses[use, 2])  # θ unwrapped: no wrap between
            off = np.abs(wrap_angle(mid_heading - np.arctan2(chord[use, 1], chord[use, 0])))
            folded = np.minimum(off, math.pi - off)
            best = (float(np.median(folded)), int(folded.size), span, float(np.mean(off > 0.5 * math.pi)))
        if best[1] >= _HEADING_STRETCHES:
            break
    return best


#: A truth whose heading points against its motion on at least this share of its stretches
#: is said to point backwards (:func:`heading_backwards`): no robot reverses so much of a drive.
BACKWARDS_SHARE = 0.9


def heading_backwards(truth: Truth, max_gap: float | None = 0.5) -> str | None:
    """One clause where the truth's heading points against the direction its positions move
    in on at least :data:`BACKWARDS_SHARE` of :data:`_HEADING_STRETCHES` or more stretches (a
    robot driving backwards all the way, or far more often a heading π off: a lawn mower's
    RTK truth whose heading was offset by π scored ATE 74.8 m against 1.48 m from its
    positions alone, silently: user study), else None (also for a position-only truth).
    :func:`heading_off_motion` folds reversing onto forwards and cannot see it."""
    if truth.theta is None:
        return None
    _, stretches, span, back = _motion_offsets(truth, max_gap)
    if stretches < _HEADING_STRETCHES or not back >= BACKWARDS_SHARE:
        return None
    return (f"the truth's heading points against the direction its positions move in on {100 * back:.0f} % "
            f"of {stretches} stretches of {span:g} s: a robot driving backwards all the way, or a heading "
            "π off (a motion-capture body's axis reversed, a heading offset by π); every start taken from it "
            "then drives the odometry backwards")


#: What makes a truth's heading no heading of the robot's (:func:`heading_off_motion`).
HEADING_OFF_CAUSES = ("a heading in degrees read as radians (name the column theta_deg), a quaternion in "
                      "another order (TUM rows are t x y z qx qy qz qw), a TUM or KITTI file whose frame "
                      "is not z-up (--truth-up: -y for a camera's, +y for a Y-up motion capture), a "
                      "motion-capture body whose axes are turned against the robot's, a truth measured at a "
                      "point far off the robot's reference point (a sensor 1.5 m ahead of a tricycle's rear "
                      "axle swings wide in its turns: give the reference point's poses), or a base that "
                      "moves sideways, which odomkit's vehicles do not")


def heading_off_motion(truth: Truth, max_gap: float | None = 0.5) -> str | None:
    """One clause saying the truth's heading is no heading of the robot's
    (:func:`heading_against_motion` beyond :data:`GROSS_HEADING_OFF`), else None (also for a
    position-only truth); :data:`HEADING_OFF_CAUSES` says why it may be."""
    if truth.theta is None:
        return None
    off, stretches, span = _against_motion(truth, max_gap)
    if not off > GROSS_HEADING_OFF:
        return None
    return (f"the truth's heading does not follow the direction its positions move in (median "
            f"{math.degrees(off):.0f}° off over {stretches} stretches of {span:g} s, a robot driving "
            "backwards counted as on it; a random heading gives 45°)")


def implausible_speed(truth: Truth, max_gap: float | None = 0.5) -> str | None:
    """One clause where the truth's positions move faster than any wheeled vehicle (the 90th
    percentile of their speed over :data:`_CHORD_SPAN`-second stretches above
    :data:`odomkit.units.FASTEST_SPEED`), else None: millimetres read as metres (a Vicon export: 0.3 m/s
    reads as 300 m/s), or a time column whose unit is too coarse."""
    before, after, use = _chords(truth, max_gap)
    if np.count_nonzero(use) < 3:
        return None
    chord = after.poses[use, :2] - before.poses[use, :2]
    speed = float(np.percentile(np.hypot(chord[:, 0], chord[:, 1]), 90)) / _CHORD_SPAN
    if not speed > units.FASTEST_SPEED:
        return None
    return (f"the truth's positions move at {speed:.3g} m/s (90th percentile over {_CHORD_SPAN:g} s "
            f"stretches), {units.FAST_TRAVEL} ({units.FASTEST_SPEED:g} m/s): likely millimetres read "
            "as metres (name the columns x_mm, y_mm) or a time unit too coarse (--truth-time-unit)")


def latlon_as_metres(truth: Truth) -> str | None:
    """One clause where the truth's x, y look like latitude and longitude in degrees read as
    metres, else None: every fix within ±90 and ±180, away from (0, 0) by more than a degree,
    and moving less than 0.1 in either over at least 10 s (a car's 1.7 km is 0.015° of
    latitude). Read so, a KITTI drive scored ATE 365 m and drift 54 969 %, and check blamed
    the speed and yaw rate swapped (user study)."""
    if len(truth) < 2 or float(truth.t[-1] - truth.t[0]) < 10.0:
        return None
    x, y = truth.xy[:, 0], truth.xy[:, 1]
    if not (np.all(np.abs(x) <= 90.0) and np.all(np.abs(y) <= 180.0)):
        return None
    moves = max(float(np.ptp(x)), float(np.ptp(y)))
    if moves >= 0.1 or max(abs(float(x.mean())), abs(float(y.mean()))) <= 1.0:
        return None
    return (f"the truth's x, y stay within {float(x.min()):.6g}..{float(x.max()):.6g} and "
            f"{float(y.min()):.6g}..{float(y.max()):.6g} over {float(truth.t[-1] - truth.t[0]):.4g} s: "
            "latitude and longitude in degrees read as metres? name them lat, lon (--truth-columns "
            "t=TIME,lat=LAT,lon=LON)")


#: A truth whose median spacing is under this fraction of its 90th-percentile spacing comes
#: in bursts (:func:`burst_stamps`): a motion capture at 87 Hz stamped with a bag's receive
#: times had a median of 0.2 ms between fixes and a burst every 0.1 s (ratio 0.002); a
#: steady truth's ratio is near 1, a GPS with gaps under trees 1 too (its gaps are few).
BURST_RATIO = 0.05


def stamp_bursts(times: ArrayLike) -> tuple[float, float] | None:
    """(median spacing, burst period) [s] where the fixes stamped ``times`` [s] (K,) come in
    bursts, else None.

    Fixes stamped when they arrived, not when they were measured (a bag's receive times, a
    logger that empties its buffer), crowd together: most follow the one before within a
    fraction of a millisecond, then a gap of the buffer's period. Their times are then off
    by up to that period, so anything compared in time is too: a window's end, a start
    heading fitted to the fixes around it (a user study's came out 0.48 ± 0.04 rad where the
    robot pointed at 0), a clock offset. The median spacing under :data:`BURST_RATIO` of the
    90th percentile says so (20 fixes at least).
    """
    d = np.diff(np.asarray(times, dtype=float).reshape(-1))
    if d.size < 20:
        return None
    median, period = float(np.median(d)), float(np.percentile(d, 90))
    if not median < BURST_RATIO * period:
        return None
    return median, period


def bursts_note(times: ArrayLike) -> str | None:
    """The warning's words where fixes stamped ``times`` [s] come in bursts
    (:func:`stamp_bursts`), else None: every reader of a truth says it alike (a truth file, a
    bag's truth topic)."""
    if (found := stamp_bursts(times)) is None:
        return None
    median, period = found
    return (f"its fixes come in bursts: half of them follow the one before within {1000 * median:.2g} ms, "
            f"and a tenth of the gaps are {period:.2g} s or longer: stamped when they arrived (a bag's "
            "receive times, --bag-time, or a message without a header; a logger's buffer), not when "
            f"measured. Every comparison in time is then off by up to {period:.2g} s (windows' ends, start "
            "headings fitted to the fixes, the clock offset) and no spikes are screened: stamp the fixes "
            "when they were measured (the messages' header stamps)")


def truth_from_log(log: OdometryLog) -> Truth | None:
    """The log's own ground truth (OptiOdom, Snowhite, ``gt_*`` columns) as a :class:`Truth`.

    Rows repeating an earlier time are dropped (the first is kept), so that the truth's
    clock is strictly increasing. A log whose ``meta["truth"]`` is a :class:`Truth` (a ROS
    bag's GPS topic: position-only, on its own clock) gives that. Returns None when the log
    carries no truth.
    """
    own = log.meta.get("truth")
    if isinstance(own, Truth):
        return own
    if log.ground_truth is None:
        return None
    t = np.asarray(log.t, dtype=float)
    keep = np.concatenate(([True], np.diff(t) > 0))
    gt = np.asarray(log.ground_truth, dtype=float)[keep]
    return Truth(t[keep], gt[:, :2].copy(), unwrap_angle(gt[:, 2]), source=log.source)


def heading_span(truth: Truth, min_fixes: int = 5) -> float:
    """The default width [s] of :func:`heading_from_positions`' window of fixes: 1 s, or
    room for ``min_fixes`` + 1 fixes at the truth's median spacing where they are sparser (a
    1 Hz GPS gets 6 s; a motion capture at 100 Hz keeps 1 s)."""
    spacing = float(np.median(np.diff(truth.t))) if len(truth) > 1 else 0.0
    return max(1.0, (max(int(min_fixes), 4) + 1) * spacing)


def heading_spans(truth: Truth, min_fixes: int = 5) -> tuple[float, ...]:
    """The widths [s] a heading fit without a given span tries, in order: :func:`heading_span`,
    then doubled while within :data:`WIDEST_HEADING_SPAN` (a 10 Hz truth: 1, 2, 4, 8 s; a
    1 Hz GPS: its 6 s only)."""
    spans = [heading_span(truth, min_fixes)]
    while 2 * spans[-1] <= WIDEST_HEADING_SPAN:
        spans.append(2 * spans[-1])
    return tuple(spans)


def _fit_spans(span: float | None, truth: Truth, min_fixes: int) -> tuple[float, ...]:
    """The widths [s] a heading fit tries: ``span`` alone, or :func:`heading_spans`."""
    if span is None:
        return heading_spans(truth, min_fixes)
    return (validate.positive(span, "span", unit="s", error=InputError),)


def _residual_limit(truth: Truth, given: float | None, speed: float = 0.0) -> float:
    """A heading fit's largest residual RMS per axis [m]: ``given``, else
    :data:`MAX_RESIDUAL_SIGMAS` × the truth's stated noise at ``speed`` [m/s], else no limit
    (inf). The stated noise is its position σ and its clock's, a fix ``time_sigma`` off
    being off by the speed times that along the path: √(σ² + (v σ_t)²/2) per axis. A
    noise fit may give the position σ as zero and the clock all of it (a 1 Hz GPS under a
    car, scored at its fixes: σ 0 m, σ_t 0.56 s), and the position σ alone then refused
    every heading."""
    if given is not None:
        return given
    stated = math.sqrt(truth.sigma**2 + 0.5 * (speed * truth.time_sigma) ** 2)
    return MAX_RESIDUAL_SIGMAS * stated if stated > 0 else math.inf


def heading_from_positions(
    truth: Truth,
    time: float,
    span: float | None = None,
    min_fixes: int = 5,
    max_residual: float | None = None,
) -> tuple[float, float] | None:
    """The heading of the truth path around ``time``, fitted to its positions, and its variance.

    x(t) and y(t) over the fixes within ±``span``/2 of ``time`` are each fitted with a
    quadratic in (t − time) by least squares; the heading is the direction of the fitted
    velocity (ẋ, ẏ) at ``time``. The quadratic term absorbs the path's curvature, so a
    robot driving an arc gets the tangent, not the chord. The position noise σ² is the
    larger of ``truth.sigma``² and the fit's residual variance (RSS/(n − 3)); with
    V = σ² [(AᵀA)⁻¹]₁₁ the variance of each velocity component, the heading variance is
    V / |v|² (first-order propagation through atan2).

    This is the direction of *travel*: a robot reversing at ``time`` faces the opposite
    way, and a caller that knows the direction of travel from odometry adds π.

    Parameters
    ----------
    truth : Truth
    time : float
        Time of the heading [s].
    span : float, optional
        Width of the window of fixes [s]; default: :func:`heading_spans` in turn, from
        :func:`heading_span` (1 s, wider for sparse fixes such as a 1 Hz GPS, which would
        otherwise never give a heading) doubling up to :data:`WIDEST_HEADING_SPAN` until
        the heading's σ is below :data:`HEADING_SIGMA_SOUGHT` (dense, noisy fixes).
    min_fixes : int
        Fewest fixes to fit (at least 4, so the residual has a degree of freedom).
    max_residual : float, optional
        Largest residual RMS per axis [m] accepted; default :data:`MAX_RESIDUAL_SIGMAS` ×
        ``truth.sigma`` where the truth states its noise, else no limit.

    Returns
    -------
    (heading [rad], variance [rad²]) or None when the fixes cannot support a heading:
    too few fixes, the robot hardly moved (heading standard deviation above
    :data:`MAX_HEADING_SIGMA`), or a residual above ``max_residual``.

    Examples
    --------
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> tr = Truth(t, np.column_stack((0.5 * t, 0.5 * t)))
    >>> h, var = heading_from_positions(tr, 1.0)
    >>> round(h, 12), var < 1e-20
    (0.785398163397, True)
    """
    return _widening(lambda width: _quadratic_heading(truth, time, width, min_fixes, max_residual),
                     _fit_spans(span, truth, min_fixes))


def _widening(fit: Callable[[float], tuple[float, float] | None], spans: Sequence[float]
              ) -> tuple[float, float] | None:
    """The first of ``fit(width)`` over ``spans`` whose heading σ is below
    :data:`HEADING_SIGMA_SOUGHT`, else the most precise one (None where none fits).

    A wider span has more fixes and more travel (a heading's σ falls about as span^-1.5),
    but holds more of what the fit leaves out (the quadratic path's misfit, the odometry's
    own drift in an alignment): so no wider than the precision sought needs.
    """
    best: tuple[float, float] | None = None
    for width in spans:
        found = fit(width)
        if found is not None and (best is None or found[1] < best[1]):
            best = found
        if best is not None and best[1] <= HEADING_SIGMA_SOUGHT**2:
            break
    return best


def _resolution(xy: NDArray[np.float64]) -> float:
    """The smallest position step [m] the fixes ``xy`` (n, 2) can tell from rounding: a few
    units in the last place of their largest coordinate. Where the truth states no noise and
    the fixes repeat exactly (a robot standing under a SLAM or motion-capture reference),
    the fit's residual is rounding alone, and without this floor a velocity of rounding
    (1e-17 m/s) gave a heading with a σ of 0.3 rad: a real robot standing 42 s at its
    start got a start heading 90° wrong."""
    return 16 * float(np.finfo(float).eps) * max(float(np.max(np.abs(xy))), 1.0)


def _quadratic_heading(truth: Truth, time: float, span: float, min_fixes: int,
                       max_residual: float | None) -> tuple[float, float] | None:
    """One quadratic fit of :func:`heading_from_positions` over ±``span``/2."""
    min_fixes = max(int(min_fixes), 4)
    near = np.flatnonzero(np.abs(truth.t - time) <= span / 2)
    if near.size < min_fixes:
        return None
    dt = truth.t[near] - time
    # Scaled design [1, τ, τ²] with τ = dt/span keeps AᵀA well conditioned.
    scale = span / 2
    tau = dt / scale
    A = np.column_stack((np.ones_like(tau), tau, tau**2))
    coef, _, rank, _ = np.linalg.lstsq(A, truth.xy[near], rcond=None)
    if rank < 3:
        return None
    resid = truth.xy[near] - A @ coef
    dof = near.size - 3
    s2 = float(np.sum(resid**2)) / (2 * dof)  # pooled over x and y
    vx, vy = coef[1, 0] / scale, coef[1, 1] / scale
    if math.sqrt(s2) > _residual_limit(truth, max_residual, math.hypot(vx, vy)):
        return None
    sigma2 = max(truth.sigma**2, s2, _resolution(truth.xy[near]) ** 2)
    speed2 = vx * vx + vy * vy
    if speed2 == 0.0:
        return None
    var_v = sigma2 * float(np.linalg.inv(A.T @ A)[1, 1]) / scale**2
    var_heading = var_v / speed2
    if var_heading > MAX_HEADING_SIGMA**2:
        return None
    return float(math.atan2(vy, vx)), float(var_heading)


def heading_by_alignment(
    truth: Truth,
    time: float,
    track_t: ArrayLike,
    track_poses: ArrayLike,
    span: float | None = None,
    min_fixes: int = 5,
    max_residual: float | None = None,
) -> tuple[float, float] | None:
    """The heading at ``time`` that turns the odometry's own path onto the truth fixes
    around it, and its variance.

    :func:`heading_from_positions` must guess the path's shape between sparse fixes (a
    quadratic in time), and on a path that turns as it goes that guess is biased: on a
    simulated car turning at 0.13 rad/s RMS, the quadratic's heading from noise-free 1 Hz
    fixes over 6 s was 0.033 rad off RMS, more than 1 m fixes' own noise there gives.
    Over a few seconds the odometry knows the shape far better, and only its heading
    is unknown. So the odometry positions r_j at the fix times (in any frame) are aligned
    to the fixes x_j by a rotation φ and a shift, x_j ≈ c + R(φ) r_j (2-D Umeyama 1991
    without scale: φ = atan2(Σ (r_j − r̄) × (x_j − x̄), Σ (r_j − r̄) · (x_j − x̄))), and the
    heading is the odometry's own heading at ``time`` plus φ (a reversing robot needs no
    special case). With σ² the larger of ``truth.sigma``² and the residual variance per
    axis (RSS / (2n − 3)), Var φ = σ² / Σ |r_j − r̄|² (the rotation's Fisher information).
    The odometry's own error over the span is left out: a fraction of a second to a few
    seconds of travel.

    Parameters
    ----------
    truth : Truth
    time : float
        Time of the heading [s], inside the track.
    track_t : array_like, shape (N,)
        Increasing times of the odometry track [s].
    track_poses : array_like, shape (N, 3)
        The odometry's poses [m, m, rad] in any frame (e.g. dead-reckoned from the origin).
    span, min_fixes, max_residual
        As in :func:`heading_from_positions` (``min_fixes`` at least 3 here): without a
        span the alignment widens as that fit does, each by its own precision.

    Returns
    -------
    (heading [rad], variance [rad²]) or None when the fixes cannot support a heading: too
    few fixes, the robot hardly moved over them (heading standard deviation above
    :data:`MAX_HEADING_SIGMA`), or a residual above ``max_residual``.

    Examples
    --------
    >>> t = np.linspace(0.0, 4.0, 41)
    >>> track = np.column_stack((np.cos(t), np.sin(t), t + np.pi / 2))  # a unit circle
    >>> fixes = Truth(t, np.column_stack((-np.sin(t), np.cos(t))))  # the same, turned by 90°
    >>> h, var = heading_by_alignment(fixes, 2.0, t, track)
    >>> round(h - (2.0 + np.pi), 9), var < 1e-20
    (0.0, True)
    """
    t_odo = np.asarray(track_t, dtype=float)
    poses = np.asarray(track_poses, dtype=float)
    if not t_odo[0] <= time <= t_odo[-1]:
        return None  # the odometry's heading there is unknown (np.interp would clamp it)
    return _widening(
        lambda width: _aligned_heading(truth, time, t_odo, poses, width, min_fixes, max_residual),
        _fit_spans(span, truth, min_fixes))


def _aligned_heading(truth: Truth, time: float, t_odo: NDArray[np.float64], poses: NDArray[np.float64],
                     span: float, min_fixes: int, max_residual: float | None) -> tuple[float, float] | None:
    """One alignment of :func:`heading_by_alignment` over the fixes within ±``span``/2."""
    near = np.flatnonzero((np.abs(truth.t - time) <= span / 2) & (truth.t >= t_odo[0])
                          & (truth.t <= t_odo[-1]))
    if near.size < max(int(min_fixes), 3):
        return None
    r = np.column_stack([np.interp(truth.t[near], t_odo, poses[:, k]) for k in (0, 1)])
    x = truth.xy[near]
    r_c, x_c = r - r.mean(axis=0), x - x.mean(axis=0)
    spread = float(np.sum(r_c**2))
    if spread == 0.0:
        return None
    # Umeyama (1991) eq. (40)-(41) in 2-D: the rotation maximising Σ x_cᵀ R r_c.
    phi = math.atan2(float(np.sum(r_c[:, 0] * x_c[:, 1] - r_c[:, 1] * x_c[:, 0])),
                     float(np.sum(r_c[:, 0] * x_c[:, 0] + r_c[:, 1] * x_c[:, 1])))
    c, s = math.cos(phi), math.sin(phi)
    resid = x_c - r_c @ np.array([[c, s], [-s, c]])
    s2 = float(np.sum(resid**2)) / max(2 * near.size - 3, 1)
    lasted = float(truth.t[near[-1]] - truth.t[near[0]])
    speed = float(np.linalg.norm(r[-1] - r[0])) / lasted if lasted > 0 else 0.0
    if math.sqrt(s2) > _residual_limit(truth, max_residual, speed):
        return None
    var = max(truth.sigma**2, s2, _resolution(x) ** 2) / spread
    if var > MAX_HEADING_SIGMA**2:
        return None
    return float(np.interp(time, t_odo, poses[:, 2])) + phi, var


def start_heading(truth: Truth, time: float, track_t: ArrayLike, track_poses: ArrayLike
                  ) -> tuple[float, float] | None:
    """The heading [rad] and its variance [rad²] to start dead reckoning from at ``time``
    where the truth has no heading: the odometry's own path aligned to the fixes around it
    (:func:`heading_by_alignment`), or None where the truth alone cannot support a heading
    there (:func:`heading_from_positions`: too few fixes, a residual above
    :data:`MAX_RESIDUAL_SIGMAS` σ, a robot hardly moving).

    Which starts are refused is the truth's decision, not the odometry's error: a window
    must not be left out for that error, which the alignment's residual also holds (the
    windows kept would then be the odometry's good ones). Where the alignment gives no
    heading (its residual, odometry included, spread over too short a path: an
    uncalibrated robot turning on the spot), the truth-only fit's heading is used, turned
    by π where the odometry moves backwards over the next 0.5 s, unless the odometry says
    the vehicle stood while the truth moved: over the truth-only fit's span it travelled
    less than half the truth's own displacement (:data:`STANDING_SHARE`). Then the truth's
    motion is its noise (a car waiting at a light under a GPS whose fixes wander metres:
    on a real drive such a start came out 185° wrong, with a σ of 0.2 rad) and the start is
    refused. Whether a vehicle moves is no odometry error: a stuck wheel aside (``odomkit
    check``), an odometry at rest is a vehicle at rest.

    Parameters
    ----------
    truth : Truth
    time : float
        Start time [s], inside the track.
    track_t : array_like, shape (N,)
    track_poses : array_like, shape (N, 3)
        The odometry over (at least) the fixes around ``time``, in any frame.
    """
    alone = heading_from_positions(truth, time)
    if alone is None:
        return None
    t_odo = np.asarray(track_t, dtype=float)
    poses = np.asarray(track_poses, dtype=float)
    aligned = heading_by_alignment(truth, time, t_odo, poses, max_residual=math.inf)
    if aligned is not None:
        return aligned
    if _stood_while_truth_moved(truth, time, t_odo, poses):
        return None
    a, b = np.searchsorted(t_odo, [time, time + 0.5]).clip(0, len(t_odo) - 1)
    moved = poses[b, :2] - poses[a, :2]
    backwards = moved[0] * math.cos(poses[a, 2]) + moved[1] * math.sin(poses[a, 2]) < 0
    return (alone[0] + math.pi if backwards else alone[0]), alone[1]


def _stood_while_truth_moved(truth: Truth, time: float, t_odo: NDArray[np.float64],
                             poses: NDArray[np.float64]) -> bool:
    """Over the truth-only heading fit's first span about ``time``, did the odometry travel
    less than :data:`STANDING_SHARE` of the truth's displacement between its first and last
    fix there?"""
    half = heading_span(truth) / 2
    near = np.flatnonzero(np.abs(truth.t - time) <= half)
    if near.size < 2:
        return False
    moved = float(np.linalg.norm(truth.xy[near[-1]] - truth.xy[near[0]]))
    inside = (t_odo >= truth.t[near[0]]) & (t_odo <= truth.t[near[-1]])
    path = poses[inside, :2]
    travel = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))) if len(path) > 1 else 0.0
    return travel < STANDING_SHARE * moved


def start_pose(truth: Truth, time: float, max_gap: float | None = 0.5, *, reverse: bool = False,
               span: float | None = None, odometry: tuple[ArrayLike, ArrayLike] | None = None
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The truth pose at ``time`` to start dead reckoning from, and its covariance.

    The covariance is diag(σ², σ², var_θ): σ = ``truth.sigma`` and var_θ =
    ``truth.heading_sigma``² when the truth measures heading; otherwise θ and var_θ are
    :func:`start_heading`'s where the ``odometry`` is given, else
    :func:`heading_from_positions`' (plus π when ``reverse``, a robot backing up).

    Parameters
    ----------
    truth : Truth
    time : float
        Start time [s].
    max_gap : float or None
        As in :func:`truth_at`.
    reverse : bool
        The robot travels backwards at ``time`` (position-only truth only).
    span : float, optional
        Width of the heading fit [s] (position-only truth without ``odometry`` only; default
        :func:`heading_span`).
    odometry : (times (N,), poses (N, 3)), optional
        The odometry in any frame around ``time`` (position-only truth only): its own path
        is aligned to the fixes (:func:`start_heading`); ``reverse`` and ``span`` then do
        not apply.

    Returns
    -------
    pose : ndarray, shape (3,)
        [m, m, rad].
    cov : ndarray, shape (3, 3)

    Raises
    ------
    InputError
        When ``time`` is outside the truth or inside a gap, or the heading cannot be fitted.
    """
    sample = truth_at(truth, [time], max_gap)
    if not sample.valid[0]:
        where = "inside a gap of" if sample.in_gaps else "outside"
        raise InputError(f"the start time {clock_text(time)} s is {where} the truth "
                         f"({clock_text(truth.t[0])}..{clock_text(truth.t[-1])} s): there is no truth pose "
                         "to start from; "
                         "give --initial-pose", source=truth.source)
    pose = sample.poses[0].copy()
    cov = np.diag([truth.sigma**2, truth.sigma**2, truth.heading_sigma**2])
    if truth.theta is None:
        fit = (heading_from_positions(truth, time, span) if odometry is None
               else start_heading(truth, time, *odometry))
        if fit is None:
            raise InputError(f"the truth has no heading, and its positions around {clock_text(time)} s "
                             "do not give one (too few fixes, fixes off a smooth path by more than 3 "
                             "--truth-sigma, or the robot hardly moves); give --initial-pose",
                             source=truth.source)
        pose[2] = fit[0] + (math.pi if reverse and odometry is None else 0.0)
        cov[2, 2] = fit[1]
    return pose, cov
