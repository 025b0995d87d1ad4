"""A data check before calibrating (``odomkit check``): is a log fit to calibrate from, and
what to record next.

Each check is a pure function of a log (and the robot, and the truth when there is one)
returning :class:`~odomkit.calibrate.check_finding.Finding`\\ s, each ``ok``, ``warn`` or
``fail`` with a message in the log's own numbers and, where something is missing or wrong,
what to do about it:

* :func:`check_values` — NaN or infinite values (the file readers and
  :class:`~odomkit.log.OdometryLog` refuse them already, so this guards a log whose arrays
  were changed in place after it was built);
* :func:`check_time` — repeated or decreasing timestamps, and time jumps (a step more
  than :data:`GAP_FACTOR` times the median period);
* :func:`check_counters` — counter wraps (an increment within a few typical steps of
  ±2^b for a b-bit counter) and other implausible spikes;
* :func:`check_stuck` — a wheel (or any distance channel) reading nothing while the other
  wheel, or the truth, moves;
* :func:`~odomkit.calibrate.check_channels.check_channels` — left and right swapped or a
  sign flipped: against the truth (the channel mapping that reproduces the truth's motion
  best: its travel and turn with a heading truth, its path's shape with a position-only
  one), or from a spin in a known direction, or, with neither, the hint a flipped sign
  leaves (a robot that spins all the time);
* :func:`~odomkit.calibrate.check_truth.check_truth_heading` — a truth's heading against
  the direction its positions move;
* :func:`~odomkit.calibrate.check_truth.check_truth_interpolated` — a truth interpolated
  between sparse keyframes, not measured;
* :func:`~odomkit.calibrate.check_ratios.check_truth_motion` — the odometry's travel and
  turning against the truth's (a unit read wrong, a robot-file entry missing);
* :func:`check_motion` — distance and turning both ways;
* :func:`~odomkit.calibrate.check_identifiable.check_identifiable` — how well each
  calibration parameter of every robot ``odomkit calibrate`` calibrates is pinned by this
  log's motion: the part of its effect on the track that no other parameter can mimic, from
  the calibration model's own Jacobian, turned into a standard error with the truth's noise.

:func:`check_log` runs them all; :func:`next_steps` collects the advice.

This module holds the checks of the log itself (values, time, counters, stuck channels,
motion), :func:`check_log` and :func:`next_steps`. The channel-mapping check lives in
:mod:`odomkit.calibrate.check_channels`, the identifiability check in
:mod:`odomkit.calibrate.check_identifiable`, and the finding all of them return in
:mod:`odomkit.calibrate.check_finding`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.check_channels import check_channels
from odomkit.calibrate.check_finding import Finding
from odomkit.calibrate.check_identifiable import check_identifiable, identifiability_sigma
from odomkit.calibrate.check_ratios import check_truth_motion
from odomkit.calibrate.check_truth import check_truth_heading, check_truth_interpolated
from odomkit.log import INCREMENT_CHANNELS, SPEED_CHANNELS, WHEEL_PAIRS, OdometryLog, clock_text
from odomkit.robot import Robot
from odomkit.truth import Truth, truth_at, truth_noise
from odomkit.units import SLOW_ROWS, SLOWEST_PERIOD, period_unit

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps
    from odomkit.truth import TruthSamples

__all__ = [
    "check_counters", "check_log", "check_motion", "check_speed", "check_stuck", "check_time", "check_values",
    "GAP_FACTOR", "next_steps",
]

#: A step longer than this many median periods is a time jump.
GAP_FACTOR = 5.0
# A wheel (distance channel) silent this long while the robot moves is stuck [s].
_STUCK_SECONDS = 1.0
# The truth's clock may be this far from the log's before a whole silent stretch is no
# longer its lead or lag [s] (calibrate fits offsets up to 2 s: positions.MAX_TIME_OFFSET).
_CLOCK_SECONDS = 2.0
# A truth that moves slower than this share of the odometry's speed around a silent stretch
# creeps (its own drift, or a robot that crawls): a stuck encoder leaves it at that speed.
_CREEP_SHARE = 0.1
# Speeds at a silent stretch's edges below this share of the log's typical speed are a crawl:
# a speed sensor that reads 0 below some speed jumps to and from 0 there.
_CRAWL_SHARE = 0.25


def _rows(index: NDArray[np.intp], limit: int = 5) -> str:
    shown = ", ".join(str(int(i) + 1) for i in index[:limit])
    return shown + (f" and {index.size - limit} more" if index.size > limit else "")


def check_values(log: OdometryLog) -> list[Finding]:
    """NaN or infinite times or channel values (row numbers count from 1)."""
    found = []
    for name, values in [("time", log.t), *log.channels.items()]:
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            found.append(Finding("values", "fail", f"{name} is NaN or infinite at row(s) {_rows(bad)}",
                                 "drop or interpolate those rows before calibrating"))
    return found or [Finding("values", "ok", "every value is a finite number")]


def check_time(log: OdometryLog) -> list[Finding]:
    """Repeated or decreasing timestamps, and jumps of more than :data:`GAP_FACTOR` median periods
    (a warning where the log counts increments, which a dropped-out logger loses; said, but
    ok, where it holds rates, which a log written on each change has gaps in by design)."""
    if len(log) < 2:
        return [Finding("time", "fail", f"the log has {len(log)} row(s): nothing to calibrate from",
                        "record a longer log")]
    bad = np.flatnonzero(~np.isfinite(log.t))
    if bad.size:  # every comparison with NaN is False: the checks below would pass it
        return [Finding("time", "fail", f"time is NaN or infinite at row(s) {_rows(bad)}: the time checks "
                        "need numbers", "drop or interpolate those rows before calibrating")]
    dt = np.diff(log.t)
    found = []
    back = np.flatnonzero(dt < 0)
    if back.size:
        found.append(Finding("time", "fail", f"time goes backwards at {back.size} row(s) ({_rows(back + 1)})",
                             "sort the rows by time or fix the logger's clock"))
    same = np.flatnonzero(dt == 0)
    if same.size:
        found.append(Finding("time", "warn", f"{same.size} repeated timestamp(s) (rows {_rows(same + 1)}): "
                             "zero-length steps", "check the logger: two samples with one time stamp"))
    positive = dt[dt > 0]
    if positive.size:
        median = float(np.median(positive))
        jumps = np.flatnonzero(dt > GAP_FACTOR * median)
        if jumps.size:
            worst = int(jumps[np.argmax(dt[jumps])])
            said = (f"{jumps.size} time jump(s) longer than {GAP_FACTOR:g}x the median period "
                    f"{median:.4g} s; the longest {dt[worst]:.4g} s, "
                    f"{log.t[worst] - log.t[0]:.6g} s into the log (row {worst + 2})")
            if INCREMENT_CHANNELS.isdisjoint(log.channels):
                # Rates (speed, yaw rate, steering) are held from each row to the next: a log
                # written when a command changes (cmd_vel, the MRCLAM robots) has such gaps by
                # design, and nothing is lost across them.
                found.append(Finding(
                    "time", "ok", f"{said}: each row's rates are held until the next (exact for commands "
                    "logged when they change)"))
            else:
                found.append(Finding(
                    "time", "warn", said,
                    "a dropped-out logger loses motion: record again, or split the log at the jumps"))
        if (unit := period_unit(median)) is not None:
            found.append(Finding(
                "time", "warn", f"the median period is {median:.4g} s, {SLOW_ROWS} "
                f"({SLOWEST_PERIOD:g} s at most): a time column in {unit} read as seconds reads so",
                f"give the log's time unit (--time-unit {unit})"))
    return found or [Finding("time", "ok", f"{len(log)} rows, steady period {np.median(dt):.4g} s, "
                                         "no repeated stamps or jumps")]


def check_counters(log: OdometryLog) -> list[Finding]:
    """Counter wraps and spikes in the tick channels (increments per row)."""
    found = []
    for name in sorted(c for c in log.channels if c.startswith("ticks")):
        x = np.asarray(log.channels[name][1:], dtype=float)
        x = x[np.isfinite(x)]  # a NaN is check_values' finding; here it would hide every spike
        if x.size < 10:
            continue
        typical = max(float(np.percentile(np.abs(x), 99)), 1.0)
        big = np.flatnonzero(np.abs(x) > 20.0 * typical)
        if not big.size:
            continue
        for bits in (8, 16, 24, 32, 64):
            near = np.abs(np.abs(x[big]) - 2.0**bits) <= 4.0 * typical
            if near.all():
                found.append(Finding(
                    "counters", "fail", f"{name} jumps by about ±2^{bits} at {big.size} row(s) "
                    f"({_rows(big + 1)}): a {bits}-bit counter wrapping",
                    f"read the raw counter with --cumulative --wrap-bits {bits}"))
                break
        else:
            found.append(Finding(
                "counters", "warn", f"{name} has {big.size} spike(s) over 20x its typical step {typical:.4g} "
                f"(rows {_rows(big + 1)}), largest {np.max(np.abs(x[big])):.4g}",
                "check the encoder wiring or the logger: such steps are not wheel motion"))
    if not any(c.startswith("ticks") for c in log.channels):
        return [Finding("counters", "ok", "no tick channels to check")]
    return found or [Finding("counters", "ok", "no counter wraps or spikes in the tick channels")]


def _distance_channels(log: OdometryLog) -> list[str]:
    return sorted(c for c in log.channels if c in INCREMENT_CHANNELS or c in SPEED_CHANNELS)


def _streaks(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(start, stop) of every run of True in ``mask``."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True))


def check_stuck(log: OdometryLog, robot: Robot, truth: Truth | None = None,
                max_gap: float | None = 0.5) -> list[Finding]:
    """A distance channel that reads nothing while the robot moves, for at least 1 s.

    A wheel of a differential drive is stuck where it reads 0 and the other wheel turns
    (a pivot about that wheel does that too: with truth the pivot is told apart, since
    the truth then turns as the odometry says, within 30 %); any channel is stuck where the
    truth moves and the channel does not.
    """
    found = []
    t = log.t
    step_t = np.diff(t)
    channels = _distance_channels(log)
    values = {c: (log.channels[c][1:] if c in INCREMENT_CHANNELS else log.channels[c][:-1]) for c in channels}
    for c in channels:
        if values[c].size and not np.any(values[c]):
            found.append(Finding("stuck", "fail", f"{c} is zero in every row",
                                 "check the channel mapping (--columns) and the encoder"))
    pairs = WHEEL_PAIRS
    truth_turn = odo_turn = None
    # The truth at the rows and the body steps, once for both checks below.
    sampled = None if truth is None else truth_at(truth, t, max_gap)
    steps = None
    if truth is not None and channels:
        from odomkit.kinematics import body_steps

        steps = body_steps(robot, log)
    if sampled is not None and steps is not None and truth is not None and truth.has_heading:
        truth_turn = np.where(sampled.valid, sampled.poses[:, 2], np.nan)
        odo_turn = np.concatenate(([0.0], np.cumsum(steps.dtheta)))
    for a, b in pairs:
        if a not in values or b not in values:
            continue
        for quiet, busy in ((a, b), (b, a)):
            mask = (values[quiet] == 0) & (values[busy] != 0)
            for i, j in _streaks(mask):
                if float(np.sum(step_t[i:j])) < _STUCK_SECONDS or not np.any(values[quiet]):
                    continue
                span = f"from t = {clock_text(t[i])} s to {clock_text(t[j])} s"
                if (truth_turn is not None and odo_turn is not None and np.isfinite(truth_turn[i])
                        and np.isfinite(truth_turn[j])):
                    turned, said = truth_turn[j] - truth_turn[i], odo_turn[j] - odo_turn[i]
                    if abs(turned - said) <= 0.3 * abs(said):
                        continue  # the truth turns as the odometry says: a pivot about the quiet wheel
                    found.append(Finding("stuck", "fail", f"{quiet} reads 0 {span} while {busy} turns: the "
                                         f"odometry turns {said:+.3g} rad there, the truth {turned:+.3g} "
                                         "rad: a stuck encoder or a slipping wheel",
                                         "check the encoder and its cable, then record again"))
                else:
                    found.append(Finding("stuck", "warn", f"{quiet} reads 0 {span} while {busy} turns: a "
                                         "stuck encoder, or a pivot about that wheel",
                                         "give --truth to tell a pivot from a stuck encoder"))
                break
    if truth is not None and sampled is not None and steps is not None:
        found += _silent_while_truth_moves(log, truth, values, sampled, steps)
    return found or [Finding("stuck", "ok", "no channel sits at zero while the robot moves")]


def _speed_around(rate: NDArray[np.float64], moving: NDArray[np.bool_], t: NDArray[np.float64], i: int,
                  j: int) -> float:
    """The odometry's mean speed [m/s] over the moving steps within 1 s before row ``i`` and
    after row ``j`` (the larger side), NaN where neither side moves."""
    dt = np.diff(t)
    sides = []
    for part in (slice(None, i), slice(j, None)):
        near = np.zeros(rate.size, dtype=bool)
        near[part] = True
        near &= moving & (np.abs(t[:-1] - (t[i] if part.stop == i else t[j])) <= _STUCK_SECONDS)
        if near.any():
            sides.append(float(np.sum(rate[near] * dt[near]) / np.sum(dt[near])))
    return max(sides) if sides else math.nan


def _goes_on(truth: Truth, a: float, b: float, c: float, rest: float) -> bool:
    """Whether the truth moves from time ``b`` to ``c`` [s] on in the direction it moved from
    ``a`` to ``b`` (within 60°), both beyond ``rest`` [m]."""
    p = truth_at(truth, [a, b, c], None).poses[:, :2]
    first, second = p[1] - p[0], p[2] - p[1]
    size = float(np.hypot(*first) * np.hypot(*second))
    return bool(np.all(np.isfinite(p)) and min(np.hypot(*first), np.hypot(*second)) > rest
                and float(first @ second) >= 0.5 * size)


def _silent_while_truth_moves(log: OdometryLog, truth: Truth, values: dict[str, NDArray[np.float64]],
                              s: TruthSamples, steps: BodySteps) -> list[Finding]:
    """Stretches of at least 1 s where every distance channel reads 0 while the truth moves
    beyond its noise, each judged by how the truth's motion lies in time:

    * all of it within :data:`_CLOCK_SECONDS` of one end, the truth at rest before (or
      after) it: the truth starts (stops) moving before (after) the odometry does, a clock
      offset or an odometry that misses slow motion (warn, with the direction measured);
    * at under :data:`_CREEP_SHARE` of the odometry's speed around the stretch: a creep,
      the truth's drift or a crawl (warn: a stuck encoder leaves the truth moving at the
      speed the odometry had);
    * the odometry crawls at both edges (under :data:`_CRAWL_SHARE` of its typical speed)
      and the truth moves no faster than three times that: a speed sensor that reads 0
      below some speed (warn, named with the speed);
    * otherwise a stuck encoder, or clocks seconds apart (fail).

    The truth's noise is :func:`odomkit.truth.truth_noise` (its stated σ or its fixes'
    scatter about a smooth path): its net motion must pass max(5 cm, 10σ). ``s`` is the
    truth at the log's rows and ``steps`` the log's body steps.
    """
    from odomkit.integrate import dead_reckon

    t = log.t
    dt = np.diff(t)
    still = np.all([v == 0 for v in values.values()], axis=0)
    silent = still & s.valid[:-1] & s.valid[1:]
    rate = np.divide(np.abs(steps.dd), dt, out=np.zeros(dt.size), where=dt > 0)
    odo: NDArray[np.float64] | None = None  # the odometry's own track, where a stretch needs it
    moving = ~still & (dt > 0)
    typical = float(np.median(rate[moving])) if moving.any() else math.nan
    noise = truth_noise(truth)
    floor = max(0.05, 10.0 * noise)
    # Within this of where it stood, the truth has not moved (its noise, or a tenth of the floor).
    rest = max(3.0 * math.sqrt(2.0) * noise, 0.1 * floor)
    xy = s.poses[:, :2]
    fails: list[Finding] = []
    warns: list[Finding] = []
    for i, j in _streaks(silent):
        duration = float(t[j] - t[i])
        # The net displacement, not the summed steps: those add up the truth's own jitter.
        moved = float(np.hypot(*(xy[j] - xy[i])))
        if duration < _STUCK_SECONDS or moved <= floor:
            continue
        span = (f"the odometry reads no motion from t = {clock_text(t[i])} s to {clock_text(t[j])} s while "
                f"the truth moves {moved:.3g} m")
        rows = t[i: j + 1]
        from_start = np.hypot(*(xy[i: j + 1] - xy[i]).T)
        to_end = np.hypot(*(xy[i: j + 1] - xy[j]).T)
        lead = float(t[j] - rows[np.flatnonzero(from_start <= rest)[-1]])
        lag = float(rows[np.flatnonzero(to_end <= rest)[0]] - t[i])
        after = j < dt.size and bool(moving[j])
        before = i > 0 and bool(moving[i - 1])
        allowed = min(_CLOCK_SECONDS, 0.5 * duration)
        # A clock's lead or lag moves the truth on as it moves beside the stretch; a jump of
        # its fixes (a GNSS's multipath) goes any way.
        leads = after and lead <= allowed and _goes_on(truth, t[j] - lead, t[j], t[j] + max(lead, 0.5), rest)
        lags = before and lag <= allowed and _goes_on(truth, t[i] - max(lag, 0.5), t[i], t[i] + lag, rest)
        if leads and (not lags or lead <= lag):
            warns.append(Finding(
                "stuck", "warn", f"{span}, all of it in the last {lead:.2g} s: the truth starts moving "
                f"{lead:.2g} s before the odometry does, a truth whose clock leads the log's (its fixes "
                "stamped early) or an odometry that misses the start of motion",
                f"check the time offset between truth and log (calibrate fits it; a truth that leads by "
                f"δ takes --truth-time-offset -δ, here up to about -{lead:.2g} s)"))
            continue
        if lags:
            warns.append(Finding(
                "stuck", "warn", f"{span}, all of it in the first {lag:.2g} s: the truth stops moving "
                f"{lag:.2g} s after the odometry does, a truth whose clock lags the log's (its fixes "
                "stamped late) or an odometry that misses the end of motion",
                f"check the time offset between truth and log (calibrate fits it; a truth that lags by "
                f"δ takes --truth-time-offset δ, here up to about {lag:.2g} s)"))
            continue
        speed = moved / duration
        around = _speed_around(rate, moving, t, i, j)
        if not math.isfinite(around):
            around = typical
        if math.isfinite(around) and speed < _CREEP_SHARE * around:
            warns.append(Finding(
                "stuck", "warn", f"{span} in {duration:.3g} s ({speed:.2g} m/s), under a tenth of the "
                f"{around:.2g} m/s the odometry reads beside it: a creep, the truth's own drift or a robot "
                "crawling below what the odometry reads, not a stuck encoder (which leaves the truth "
                "moving at the odometry's speed)",
                "nothing to do if the robot stood; else check the odometry's smallest speed"))
            continue
        edges = [float(rate[k]) for k, there in ((i - 1, before), (j, after)) if there]
        if (edges and min(edges) > 0 and math.isfinite(typical) and max(edges) <= _CRAWL_SHARE * typical
                and speed <= 3.0 * max(edges)):
            sensor = "a speed sensor" if SPEED_CHANNELS & set(values) else "an encoder"
            said = " and ".join(f"{v:.2g} m/s {side}" for v, side in zip(
                edges, [side for side, there in (("just before", before), ("just after", after)) if there],
                strict=True))
            warns.append(Finding(
                "stuck", "warn", f"{span} ({speed:.2g} m/s), and the odometry reads {said}, a crawl "
                f"against its typical {typical:.2g} m/s: {sensor} that reads 0 below about "
                f"{min(edges):.2g} m/s?",
                "nothing to fix if the robot crawls only to stop (calibrate sees a short stop); a log that "
                "crawls often loses that distance: log a channel that reads low speeds (wheel ticks)"))
            continue
        # A stuck encoder loses the distance: over the stretch and _CLOCK_SECONDS either side,
        # the odometry's chord falls short of the truth's by about what the truth moved in it.
        # A truth whose timing differs (a clock offset, or fixes smoothed or interpolated in
        # time) only moves the motion the odometry reads beside the stretch into it.
        lo = int(np.searchsorted(t, t[i] - _CLOCK_SECONDS))
        hi = int(np.searchsorted(t, t[j] + _CLOCK_SECONDS, side="right")) - 1
        lo = lo if s.valid[lo] else i
        hi = hi if s.valid[hi] else j
        if odo is None:  # from the origin, midpoint headings: enough for a chord
            odo = dead_reckon(steps.dd, steps.dtheta, (0.0, 0.0, 0.0), "midpoint")[:, :2]
        lost = float(np.hypot(*(xy[hi] - xy[lo])) - np.hypot(*(odo[hi] - odo[lo])))
        if lost < 0.5 * moved:
            warns.append(Finding(
                "stuck", "warn", f"{span} in {duration:.3g} s ({speed:.2g} m/s), but from "
                f"{_CLOCK_SECONDS:g} s before to {_CLOCK_SECONDS:g} s after it the odometry's chord falls "
                f"short of the truth's by only {lost:.2g} m: the truth moves there what the odometry reads "
                "beside it, a truth whose timing differs (a clock offset either way, or fixes smoothed "
                "or interpolated in time), not a stuck encoder",
                "check the time offset between truth and log, and how the truth's fixes were made"))
            continue
        fails.append(Finding(
            "stuck", "fail", f"{span} in {duration:.3g} s ({speed:.2g} m/s; the odometry reads "
            f"{around:.2g} m/s beside it): a stuck encoder, or truth and log clocks seconds apart",
            "check the encoders, and the time offset between truth and log"))
    return (fails or warns)[:1]


# --- motion ------------------------------------------------------------------------------

#: What turning one way only confounds, by robot type: two parameters that bend a one-way
#: turn alike (a constant curvature added, or the curvature scaled).
_MIMIC = {
    "diff": "a wheel-size ratio and a wheel-base error",
    "tricycle": "a steering offset and a wheel-to-axle (L) error",
    "car": "a steering offset and a wheel-base error",
    "unicycle": "a yaw-rate bias and a yaw-rate scale error",
    "gyro": "a gyro bias and a gyro scale error",
    "compass": "a compass offset and the heading's own errors",
}

def check_speed(log: OdometryLog, robot: Robot) -> list[Finding]:
    """The ``speed`` finding: a log whose odometry moves faster than any wheeled vehicle
    (:func:`odomkit.kinematics.too_fast`) is read wrong (a raw counter read as increments,
    a unit), and fails."""
    from odomkit.kinematics import body_steps, moving_speed, too_fast

    steps = body_steps(robot, log)
    if (fast := too_fast(steps, log)) is not None:
        return [Finding("speed", "fail", *fast)]
    if (speed := moving_speed(steps)) is None:
        return [Finding("speed", "ok", "the odometry does not move")]
    return [Finding("speed", "ok", f"the odometry moves at {speed:.3g} m/s (the median of its moving steps)")]


def check_motion(log: OdometryLog, robot: Robot) -> list[Finding]:
    """Distance driven and turning each way (from the odometry)."""
    from odomkit.kinematics import body_steps

    steps = body_steps(robot, log)
    travel = float(np.sum(np.abs(steps.dd)))
    ccw = float(np.sum(np.clip(steps.dtheta, 0, None)))
    cw = abs(float(np.sum(np.clip(steps.dtheta, None, 0))))
    found = []
    if not all(math.isfinite(x) for x in (travel, ccw, cw)):
        return [Finding(check, "warn", f"the odometry's {what} is not a number (travel {travel:.4g} m, "
                        f"turning {ccw:.3g} rad counter-clockwise and {cw:.3g} rad clockwise): not checked",
                        "check the log's values and the robot file") for check, what in
                (("distance", "travel"), ("turning", "turning"))]
    if travel < 0.2:
        found.append(Finding("distance", "fail", f"the robot travels {travel:.3g} m: too little to calibrate "
                             "from", "drive at least 2 m"))
    elif travel < 2.0:
        found.append(Finding("distance", "warn", f"the robot travels {travel:.3g} m", "drive at least 2 m"))
    else:
        found.append(Finding("distance", "ok", f"the robot travels {travel:.4g} m"))
    turns = f"it turns {ccw:.3g} rad counter-clockwise and {cw:.3g} rad clockwise"
    if max(ccw, cw) < 0.5 * math.pi:
        # Not "hardly any turning": a slalom's 1.47 and 1.32 rad are turning, only not far
        # enough either way (a user study's F1TENTH car).
        found.append(Finding("turning", "warn", f"{turns}: under a quarter turn either way",
                             "drive turns both ways, at least a half turn each (e.g. "
                             + ("a loop round a block, or a roundabout, each way" if robot.type_name == "car"
                                else "a square each way") + ")"))
    elif min(ccw, cw) < 0.5 * math.pi:
        way = "clockwise" if cw < ccw else "counter-clockwise"
        pair = _MIMIC.get(robot.type_name, "two calibration parameters")
        found.append(Finding("turning", "warn", f"{turns}: almost all one way",
                             f"also drive at least a half turn {way}: turning one way lets {pair} mimic each "
                             "other at the run's end, so an endpoint fit (UMBmark, --from endpoints) needs "
                             "both ways; a fit to the whole trajectory copes if 'identifiable' says so"))
    else:
        found.append(Finding("turning", "ok", turns))
    return found



def check_log(log: OdometryLog, robot: Robot, truth: Truth | None = None, *, spin: str | None = None,
              max_gap: float | None = 0.5) -> list[Finding]:
    """Every check, in the order a user fixes things: values and time, counters, the speed
    the odometry moves at, stuck channels, the channel mapping, the truth's own heading, the
    odometry's travel and turning against the truth's, then what the motion can identify."""
    found = check_values(log)
    if any(f.status == "fail" for f in found):
        return found
    found += check_time(log)
    if len(log) < 2 or any(f.status == "fail" and f.check == "time" for f in found):
        return found
    found += check_counters(log)
    found += check_speed(log, robot)
    if found[-1].status == "fail":
        return found  # a log read wrong (a counter as increments): nothing after it means anything
    found += check_stuck(log, robot, truth, max_gap)
    found += check_channels(log, robot, truth, spin=spin, max_gap=max_gap)
    if any(f.status == "fail" and f.check == "channels" for f in found):
        return found  # what the motion identifies means nothing until the channels are right
    found += check_truth_heading(log, robot, truth, max_gap)
    found += check_truth_interpolated(truth)
    found += check_truth_motion(log, robot, truth, max_gap)
    found += check_motion(log, robot)
    failed = [f.check for f in found if f.status == "fail" and f.check in ("travel_ratio", "turn_ratio")]
    if failed:
        # The figures rest on the model describing the drive: an odometry that turns or travels
        # nothing like the truth gave ±1e+11 % (a Husky's IMU read about the wrong axis).
        what = " and ".join({"travel_ratio": "travel", "turn_ratio": "turning"}[c] for c in failed)
        found.append(Finding("identifiable", "warn", f"not judged: the odometry's {what} does not match "
                             "the truth's (above), so what this log would pin cannot be told",
                             "mend the failures above, then check again"))
        return found
    # A parameter beyond its range is said with the calibrate --fix that pins the rest: the
    # windows refitted with it held (only then, for such a parameter).
    held = (None if truth is None else
            lambda name: identifiability_sigma(truth, log, robot, max_gap, fixed=(name,)))
    found += check_identifiable(log, robot, identifiability_sigma(truth, log, robot, max_gap),
                                held_sigma=held)
    return found


def next_steps(findings: list[Finding]) -> list[str]:
    """The advice of every finding that is not ok, without repeats: how the log was read
    first (a counter read as increments misfits every check after it: a user study's LEGO
    robot was first told to flip a channel's sign), then the failures, then the warnings."""
    ordered = sorted((f for f in findings if f.status != "ok" and f.advice),
                     key=lambda f: 0 if f.check == "reading" else 1 if f.status == "fail" else 2)
    return list(dict.fromkeys(f.advice for f in ordered if f.advice))
