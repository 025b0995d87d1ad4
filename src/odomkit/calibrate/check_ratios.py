"""How far and how much the odometry turns against the truth (part of ``odomkit check``).

A unit read wrong or a robot-file entry left out scales the whole track: a speed in mph read
as m/s drives 2.24× as far as the car did, a steering-wheel angle read as the road wheels'
turns a car about 15× as much (its ``steering_ratio``), a gyro in °/s read as rad/s turns
57× as much. ``calibrate`` then bends a scale or a wheel base to the edge of its range and
the user is told nothing about why. Both show plainly against a truth, position-only or not:

* **travel**: over straight stretches of a few seconds, the distance the odometry says it
  rolled against the straight-line distance (chord) between the truth's fixes at the
  stretch's ends. Straight, because a chord is the path only there (and a speed read 2×
  too large drives the odometry twice round the same bend, so chords would not compare);
  the truth's noise adds to its chords (by σ²/chord relative, 0.5 % at the
  :data:`CHORD_SIGMAS` kept), so only stretches with a chord well beyond the noise count.
* **turning**: with a heading truth, its heading change over each stretch against the
  odometry's; with a position-only truth, the change of direction between consecutive
  stretches' chords, the same on both sides (a chord's direction is the heading at its
  middle for a steady turn, and flips alike on both sides where the robot reverses), also
  across stretches where the robot stands or turns on the spot (their chords are too short to
  have a direction); a pair counts where the truth turns beyond its noise or the odometry
  turns well beyond the wobble a smoothed truth does not show.

Each is a ratio of sums (odometry over truth), with a standard error from the spread of the
stretches' own ratios. The ratios name a likely cause where they sit on a known unit factor,
and the robot-file entry that would absorb them otherwise (for a differential drive, the
turning ratio over the travel ratio is the wheel base's error; for a car, about the
steering ratio's). A log of rates (speeds, a yaw rate) whose times are in ms read as seconds
drives and turns 1000 times as far, both alike: where every ratio a time unit scales sits
near its factor (1000, 1e6, 1e9) and the ratios measured again with the times read in that
unit come out near 1, the finding names the time unit (:func:`time_unit_off`), not a speed's
or a yaw rate's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from odomkit import units
from odomkit.calibrate.check_finding import Finding, Status
from odomkit.log import SPEED_CHANNELS, OdometryLog
from odomkit.robot import Car, CompassOdometry, DiffDrive, Robot, Tricycle
from odomkit.truth import Truth, heading_span, longest_gap, truth_noise

__all__ = ["check_truth_motion", "FOLLOWS", "follows_note", "judging_noise", "motion_follows",
           "motion_problems", "MotionRatios", "motion_ratios",
           "UNSEEN_TURN", "UnseenTurning", "unseen_turning", "speed_clock", "speed_clock_note",
           "COVERS_ONE", "NO_TURN", "RATIO_FAIL", "TRAVEL_WARN", "TURN_WARN", "time_unit_off", "TimeUnitOff",
           "unit_mixup"]

#: A stretch's truth chord counts where it exceeds this many times the chord's own noise
#: (σ√2 for two fixes of σ per axis): a 7 % error on one stretch's ratio at worst, and a
#: bias of its length below 0.5 %.
CHORD_SIGMAS = 10.0
#: ... and this many metres (a motion capture's fixes are nearly exact; an encoder's
#: quantisation is not).
MIN_CHORD = 0.05
#: A position-only truth's turn is compared only across stretches that roll at least this
#: share of the drive's median stretch (:func:`motion_ratios`): a car crawling at 0.1 m/s
#: for 6.5 s, its INS wandering 20 cm, showed 7.6 rad of "turning" where the odometry turned
#: 0.93 rad, a false failure naming the yaw rate's unit (user study).
CRAWL_SHARE = 0.2
#: A stretch is straight where the odometry turns less than this [rad] over it (its chord
#: is then its path within 0.1 %) and the truth's middle fix lies within this share of the
#: chord from it (a turn of about 0.4 rad) plus its noise.
STRAIGHT_TURN = 0.15
STRAIGHT_SAGITTA = 0.05
#: ... and the odometry turns no more than a circle of this radius [m] would, plus
#: :data:`STRAIGHT_TURN_FLOOR` [rad] (an encoder's quantisation).
STRAIGHT_RADIUS = 20.0
STRAIGHT_TURN_FLOOR = 0.01
#: Each half of a straight stretch holds at least this share of its distance.
EVEN_SHARE = 0.3
#: A turn counts where the truth turns more than this [rad], and more than
#: :data:`TURN_SIGMAS` times its turn's own noise, ...
MIN_TURN = 0.1
TURN_SIGMAS = 4.0
#: ... or where the odometry turns more than this [rad] (and the truth's noise): a truth
#: that barely turns against an odometry that spins (a unit read wrong) still gives its
#: ratio. Higher than :data:`MIN_TURN` because the odometry's own short-term wobble, which a
#: smoothed truth does not show, is not in the truth's noise: chosen where either side passed
#: 0.1 rad, the pairs of a corridor robot's 1.2 s chords that passed only by the odometry's
#: wobble (0.11 rad against the truth's 0.00) made it turn 1.54 × as much as the truth,
#: against 0.91 with a heading truth and a calibrated yaw-rate scale of 1.03 (TUC SLAM study).
ODOMETRY_TURN = 0.5
#: Two chords' directions this close to a half turn apart [rad] are a turn round (a robot
#: turning on the spot between two drives): its sign is the odometry's.
HALF_TURN_MARGIN = 0.5
#: Fewer stretches than this give no ratio.
MIN_STRETCHES = 5
#: The longest stretch tried [s]: a stretch span doubles from the truth's heading span until
#: :data:`ENOUGH_STRETCHES` stretches have chords beyond the noise.
LONGEST_STRETCH = 32.0
ENOUGH_STRETCHES = 10
#: Travel off by more than this factor either way is warned about: a wheel's radius or a
#: speed's scale is seldom more than a few percent off, and calibrate fits that much.
TRAVEL_WARN = 1.15
#: Turning off by more than this factor: a wheel base (which slips in turns) or a steering
#: gain is more often off, by up to about 20 %.
TURN_WARN = 1.25
#: Off by more than this factor either way is no calibration error: a unit or a missing
#: robot-file entry (the check fails).
RATIO_FAIL = 2.0
#: A ratio within this many of its standard errors of 1 is not told apart from 1: no warning
#: and no failure, whatever its size (a few noisy turns of a GPS's long chords gave 1.8 ± 1.1).
COVERS_ONE = 2.0
#: A ratio off by more than this factor either way is judged by its size alone, whatever its
#: standard error: no noise of a truth makes an odometry that reads its travel right turn
#: 10× as much, or a tenth (a raw counter read as increments turned 539 ± 310 × as much, "within 2
#: standard errors of 1").
NOT_NOISE = 10.0
#: A turning gain (odometry over truth) under this in size is no scale error either: the
#: odometry hardly turns where the truth does (an IMU on its side read about the wrong axis),
#: or, below its negative, turns the other way (a sign flipped; a flipped sign turning g
#: times as much gives −g, :func:`motion_ratios`). A unit's factor is named before it (radians
#: read as degrees turn 0.0175×).
NO_TURN = 0.1

# (factor, what it is, what to do): odometry over truth near a unit factor (within 4 %).
_TRAVEL_UNITS = (
    (1 / units.MPH, "a speed in mph read as m/s", "name the column speed_mph in --columns"),
    (1 / units.KMH, "a speed in km/h read as m/s", "name the column speed_kmh in --columns"),
    (units.MPH, "a speed in m/s read as mph", "name the column speed (m/s), not speed_mph"),
    (units.KMH, "a speed in m/s read as km/h", "name the column speed (m/s), not speed_kmh"),
    (units.MPH / units.KMH, "a speed in km/h read as mph", "name the column speed_kmh, not speed_mph"),
    (units.KMH / units.MPH, "a speed in mph read as km/h", "name the column speed_mph, not speed_kmh"),
    (1 / units.FOOT, "feet read as metres", "convert feet to metres (m_per_tick, or the speed's unit)"),
    (1000.0, "millimetres read as metres", "check the distance channels' unit or m_per_tick (1000x too big)"),
    (units.MILLIMETRE, "the truth's millimetres read as metres",
     "name the truth's position columns x_mm, y_mm (--truth-columns)"),
    (100.0, "centimetres read as metres", "check the distance channels' unit or m_per_tick (100x too big)"),
    (0.001, "metres read as millimetres",
     "check the distance channels' unit or m_per_tick (1000x too small)"),
    (0.01, "metres read as centimetres", "check the distance channels' unit or m_per_tick (100x too small)"),
)
_TURN_UNITS = (
    # The turning is the odometry's over the truth's, so either side's unit can be wrong.
    (1 / units.DEGREE, "degrees read as radians",
     "name a column in degrees with its _deg name (steer_deg, yaw_rate_deg, heading_deg), or a truth "
     "heading in radians without _deg"),
    (units.DEGREE, "radians read as degrees, or the truth's heading in degrees read as radians",
     "name a column in radians without _deg, or the truth's heading in degrees theta_deg"),
)
_UNIT_TOLERANCE = 0.04


@dataclass(frozen=True)
class MotionRatios:
    """The odometry's travel and turning over the truth's (:func:`motion_ratios`).

    Parameters
    ----------
    travel, travel_se : float
        Σ odometry distance / Σ truth chord over the straight stretches kept, and its standard error
        (NaN when fewer than :data:`MIN_STRETCHES` are kept).
    travel_stretches : int
        Stretches kept for the travel.
    turn, turn_se : float
        Σ |odometry turn| / Σ |truth turn| over the turns kept, and its standard error (NaN
        when fewer than :data:`MIN_STRETCHES` turns are kept).
    turns : int
        Turns kept.
    span : float
        The stretches' length [s].
    truth_turned, odometry_turned : float
        Σ |turn| of the truth and of the odometry over the turns compared [rad].
    unseen : UnseenTurning or None
        Where a position-only truth gives too few turns for a ratio: how much the odometry's
        turns between stretches vary against the truth's (:func:`unseen_turning`), else None.
    """

    travel: float
    travel_se: float
    travel_stretches: int
    turn: float
    turn_se: float
    turns: int
    span: float
    truth_turned: float
    odometry_turned: float
    unseen: UnseenTurning | None = None


def judging_noise(truth: Truth, noise: float | None = None) -> tuple[float, float | None]:
    """The truth's position noise [m per axis] the ratios are judged with, and the scatter it
    replaced where the σ the truth's file states (``truth.stated_sigma``: a bag's GPS fixes'
    covariance, not given as ``--truth-sigma``) is the larger (else None).

    ``noise`` (default :func:`odomkit.truth.truth_noise`: the σ given, or the fixes' scatter
    about a smooth path where larger) is the estimate. A GPS's error is correlated in time:
    consecutive fixes wander together, so their scatter about a smooth path understates it
    (a Husky's 2.5 Hz fixes stating 0.8 m scattered 0.1 m) and the ratio check, judging chords
    and turns of a few seconds against that, counts the wander as the odometry's error (it
    turned 0.25× as much as the truth over 2.4 s stretches, 0.97× over the 19 s that 0.8 m
    asks for). The stated σ only judges here; no fit uses it unasked.
    """
    estimate = truth_noise(truth) if noise is None else noise
    if truth.stated_sigma > estimate:
        return float(truth.stated_sigma), estimate
    return estimate, None


def _ratio(odometry: NDArray[np.float64], truth: NDArray[np.float64]) -> tuple[float, float]:
    """Σ odometry / Σ truth (both ≥ 0) and its standard error: the ratio estimator's, from the
    residuals odometry − ratio·truth (a linearised delta method)."""
    n = truth.size
    total = float(np.sum(truth))
    if n < MIN_STRETCHES or total <= 0:
        return math.nan, math.nan
    ratio = float(np.sum(odometry)) / total
    resid = odometry - ratio * truth
    se = float(np.sqrt(n * np.sum(resid**2) / (n - 1)) / total)
    if not (math.isfinite(ratio) and math.isfinite(se)):
        return math.nan, math.nan
    return ratio, se


def _stretch_ends(truth_t: NDArray[np.float64], start: float, stop: float, span: float, max_gap: float
                  ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Fix indices (first, last) of consecutive stretches of ``span`` seconds in
    [start, stop], each without a gap between fixes beyond ``max_gap``; the last fix of
    one is the first of the next, so consecutive stretches share an end."""
    bounds = np.arange(start, stop + 1e-9 * span, span)
    idx = np.unique(np.searchsorted(truth_t, bounds))
    idx = idx[idx < truth_t.size]
    if idx.size < 2:
        return np.empty(0, np.intp), np.empty(0, np.intp)
    first, last = idx[:-1], idx[1:]
    # Each stretch's widest gap: the gaps first..last-1 (the stretches are consecutive, so
    # cutting the gaps at the last stretch's end keeps later gaps out of it).
    widest = np.maximum.reduceat(np.diff(truth_t)[: last[-1]], first)
    keep = (widest <= max_gap) & (truth_t[last] - truth_t[first] <= 1.5 * span)
    return first[keep], last[keep]


@dataclass(frozen=True)
class UnseenTurning:
    """The odometry's turning between consecutive stretches where a position-only truth
    barely turns (:func:`unseen_turning`): over ``pairs`` pairs of stretches of ``span`` [s],
    the RMS [rad] of the odometry's turns about its steady turn per metre (``odometry``; a
    steering offset or a gyro's bias turns it steadily, which ``calibrate`` fits), the
    truth's likewise (``truth``) and the RMS of the truth's turn noise (``noise``)."""

    span: float
    pairs: int
    odometry: float
    truth: float
    noise: float

    @property
    def times(self) -> float:
        """How many times the truth's turning (or its noise, the larger) the odometry's varies."""
        floor = max(self.truth, self.noise)
        return self.odometry / floor if floor > 0 else math.inf


#: A truth heading whose turning ratio to the odometry's lies within this of 1, with a
#: standard error below it, is the odometry's own heading (:func:`check_truth_motion`).
OWN_HEADING = 1e-6
#: The odometry's turns between stretches vary by at least this RMS [rad] (3°) before
#: :func:`unseen_turning`'s finding judges them: an encoder's or a gyro's own wobble along a
#: straight drive is smaller.
UNSEEN_TURN = 0.05


def _steady_removed(turn: NDArray[np.float64], distance: NDArray[np.float64]) -> float:
    """The RMS of ``turn`` about its least-squares steady turn per metre of ``distance``."""
    k = float(turn @ distance / (distance @ distance)) if np.any(distance) else 0.0
    return float(np.sqrt(np.mean((turn - k * distance) ** 2)))


@dataclass(frozen=True)
class _Along:
    """What :func:`motion_ratios` compares a position-only truth's turning with, at the
    truth's fixes (K,): the fixes ``xy`` [m] (K, 2), the distance the odometry rolled up to
    each, either way (``rolled``, m) and signed (``travelled``, m), ∫ θ over the distance
    rolled (``heading_sum``, rad·m), the truth's noise σ [m per axis] and the shortest chord
    [m] with a direction."""

    xy: NDArray[np.float64]
    rolled: NDArray[np.float64]
    travelled: NDArray[np.float64]
    heading_sum: NDArray[np.float64]
    noise: float
    least_chord: float

    def chord_turns(self, first: NDArray[np.intp], last: NDArray[np.intp]
                    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64], NDArray[np.float64],
                               NDArray[np.float64]]:
        """The pairs (a, b) of stretches (fixes ``first`` to ``last``, (S,)) compared, the
        truth's turn between their chords, the odometry's, and the truth turn's noise [rad].

        Each stretch with a chord beyond the noise and the next such one, driven the same
        way, with no gap in the truth between them (consecutive stretches, or stretches
        without a chord between: a robot that turns on the spot between two drives, as a
        corridor robot turns round, shows its turn only across them): the truth's turn
        between their chords' directions (a chord's direction is the heading at its middle
        on a steady turn, turned by π when reversing), with its noise from each direction's
        σ√2/chord, against the change of the odometry's own mean heading over each stretch
        (unwrapped: an odometry that spins more than a turn between two consecutive
        stretches still counts every turn)."""
        xy, rolled, noise = self.xy, self.rolled, self.noise
        truth_step = xy[last] - xy[first]
        truth_chord = np.linalg.norm(truth_step, axis=1)
        long_enough = truth_chord >= self.least_chord
        way = np.sign(self.travelled[last] - self.travelled[first])
        chain = np.cumsum(np.concatenate(([True], last[:-1] != first[1:])))
        # A stretch crawled through (a car at a walking pace while its GPS or INS wanders
        # decimetres) gives a chord whose direction is the truth's wander, not the path's:
        # only stretches that roll at least a fifth of the drive's typical stretch are compared.
        rolled_over = rolled[last] - rolled[first]
        moving = rolled_over[rolled_over > 0]
        typical = float(np.median(moving)) if moving.size else 0.0
        chorded = np.flatnonzero(long_enough & (rolled_over >= CRAWL_SHARE * typical))
        a, b = chorded[:-1], chorded[1:]
        same = (chain[a] == chain[b]) & (way[a] == way[b])
        a, b = a[same], b[same]
        ang = np.arctan2(truth_step[:, 1], truth_step[:, 0])
        truth_turn = np.angle(np.exp(1j * (ang[b] - ang[a])))
        mean_heading = (self.heading_sum[last] - self.heading_sum[first]) / np.maximum(
            rolled[last] - rolled[first], 1e-300)
        odo_turn = mean_heading[b] - mean_heading[a]
        # A turn round lies at ±π between the chords, either sign alike: the odometry's.
        round_ = (np.abs(truth_turn) > math.pi - HALF_TURN_MARGIN) & (truth_turn * odo_turn < 0)
        truth_turn = np.where(round_, truth_turn + 2 * math.pi * np.sign(odo_turn), truth_turn)
        # Across standing stretches the chords cannot count whole turns: more than a turn and
        # a half on the odometry is left out there.
        countable = (b == a + 1) | (np.abs(odo_turn) <= 1.5 * math.pi)
        a, b = a[countable], b[countable]
        truth_turn, odo_turn = truth_turn[countable], odo_turn[countable]
        with np.errstate(divide="ignore"):
            turn_noise = math.sqrt(2.0) * noise * np.hypot(1 / truth_chord[a], 1 / truth_chord[b])
        return a, b, truth_turn, odo_turn, turn_noise


def motion_ratios(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None = 0.5,
                  noise: float | None = None) -> MotionRatios:
    """The odometry's travel and turning against the truth's over stretches of a few seconds.

    Parameters
    ----------
    log : the odometry log, dead-reckoned with ``robot`` from the origin
    robot : the robot the log is read with
    truth : Truth, with or without heading; its noise is the larger of its stated σ and its
        fixes' own scatter (:func:`odomkit.truth.scatter_sigma`), and of the σ its file
        states where none was given (:func:`judging_noise`)
    max_gap : a stretch holding a gap between fixes longer than this [s] is left out; a
        sparse truth (a 1 Hz GPS) is allowed twice its median spacing
        (:func:`odomkit.truth.longest_gap`, :func:`odomkit.truth.truth_at`'s rule)
    noise : the truth's noise [m per axis] where the caller has it (default
        :func:`odomkit.truth.truth_noise`); the σ the truth's file states is still the floor

    Returns
    -------
    MotionRatios
    """
    from odomkit.kinematics import body_steps

    t = np.asarray(log.t, dtype=float)
    inside = (truth.t >= t[0]) & (truth.t <= t[-1])
    tt, xy = truth.t[inside], truth.xy[inside]
    nothing = MotionRatios(math.nan, math.nan, 0, math.nan, math.nan, 0, math.nan, 0.0, 0.0)
    if tt.size < 3:
        return nothing
    steps = body_steps(robot, log)
    # The odometry's own heading from the origin (a measured heading may wrap: unwrapped).
    turned = np.concatenate(([0.0], np.cumsum(steps.dtheta)))
    odo_heading = np.unwrap(turned) if robot.measures_heading else turned
    heading_at = np.interp(tt, t, odo_heading)
    # Signed (backwards is negative), and the distance rolled either way.
    travelled = np.interp(tt, t, np.concatenate(([0.0], np.cumsum(steps.dd))))
    rolled = np.interp(tt, t, np.concatenate(([0.0], np.cumsum(np.abs(steps.dd)))))
    # ∫ θ over the distance rolled: its mean over a stretch is the direction of the stretch's
    # chord to first order, as the truth's chord direction is (the same smoothing on both
    # sides: the heading at the stretch's middle turns 2 % more on a car's random bends).
    mid_heading = 0.5 * (odo_heading[:-1] + odo_heading[1:])
    heading_sum = np.interp(tt, t, np.concatenate(([0.0], np.cumsum(mid_heading * np.abs(steps.dd)))))
    heading = None if truth.theta is None else np.unwrap(truth.theta[inside])
    noise = judging_noise(truth, noise)[0]
    gap = longest_gap(truth, max_gap)
    least_chord = max(MIN_CHORD, CHORD_SIGMAS * math.sqrt(2.0) * noise)

    def straight(first: NDArray[np.intp], last: NDArray[np.intp]) -> NDArray[np.bool_]:
        """Stretches driven straight on, with a truth chord long beyond the noise:

        * the odometry turns less than :data:`STRAIGHT_TURN` over it, and no more than a
          circle of :data:`STRAIGHT_RADIUS` would (a point of the body off its reference
          point, a motion capture's marker, draws a wider circle on a bend);
        * the truth's middle fix lies within :data:`STRAIGHT_SAGITTA` of the chord plus 3σ
          of it (an odometry that turns too little cannot call a truth's bend straight);
        * each half of the stretch holds at least :data:`EVEN_SHARE` of its motion, on both
          sides (a start or a stop in it would compare the truth's lag on its own clock).
        """
        step = xy[last] - xy[first]
        chord = np.linalg.norm(step, axis=1)
        middle = (first + last) // 2
        off = xy[middle] - xy[first]
        odo_turn = np.abs(heading_at[last] - heading_at[first])
        odo_rolled = rolled[last] - rolled[first]
        with np.errstate(invalid="ignore", divide="ignore"):
            sagitta = np.abs(step[:, 0] * off[:, 1] - step[:, 1] * off[:, 0]) / chord
        odo_halves = np.minimum(rolled[middle] - rolled[first], rolled[last] - rolled[middle])
        truth_halves = np.minimum(np.linalg.norm(off, axis=1), np.linalg.norm(xy[last] - xy[middle], axis=1))
        even = (odo_halves >= EVEN_SHARE * odo_rolled) & (truth_halves >= EVEN_SHARE * chord)
        return ((chord >= least_chord) & (odo_turn <= STRAIGHT_TURN)
                & (odo_turn <= STRAIGHT_TURN_FLOOR + odo_rolled / STRAIGHT_RADIUS)
                & (sagitta <= STRAIGHT_SAGITTA * chord + 3.0 * noise) & even)

    best: tuple[int, float, NDArray[np.intp], NDArray[np.intp]] | None = None
    span = heading_span(truth)
    while True:
        first, last = _stretch_ends(tt, tt[0], tt[-1], span, gap)
        kept = int(np.count_nonzero(straight(first, last)))
        if best is None or kept > best[0]:
            best = (kept, span, first, last)
        if kept >= ENOUGH_STRETCHES or 2 * span > LONGEST_STRETCH:
            break
        span *= 2
    _, span, first, last = best
    truth_step = xy[last] - xy[first]
    truth_chord = np.linalg.norm(truth_step, axis=1)
    # On a straight stretch the truth's chord is its path; the odometry's path is the
    # distance its wheels (or its speed) say it rolled, whatever it thinks it turned.
    is_straight = straight(first, last)
    along = _Along(xy, rolled, travelled, heading_sum, noise, least_chord)
    travel, travel_se = _ratio((rolled[last] - rolled[first])[is_straight], truth_chord[is_straight])

    if heading is not None:
        truth_turn = heading[last] - heading[first]
        odo_turn = heading_at[last] - heading_at[first]
        turn_noise = np.full(truth_turn.shape, math.sqrt(2.0) * truth.heading_sigma)
    else:
        _, _, truth_turn, odo_turn, turn_noise = along.chord_turns(first, last)
    beyond_noise = np.maximum(np.abs(truth_turn), np.abs(odo_turn)) >= TURN_SIGMAS * turn_noise
    if heading is not None:
        # Chosen on the larger of the two turns over the same stretch, so that neither
        # side's turns alone pick them: a truth that barely turns against an odometry that
        # spins still gives its ratio.
        turning = beyond_noise & (np.maximum(np.abs(truth_turn), np.abs(odo_turn)) >= MIN_TURN)
    else:
        # Chosen on each side's turn against its own threshold: the truth's beyond MIN_TURN
        # (and its noise), the odometry's beyond ODOMETRY_TURN, so that a truth that barely
        # turns against an odometry that spins still gives its ratio, while the odometry's
        # short-term wobble, which the chords smooth away and the truth's noise does not
        # hold, cannot pick pairs on its own (a pair chosen by one side's wobble biases the
        # ratio that side's way).
        turning = beyond_noise & ((np.abs(truth_turn) >= MIN_TURN) | (np.abs(odo_turn) >= ODOMETRY_TURN))
    # Each turn counted the way it went: the truth's way where the truth turns clearly (beyond
    # MIN_TURN and its noise), else the way of the two turns' sum (a truth that barely turns
    # against an odometry that spins). Not the sum's way alone: an odometry that turns the
    # other way about as much as the truth (a flipped sign, −g × the truth's turns with g
    # near 1) leaves that sum to the noise, and the ratio of sums signed at random came out
    # anywhere (−1.4 ± 1.8) or not at all (a negative sum of the truth's turns); signed by the
    # truth, it is −g.
    truth_clear = (np.abs(truth_turn) >= TURN_SIGMAS * turn_noise) & (np.abs(truth_turn) >= MIN_TURN)
    way_turned = np.where(truth_clear, np.sign(truth_turn), np.sign(odo_turn + truth_turn))[turning]
    if np.sum(way_turned * truth_turn[turning]) < 0:  # every sign turned round: the same ratio
        way_turned = -way_turned
    turn, turn_se = _ratio(way_turned * odo_turn[turning], way_turned * truth_turn[turning])
    unseen = None
    if heading is None and not math.isfinite(turn):
        unseen = unseen_turning(along, tt, span, gap)
    return MotionRatios(travel, travel_se, int(np.count_nonzero(is_straight)), turn, turn_se,
                        int(np.count_nonzero(turning)), span, float(np.sum(np.abs(truth_turn[turning]))),
                        float(np.sum(np.abs(odo_turn[turning]))), unseen)


def unseen_turning(along: _Along, tt: NDArray[np.float64], span: float, gap: float) -> UnseenTurning | None:
    """How much the odometry turns between stretches where a position-only truth gives too
    few turns for a ratio (:func:`motion_ratios`), at the stretch span from ``span`` doubling
    to :data:`LONGEST_STRETCH` that tells them apart best; None with fewer than
    :data:`MIN_STRETCHES` pairs at every span.

    A car read without its ``steering_ratio`` on a highway (a user study's RAV4, 60 s at
    17 m/s): its GPS turned within its noise between 2 s chords, no pair passed
    :data:`MIN_TURN` or :data:`ODOMETRY_TURN`, and ``check`` said "not compared" while the
    track ended 521 m off. Its odometry's turns varied 15× the truth's noise there. Each
    side's steady turn per metre is taken out first (an offset turns the odometry steadily
    one way; calibrate fits it), then the RMS of what is left compared. Every pair is used,
    none chosen by either side's turn, so neither side's wobble biases the comparison."""
    best: UnseenTurning | None = None
    while span <= LONGEST_STRETCH:
        first, last = _stretch_ends(tt, tt[0], tt[-1], span, gap)
        a, b, truth_turn, odo_turn, noise = along.chord_turns(first, last)
        if a.size >= MIN_STRETCHES and np.all(np.isfinite(noise)):
            # The distance between the two stretches' middles, which a steady turn turns through.
            middle = 0.5 * (along.rolled[first] + along.rolled[last])
            distance = middle[b] - middle[a]
            found = UnseenTurning(span, int(a.size), _steady_removed(odo_turn, distance),
                                  _steady_removed(truth_turn, distance), float(np.sqrt(np.mean(noise**2))))
            if best is None or found.times > best.times:
                best = found
        span *= 2
    return best


def _unit(ratio: float, units: tuple[tuple[float, str, str], ...]) -> tuple[str, str] | None:
    if not ratio > 0:  # no unit turns a track round or stops it
        return None
    for factor, what, fix in units:
        if abs(math.log(ratio / factor)) <= _UNIT_TOLERANCE:
            return what, fix
    return None


def unit_mixup(travel: float, turn: float) -> str | None:
    """What a travel ratio or a turning gain (odometry over truth) near a unit factor says
    (``"a speed in mph read as m/s"``), or None: a unit read wrong, which the user fixes
    at the column, not by calibrating it away."""
    for ratio, table in ((travel, _TRAVEL_UNITS), (turn, _TURN_UNITS)):
        if math.isfinite(ratio) and ratio > 0 and (found := _unit(ratio, table)) is not None:
            return found[0]
    return None


@dataclass(frozen=True)
class TimeUnitOff:
    """Times in ``unit`` (``"ms"``, ``"us"``, ``"ns"``) read as seconds (:func:`time_unit_off`):
    ``again`` the ratios measured with the log's and the truth's times read in that unit;
    ``or_distance`` where a speed's distance unit off by the same factor would read alike (a
    wheeled base's turning follows its distance)."""

    unit: str
    again: MotionRatios
    or_distance: bool = False

    def cause(self) -> str:
        """What the finding says: the unit, and the ratios read in it."""
        ratios = (("travels", self.again.travel), ("turns", self.again.turn))
        said = [f"{what} {x:.3g} ×" for what, x in ratios if math.isfinite(x)]
        other = " (or the speeds' distance unit that many times too small)" if self.or_distance else ""
        return (f"times in {self.unit} read as seconds{other}? (read in {self.unit}, the odometry "
                f"{' and '.join(said)} as much as the truth)")

    def advice(self) -> str:
        other = ", or check the speeds' unit" if self.or_distance else ""
        return (f"read the times in {self.unit}: --time-unit {self.unit} for the log and --truth-time-unit "
                f"{self.unit} for the truth file{other}")


def time_unit_off(log: OdometryLog, robot: Robot, truth: Truth, r: MotionRatios,
                  max_gap: float | None = 0.5, noise: float | None = None) -> TimeUnitOff | None:
    """Whether the log's and the truth's times are in ms, µs or ns read as seconds.

    Read so, a log of rates integrates each over 1000 (1e6, 1e9) times the time it held: its
    travel (from a speed) and its turning (from a yaw rate, or a wheeled base's from the
    distance) both come out near that factor (within 2x: :func:`odomkit.units.time_unit_factor`),
    while the truth, on the same clock, moves as it did. The unit is named where the log's
    travel comes from a speed and its turning from a yaw rate or the distance, every ratio of
    ``r`` measured (at least one) sits near the same factor, and :func:`motion_ratios` again,
    with both clocks read in that unit, gives every ratio it measures (at least one) within
    :data:`RATIO_FAIL` of 1. Not for a log of increments (its travel is metres in any time
    unit: a yaw rate in mrad/s read as rad/s would pass for a time unit) nor for a measured
    heading (a speed in mm/s would). A wheeled base's turning follows its distance, so a
    speed's distance unit reads alike (``or_distance``). None otherwise. (A log in ms against
    a truth in s: their spans differ by the factor, :func:`odomkit.truth.clock_unit_hint`.)"""
    from odomkit.units import TIME_UNITS, time_unit_factor

    by_distance = isinstance(robot, (DiffDrive, Car, Tricycle))
    if (SPEED_CHANNELS.isdisjoint(log.channels) or isinstance(robot, CompassOdometry)
            or not (by_distance or "yaw_rate" in log.channels)):
        return None
    measured = [x for x in (r.travel, r.turn) if math.isfinite(x)]
    found = {time_unit_factor(x) for x in measured}
    if not measured or len(found) != 1 or None in found:
        return None
    (unit,) = found
    assert unit is not None
    seconds = TIME_UNITS[unit]
    with np.errstate(all="ignore"):
        again = motion_ratios(replace(log, t=log.t * seconds), robot, replace(truth, t=truth.t * seconds),
                              max_gap, noise)
    near = [x for x in (again.travel, again.turn) if math.isfinite(x)]
    if not near or not all(x > 0 and abs(math.log(x)) <= math.log(RATIO_FAIL) for x in near):
        return None
    return TimeUnitOff(unit, again, by_distance)


def _status(ratio: float, warn: float, se: float = math.nan) -> Status:
    # No evidence against 1 (NaN: none either way), unless the ratio is too far off for noise.
    if abs(ratio - 1) <= COVERS_ONE * se and 1.0 / NOT_NOISE <= abs(ratio) <= NOT_NOISE:
        return "ok"
    if not ratio > 0:  # the other way, or not at all: no scale error (and no logarithm)
        return "fail"
    off = abs(math.log(ratio))
    return "fail" if off > math.log(RATIO_FAIL) else "warn" if off > math.log(warn) else "ok"


def _covers_one(ratio: float, warn: float, se: float) -> str:
    """What an ``ok`` says where the ratio alone would not be ok: it is within
    :data:`COVERS_ONE` standard errors of 1."""
    if _status(ratio, warn) == "ok":
        return ""
    return f": within {COVERS_ONE:g} standard errors of 1, not told apart from it"


def _travel_finding(r: MotionRatios, robot: Robot, speed_fed: bool, judged: str = "",
                    clock: TimeUnitOff | None = None) -> Finding:
    said = (f"the odometry travels {r.travel:.3g} ± {r.travel_se:.2g} × the truth's distance "
            f"over {r.travel_stretches} straight stretches of {r.span:.3g} s{judged}")
    status = _status(r.travel, TRAVEL_WARN, r.travel_se)
    if status == "ok":
        return Finding("travel_ratio", "ok", said + _covers_one(r.travel, TRAVEL_WARN, r.travel_se),
                       value=r.travel)
    if clock is not None:
        return Finding("travel_ratio", status, f"{said}: {clock.cause()}", clock.advice(), r.travel)
    # A speed's unit only where the log has a speed: a ticks log 0.62x off is no mph.
    units_here = (_TRAVEL_UNITS if speed_fed
                  else tuple(u for u in _TRAVEL_UNITS if not u[1].startswith("a speed")))
    unit = _unit(r.travel, units_here)
    if unit is not None:
        return Finding("travel_ratio", status, f"{said}: {unit[0]}?", unit[1], r.travel)
    if not r.travel > 0:  # Σ distance rolled is never negative: it rolled nothing
        return Finding("travel_ratio", status, f"{said}: the odometry does not move where the truth does",
                       "check that the log's distance or speed channel is the robot's (the topic, column or "
                       "field read)", r.travel)
    if isinstance(robot, DiffDrive):
        entry = ("the wheel speeds' unit (m/s) and c_left, c_right" if speed_fed
                 else "m_per_tick (the wheels' radius and ticks per revolution)")
    else:
        entry = "the speed's unit and c_scale" if speed_fed else "m_per_tick"
    why = ("no calibration error is this large" if status == "fail"
           else "calibrate fits a scale, but one this far off is more often a unit or the robot file")
    return Finding("travel_ratio", status, f"{said}: {why}",
                   f"check {entry} in the robot file and the log's distance unit", r.travel)


def _turn_finding(r: MotionRatios, robot: Robot, judged: str = "", clock: TimeUnitOff | None = None
                  ) -> Finding:
    per_metre = r.turn / r.travel if math.isfinite(r.travel) and r.travel > 0 else math.nan
    said = (f"the odometry turns {r.turn:.3g} ± {r.turn_se:.2g} × as much as the truth "
            f"({r.odometry_turned:.3g} rad against {r.truth_turned:.3g} rad over {r.turns} turns"
            + (f"; {per_metre:.3g} × per metre driven)" if math.isfinite(per_metre) else ")") + judged)
    # A wheeled base turns by the distance its wheels roll (a car and a tricycle by the
    # steering angle per metre), so a distance's scale scales its turning alike: only the
    # turning per metre speaks of the steering or the wheel base. A gyro's or a compass's
    # turning is its own, whatever the speed.
    by_distance = isinstance(robot, (DiffDrive, Car, Tricycle))
    metred = by_distance and math.isfinite(per_metre)
    gain = per_metre if metred else r.turn
    # The turning per metre's standard error: both ratios' errors, taken as independent.
    gain_se = math.hypot(r.turn_se, per_metre * r.travel_se) / r.travel if metred else r.turn_se
    status = _status(gain, TURN_WARN, gain_se)
    if status == "ok":
        return Finding("turn_ratio", "ok", said + _covers_one(gain, TURN_WARN, gain_se), value=gain)
    if clock is not None:
        # MRCLAM user study: both clocks in ms turned 1.44e+03 × and advised yaw_rate_deg.
        return Finding("turn_ratio", status, f"{said}: {clock.cause()}", clock.advice(), gain)
    unit = _unit(gain, _TURN_UNITS)
    if unit is not None:
        return Finding("turn_ratio", status, f"{said}: {unit[0]}?", unit[1], gain)
    if gain < NO_TURN:
        return _no_turn_finding(said, gain, robot)
    if isinstance(robot, DiffDrive):
        advice = (f"check wheel_base in the robot file: the turning per metre says about "
                  f"{robot.wheel_base * gain:.3g} m (the file has {robot.wheel_base:.3g} m)")
    elif isinstance(robot, Car) and gain > 1:
        # Small angles: the turn per metre is tan(α)/L ≈ steer / (ratio · L).
        advice = (f"a steering-wheel angle read as the road wheels' angle? set steering_ratio to about "
                  f"{robot.steering_ratio * gain:.2g} (the file has {robot.steering_ratio:.3g}), or check "
                  "wheel_base and the steering's unit")
    elif isinstance(robot, Car):
        advice = "check the steering's unit, steering_ratio and wheel_base in the robot file"
    elif isinstance(robot, Tricycle):
        # Small angles: the turn per metre is sin(α)/L ≈ steer / (ratio · L); a steering
        # encoder's ticks need their ticks per radian as the ratio (user study: 8192 a turn).
        advice = (f"check the steering's unit: radians (steer_deg for degrees), or steering_ratio in the "
                  f"robot file (the steer channel per radian of the wheel, an encoder's ticks per radian) "
                  f"about {robot.steering_ratio * gain:.4g} (the file has {robot.steering_ratio:.4g}); or "
                  "wheel_to_axle")
    else:
        advice = "check the yaw rate's unit and scale (yaw_rate_deg for °/s)"
    return Finding("turn_ratio", status, said, advice, gain)


def _unseen_finding(u: UnseenTurning, robot: Robot, judged: str = "") -> Finding:
    """The ``turn_ratio`` failure where the odometry turns between stretches far more than
    a truth that barely turns (:func:`unseen_turning`): its turning is scaled up, by at least
    :attr:`UnseenTurning.times`."""
    said = (f"the odometry's turns between consecutive {u.span:.3g} s stretches vary by {u.odometry:.3g} rad "
            f"RMS about their steady turn, where the truth's vary by {u.truth:.2g} rad (its noise "
            f"{u.noise:.2g} rad; {u.pairs} pairs){judged}: it turns at least {u.times:.3g}x as much as the "
            "truth, whose turns are too small for a ratio")
    if isinstance(robot, Car):
        advice = (f"a steering-wheel angle read as the road wheels' angle? set steering_ratio in the robot "
                  f"file (the file has {robot.steering_ratio:.3g}; a car's is about 12-20), or check the "
                  "steering's unit (steer_deg for degrees)")
    elif isinstance(robot, Tricycle):
        advice = ("check the steering's unit (steer_deg for degrees) or steering_ratio in the robot file "
                  f"(the steer channel per radian of the wheel; the file has {robot.steering_ratio:.4g})")
    elif isinstance(robot, DiffDrive):
        advice = (f"check wheel_base in the robot file (the file has {robot.wheel_base:.3g} m) and that the "
                  "left and right channels are two wheels read in one unit")
    elif isinstance(robot, CompassOdometry):
        advice = "check the heading's unit (heading_deg for degrees)"
    else:
        advice = "check the yaw rate's unit (yaw_rate_deg for deg/s) and scale"
    return Finding("turn_ratio", "fail", said, advice, u.times)


def _no_turn_finding(said: str, gain: float, robot: Robot) -> Finding:
    """The ``turn_ratio`` failure where the odometry turns the other way to the truth
    (``gain`` ≤ −:data:`NO_TURN`) or hardly at all: a sign or the source of the turning is
    wrong, which no calibration fixes (a scale of −1 or of 1/``gain`` is no robot's)."""
    if gain <= -NO_TURN:
        what = "it turns the opposite way to the truth"
        if isinstance(robot, DiffDrive):
            advice = ("a sign flipped: left and right swapped, or one wheel's sign flipped (the channels "
                      "check names the mapping that fits)")
        elif isinstance(robot, (Car, Tricycle)):
            advice = "the steering angle's sign is flipped (positive steers left, counter-clockwise)"
        elif isinstance(robot, CompassOdometry):
            advice = ("the heading's sign is flipped (counter-clockwise positive; a compass's bearing turns "
                      "clockwise)")
        else:
            advice = ("the yaw rate's sign is flipped (counter-clockwise positive, about the robot's up "
                      "axis): an IMU mounted upside down, or the wrong axis")
    else:
        what = "it hardly turns where the truth does"
        if isinstance(robot, DiffDrive):
            advice = ("check that the left and right channels are two different wheels, and wheel_base in "
                      "the robot file")
        elif isinstance(robot, (Car, Tricycle)):
            advice = ("check that the steering channel is the road wheels' angle (the right column or "
                      "field) and its unit (radians read as degrees turn 57x too little)")
        elif isinstance(robot, CompassOdometry):
            advice = ("check that the heading channel is the robot's heading (the right column or field) "
                      "and its unit")
        else:
            advice = ("the yaw rate read is not the robot's: an IMU not mounted level turns about another "
                      "axis (its angular_velocity.x or .y is the yaw rate then: --imu-up), or the wrong "
                      "topic or field; check the unit too (radians read as degrees turn 57x too little)")
    return Finding("turn_ratio", "fail", f"{said}: {what}", advice, gain)


#: Stretches of :func:`motion_follows` [s]: long enough that a robot's stops and starts
#: show, short enough that a run holds tens of them.
FOLLOW_SPAN = 2.0
#: Fewest stretches :func:`motion_follows` judges on.
FOLLOW_STRETCHES = 50
#: Fewest stretches :func:`speed_clock` judges on: its standard error comes from the misfit
#: itself, so fewer do than a correlation needs (simulated 40–200 s drives against a 0.5 m
#: GPS: 18–100 stretches, errors within 0.5–0.7 of the stated standard error); a 56 s half
#: drive's 26 stretches went unchecked at 50 while its fitted clock was 0.9 s off.
CLOCK_STRETCHES = 15
#: A correlation below this between the odometry's and the truth's travel per stretch is a
#: truth that does not follow the log (another robot's, another run's, a clock far off).
FOLLOWS = 0.4


@dataclass(frozen=True)
class _Travel:
    """The truth's chord over consecutive stretches of :data:`FOLLOW_SPAN` seconds (wider for a
    sparse truth), and the distance the odometry rolls, for :func:`motion_follows` and
    :func:`speed_clock`: stretches from ``start`` to ``end`` [s] (S,), their ``chord`` [m]
    (S,), the log's times ``t`` [s] (N,) and the distance rolled by each row ``rolled`` [m]
    (N,), reversing counted."""

    start: NDArray[np.float64]
    end: NDArray[np.float64]
    chord: NDArray[np.float64]
    t: NDArray[np.float64]
    rolled: NDArray[np.float64]

    def odometry(self, late: float | NDArray[np.float64] = 0.0) -> NDArray[np.float64]:
        """The distance the odometry rolls over each stretch, the truth's clock ``late`` [s]
        (a fix stamped t is the pose at log time t − late); ``late`` of shape (G, 1) gives
        (G, S)."""
        return (np.interp(self.end - late, self.t, self.rolled)
                - np.interp(self.start - late, self.t, self.rolled))


def _travel(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None, margin: float = 0.0
            ) -> _Travel | None:
    """The stretches of :class:`_Travel` over the truth's fixes at least ``margin`` [s] inside
    the log's span; None where fewer than 3 fixes are."""
    from odomkit.kinematics import body_steps

    t = np.asarray(log.t, dtype=float)
    inside = (truth.t >= t[0] + margin) & (truth.t <= t[-1] - margin)
    tt, xy = truth.t[inside], truth.xy[inside]
    if tt.size < 3:
        return None
    first, last = _stretch_ends(tt, tt[0], tt[-1], max(FOLLOW_SPAN, heading_span(truth)),
                                longest_gap(truth, max_gap))
    rolled = np.concatenate(([0.0], np.cumsum(np.abs(body_steps(robot, log).dd))))
    return _Travel(tt[first], tt[last], np.linalg.norm(xy[last] - xy[first], axis=1), t, rolled)


def motion_follows(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None = 0.5,
                   noise: float | None = None) -> tuple[float, int]:
    """How closely the truth's motion follows the odometry's: the correlation, over
    consecutive stretches of :data:`FOLLOW_SPAN` seconds (wider for a sparse truth), of the
    distance the odometry rolls in each with the truth's chord over it, and the number of
    stretches. A robot's own truth moves when its odometry does, stops when it stops (r
    near 1, whatever the calibration: a scale error keeps the correlation); another robot's
    truth, another run's, or one whose clock is seconds off does not (r near 0).

    NaN where it cannot tell: fewer than :data:`FOLLOW_STRETCHES` stretches, or travel per
    stretch that hardly varies (a constant speed correlates with nothing: the odometry's
    spread under a tenth of its mean, or the truth's chords' spread under 4 × their noise
    σ√2, ``noise`` as in :func:`motion_ratios`)."""
    found = _travel(log, robot, truth, max_gap)
    if found is None:
        return math.nan, 0
    stretches = int(found.chord.size)
    if stretches < FOLLOW_STRETCHES:
        return math.nan, stretches
    odometry, chord = found.odometry(), found.chord
    sigma = judging_noise(truth, noise)[0]
    spread, chord_spread = float(np.std(odometry)), float(np.std(chord))
    if not (spread > 0 and spread >= 0.1 * float(np.mean(odometry))
            and chord_spread > 0 and chord_spread >= 4.0 * math.sqrt(2.0) * sigma):
        return math.nan, stretches
    return float(np.corrcoef(odometry, chord)[0, 1]), stretches


def _follows_finding(r: float, stretches: int) -> Finding | None:
    if not math.isfinite(r):
        return None
    said = (f"over {stretches} stretches, the distance the odometry rolls in each and the truth's chord "
            f"over it correlate at r = {r:.2f}")
    if r >= FOLLOWS:
        return Finding("truth_follows", "ok", f"the truth moves when the odometry does: {said}")
    return Finding("truth_follows", "fail", f"the truth does not move when the odometry does: {said} (a "
                   "robot's own truth: near 1): the truth of another robot or run, or on a clock seconds off",
                   "give this log's own truth (the i-th --truth belongs to the i-th log), or its clock "
                   "offset (--truth-time-offset)")


#: The clock offsets :func:`speed_clock` tries [s]: calibrate's range (positions.MAX_TIME_OFFSET).
_SPEED_CLOCK_GRID = np.arange(-2.0, 2.0 + 1e-9, 0.02)


def speed_clock(logs: Sequence[OdometryLog], robot: Robot, truths: Sequence[Truth],
                max_gap: float | None = 0.5) -> tuple[float, float] | None:
    """The truth's clock offset δ [s] (a fix stamped t is the pose at log time t − δ) that
    the vehicle's speed alone gives, and its standard error: over consecutive stretches of
    :data:`FOLLOW_SPAN` seconds (wider for a sparse truth), the truth's chord against the
    distance the odometry rolls over the same stretch δ earlier, a scale fitted at each δ,
    the sum of squared misfits smallest (pooled over the runs). Speed changes (starts,
    stops, braking) pin it; what the vehicle turns does not enter, so a lag in its turning
    (a steering sensor's, the yaw's response) cannot move it, where a fit of positions
    takes such a lag as the clock. Its standard error comes from the misfit's curvature
    about its minimum, σ̂²/k with σ̂² the misfit per stretch.

    None where the speeds cannot tell: fewer than :data:`CLOCK_STRETCHES` stretches in all,
    travel per stretch that hardly varies (under a tenth of its mean), or a minimum at the
    grid's edge (±2 s)."""
    misfit = np.zeros(_SPEED_CLOCK_GRID.size)
    stretches, varies = 0, False
    for log, truth in zip(logs, truths, strict=True):
        found = _travel(log, robot, truth, max_gap, margin=2.0)  # room to move the clock
        if found is None or found.chord.size == 0:
            continue
        chord = found.chord
        # (grid, stretches): the odometry's travel over each stretch with the clock δ late
        odo = found.odometry(_SPEED_CLOCK_GRID[:, None])
        scale = np.sum(odo * chord, axis=1) / np.maximum(np.sum(odo * odo, axis=1), 1e-300)
        misfit += np.sum((chord[None, :] - scale[:, None] * odo) ** 2, axis=1)
        stretches += chord.size
        middle = odo[_SPEED_CLOCK_GRID.size // 2]
        varies = varies or bool(np.std(middle) > 0.1 * np.mean(middle) > 0)
    if stretches < CLOCK_STRETCHES or not varies:
        return None
    best = int(np.argmin(misfit))
    if best in (0, misfit.size - 1):
        return None
    # The parabola through the minimum and its neighbours: misfit ≈ m* + k (δ − δ*)².
    h = float(_SPEED_CLOCK_GRID[1] - _SPEED_CLOCK_GRID[0])
    curvature = (misfit[best - 1] - 2 * misfit[best] + misfit[best + 1]) / (2 * h * h)
    if not curvature > 0:
        return None
    shift = (misfit[best - 1] - misfit[best + 1]) / (4 * curvature * h)
    sigma2 = float(misfit[best]) / max(stretches - 2, 1)
    return float(_SPEED_CLOCK_GRID[best] + shift), float(math.sqrt(sigma2 / curvature))


def speed_clock_note(fitted: float, std_error: float, logs: Sequence[OdometryLog], robot: Robot,
                     truths: Sequence[Truth], max_gap: float | None = 0.5) -> str | None:
    """The warning where a calibration's fitted clock offset [s] (``std_error`` its own)
    and :func:`speed_clock`'s differ by more than 3 of their joint standard errors and
    0.2 s: the fit took something else for the clock, most often a lag in the turning,
    which moves a path's positions as a late clock does. None where they agree or the
    speeds cannot tell."""
    with np.errstate(all="ignore"):
        found = speed_clock(logs, robot, truths, max_gap)
    if found is None:
        return None
    offset, se = found
    joint = math.hypot(se, std_error)
    if abs(fitted - offset) <= max(3.0 * joint, 0.2):
        return None
    return (f"the fitted truth clock offset, {fitted:+.2f} s, is not the one the speeds give: the truth's "
            f"travel over {FOLLOW_SPAN:g} s stretches matches the odometry's best at {offset:+.2f} ± "
            f"{se:.2f} s. The fit of positions may have taken a lag in the turning (the steering's or the "
            "yaw's response) for the truth's clock, and every command that reads the robot file's [truth] "
            f"time_offset moves the truth by it: try --truth-time-offset {offset:.2f} (calibrate, then "
            "fit-noise and evaluate) and compare")


def follows_note(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None = 0.5) -> str | None:
    """The ``truth_follows`` failure as one warning (message; advice), for the honesty test: a
    covariance scored against another robot's truth reads "optimistic" (MRCLAM: NEES 97),
    with nothing to say why. None where the truth follows, or it cannot tell."""
    with np.errstate(all="ignore"):
        found = _follows_finding(*motion_follows(log, robot, truth, max_gap))
    if found is None or found.status == "ok":
        return None
    return f"{found.message}; {found.advice}"


def check_truth_motion(log: OdometryLog, robot: Robot, truth: Truth | None,
                       max_gap: float | None = 0.5, noise: float | None = None) -> list[Finding]:
    """The ``travel_ratio`` and ``turn_ratio`` findings (none without truth); ``max_gap`` and
    ``noise`` as in :func:`motion_ratios`."""
    if truth is None:
        return []
    # A fuzzed or broken file (positions of 1e200 m) overflows here: that is no finding of
    # this check's, which then compares nothing (the ratios come out NaN).
    with np.errstate(all="ignore"):
        r = motion_ratios(log, robot, truth, max_gap, noise)
        used, estimate = judging_noise(truth, noise)
    # Said wherever it judged: a check that reads noise no one gave says whose it is.
    judged = "" if estimate is None else (
        f" (judged at the {used:.3g} m sigma the fixes state, not their {estimate:.2g} m scatter about a "
        "smooth path, which misses a GPS's error correlated in time; --truth-sigma sets it)")
    clock = time_unit_off(log, robot, truth, r, max_gap, noise)
    found = []
    if math.isfinite(r.travel):
        found.append(_travel_finding(r, robot, not SPEED_CHANNELS.isdisjoint(log.channels), judged, clock))
    else:
        found.append(Finding("travel_ratio", "ok", f"only {r.travel_stretches} straight stretch(es) where "
                             "the truth moves beyond its noise: the odometry's travel not compared with the "
                             "truth's"))
    if math.isfinite(r.turn) and truth.theta is not None and abs(r.turn - 1.0) < OWN_HEADING and \
            r.turn_se < OWN_HEADING:
        # Agreement no sensor gives: the truth's heading is the odometry's own (a lawn mower's
        # "ground truth" heading was its integrated gyro, to 1e-15: user study).
        found.append(Finding("turn_ratio", "warn", f"the odometry turns {r.turn:.9g} ± {r.turn_se:.2g} × as "
                             f"much as the truth over {r.turns} turns: an agreement no two sensors give, so "
                             "the truth's heading is the odometry's own (integrated from the same gyro or "
                             "wheels)",
                             "compare against an independent heading, or read the truth as positions only "
                             "(--truth-columns without theta), which then checks the turning"))
    elif math.isfinite(r.turn):
        found.append(_turn_finding(r, robot, judged, clock))
    elif (r.unseen is not None and r.unseen.odometry >= UNSEEN_TURN and r.unseen.times >= NOT_NOISE
          and clock is None):
        found.append(_unseen_finding(r.unseen, robot, judged))
    else:
        varies = ("" if r.unseen is None else
                  f" (between {r.unseen.pairs} pairs of {r.unseen.span:.3g} s stretches its turns vary "
                  f"{r.unseen.times:.2g}x the truth's, or its noise: under the {NOT_NOISE:g}x that says a "
                  "unit or a robot-file entry)")
        found.append(Finding("turn_ratio", "ok", f"only {r.turns} turn(s) beyond the truth's noise: the "
                             f"odometry's turning not compared with the truth's{varies}"))
    with np.errstate(all="ignore"):
        follows = _follows_finding(*motion_follows(log, robot, truth, max_gap, noise))
    if follows is not None:
        # First: a truth that is not the log's makes every ratio after it meaningless.
        found.insert(0, follows)
    return found


def motion_problems(log: OdometryLog, robot: Robot, truth: Truth, max_gap: float | None = 0.5, *,
                    warnings: bool = False, noise: float | None = None) -> list[str]:
    """The failures of :func:`check_truth_motion` (and its warnings, with ``warnings``) as
    ``"LOG: message; advice"`` lines, for a command that fits (``calibrate``, ``fit-noise``):
    a unit read wrong or a steering ratio left out bends a fit without saying why."""
    bad = ("fail", "warn") if warnings else ("fail",)
    return [f"{log.source or 'the log'}: {f.message}" + (f"; {f.advice}" if f.advice else "")
            for f in check_truth_motion(log, robot, truth, max_gap, noise) if f.status in bad]
