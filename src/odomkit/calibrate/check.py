"""A data check before calibrating (``odomkit check``): is a log fit to calibrate from, and
what to record next.

Each check is a pure function of a log (and the robot, and the truth when there is one)
returning :class:`~odomkit.calibrate.check_finding.Finding`\\ s, each ``ok``, ``warn`` or
``fail`` with a message in the log's own numbers and, where something is missing or wrong,
what to do about it:

* :func:`check_values` — NaN or infinite values (the file readers refuse them already, so
  this guards logs built in Python);
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

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.check_channels import check_channels
from odomkit.calibrate.check_finding import Finding
from odomkit.calibrate.check_identifiable import check_identifiable, identifiability_sigma
from odomkit.calibrate.check_ratios import check_truth_motion
from odomkit.calibrate.check_truth import check_truth_heading
from odomkit.log import INCREMENT_CHANNELS, OdometryLog
from odomkit.robot import Robot
from odomkit.truth import Truth, truth_at

__all__ = [
    "check_counters", "check_log", "check_motion", "check_stuck", "check_time", "check_values", "GAP_FACTOR",
    "next_steps",
]

#: A step longer than this many median periods is a time jump.
GAP_FACTOR = 5.0
# A wheel (distance channel) silent this long while the robot moves is stuck [s].
_STUCK_SECONDS = 1.0


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
    return sorted(c for c in log.channels if c in INCREMENT_CHANNELS or c == "speed")


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
    pairs = [("ticks_left", "ticks_right"), ("dist_left", "dist_right")]
    truth_turn = odo_turn = None
    if truth is not None and truth.has_heading:
        from odomkit.kinematics import body_steps

        s = truth_at(truth, t, max_gap)
        truth_turn = np.where(s.valid, s.poses[:, 2], np.nan)
        odo_turn = np.concatenate(([0.0], np.cumsum(body_steps(robot, log).dtheta)))
    for a, b in pairs:
        if a not in values or b not in values:
            continue
        for quiet, busy in ((a, b), (b, a)):
            mask = (values[quiet] == 0) & (values[busy] != 0)
            for i, j in _streaks(mask):
                if float(np.sum(step_t[i:j])) < _STUCK_SECONDS or not np.any(values[quiet]):
                    continue
                span = f"from t = {t[i]:.6g} s to {t[j]:.6g} s"
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
    if truth is not None and channels:
        s = truth_at(truth, t, max_gap)
        silent = np.all([values[c] == 0 for c in channels], axis=0) & s.valid[:-1] & s.valid[1:]
        for i, j in _streaks(silent):
            # The net displacement, not the summed steps: those add up the truth's own jitter.
            moved = float(np.hypot(*(s.poses[j, :2] - s.poses[i, :2])))
            if float(np.sum(step_t[i:j])) >= _STUCK_SECONDS and moved > max(0.05, 10 * truth.sigma):
                found.append(Finding("stuck", "fail", f"the odometry reads no motion from t = {t[i]:.6g} s "
                                     f"to {t[j]:.6g} s while the truth moves {moved:.3g} m: a stuck encoder, "
                                     "or a truth whose clock lags the odometry's",
                                     "check the encoders, and the time offset between truth and log"))
                break
    return found or [Finding("stuck", "ok", "no channel sits at zero while the robot moves")]


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
        found.append(Finding("turning", "warn", f"{turns}: hardly any turning",
                             "drive turns both ways, at least a half turn each (e.g. a square each way)"))
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
    """Every check, in the order a user fixes things: values and time, counters, stuck
    channels, the channel mapping, the truth's own heading, the odometry's travel and turning
    against the truth's, then what the motion can identify."""
    found = check_values(log)
    if any(f.status == "fail" for f in found):
        return found
    found += check_time(log)
    if len(log) < 2 or any(f.status == "fail" and f.check == "time" for f in found):
        return found
    found += check_counters(log)
    found += check_stuck(log, robot, truth, max_gap)
    found += check_channels(log, robot, truth, spin=spin, max_gap=max_gap)
    if any(f.status == "fail" and f.check == "channels" for f in found):
        return found  # what the motion identifies means nothing until the channels are right
    found += check_truth_heading(log, robot, truth, max_gap)
    found += check_truth_motion(log, robot, truth, max_gap)
    found += check_motion(log, robot)
    found += check_identifiable(log, robot, identifiability_sigma(truth))
    return found


def next_steps(findings: list[Finding]) -> list[str]:
    """The advice of every finding that is not ok, failures first, without repeats."""
    ordered = sorted((f for f in findings if f.status != "ok" and f.advice),
                     key=lambda f: 0 if f.status == "fail" else 1)
    return list(dict.fromkeys(f.advice for f in ordered if f.advice))
