"""A data check before calibrating (``odomkit check``): is a log fit to calibrate from, and
what to record next.

Each check is a pure function of a log (and the robot, and the truth when there is one)
returning :class:`Finding`\\ s, each ``ok``, ``warn`` or ``fail`` with a message in the
log's own numbers and, where something is missing or wrong, what to do about it:

* :func:`check_values` — NaN or infinite values (the file readers refuse them already, so
  this guards logs built in Python);
* :func:`check_time` — repeated or decreasing timestamps, and time jumps (a step more
  than :data:`GAP_FACTOR` times the median period);
* :func:`check_counters` — counter wraps (an increment within a few typical steps of
  ±2^b for a b-bit counter) and other implausible spikes;
* :func:`check_stuck` — a wheel (or any distance channel) reading nothing while the other
  wheel, or the truth, moves;
* :func:`check_channels` — left and right swapped or a sign flipped: against the truth
  (the channel mapping that reproduces the truth's motion best: its travel and turn with a
  heading truth, its path's shape with a position-only one), or from a spin in a known
  direction, or, with neither, the hint a flipped sign leaves (a robot that spins all
  the time);
* :func:`check_motion` — distance and turning both ways;
* :func:`check_identifiable` — how well each calibration parameter of every robot
  ``odomkit calibrate`` calibrates is pinned by this log's motion: the part of its effect
  on the track that no other parameter can mimic, from the calibration model's own
  Jacobian, turned into a standard error with the truth's noise.

:func:`check_log` runs them all; :func:`next_steps` collects the advice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from odomkit.log import INCREMENT_CHANNELS, OdometryLog
from odomkit.robot import DiffDrive, Robot, Tricycle
from odomkit.truth import Truth, scatter_sigma, truth_at

if TYPE_CHECKING:
    from odomkit.calibrate.residuals import CalibratedRobot

__all__ = [
    "check_channels", "check_counters", "check_identifiable", "check_log", "check_motion", "check_stuck",
    "check_time", "check_values", "Finding", "GAP_FACTOR", "next_steps", "Status",
]

Status = Literal["ok", "warn", "fail"]
#: A step longer than this many median periods is a time jump.
GAP_FACTOR = 5.0
# A wheel (distance channel) silent this long while the robot moves is stuck [s].
_STUCK_SECONDS = 1.0
# Position noise assumed for the identifiability figures when the truth states none [m]:
# motion-capture noise plus the odometry's own random drift between samples.
_DEFAULT_SIGMA = 0.005


@dataclass(frozen=True)
class Finding:
    """One result of a check.

    Parameters
    ----------
    check : str
        Which check (``time``, ``values``, ``counters``, ``stuck``, ``channels``, ``distance``,
        ``turning``, ``identifiable``, ``reading``).
    status : {"ok", "warn", "fail"}
    message : str
        What was found, in the log's numbers.
    advice : str, optional
        What to do or record next.
    value : float, optional
        The figure the status was judged on, where there is one (``identifiable``: the
        standard error, relative for a scale or length, rad for a steering offset, rad/s
        for a yaw-rate bias; ``channels``: the misfit of the mapping as given).
    """

    check: str
    status: Status
    message: str
    advice: str | None = None
    value: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (an unbounded ``value`` is None)."""
        value = None if self.value is None or not math.isfinite(self.value) else float(self.value)
        return {"check": self.check, "status": self.status, "message": self.message, "advice": self.advice,
                "value": value}


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
    """Repeated or decreasing timestamps, and jumps of more than :data:`GAP_FACTOR` median periods."""
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
            found.append(Finding(
                "time", "warn", f"{jumps.size} time jump(s) longer than {GAP_FACTOR:g}x the median period "
                f"{median:.4g} s; the longest {dt[worst]:.4g} s at t = {log.t[worst]:.6g} s "
                f"(row {worst + 2})",
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


# --- channels: swapped or sign-flipped -------------------------------------------------

def _hypotheses(robot: Robot, log: OdometryLog) -> list[tuple[str, dict[str, Any]]]:
    """(description, channel changes) for each wrong mapping a robot's log can have."""
    if isinstance(robot, DiffDrive):
        # After a swap the left wheel is read from the right channel (times "left") and the
        # right wheel from the left channel (times "right"); the words say what each given
        # channel holds.
        out = []
        for swap in (False, True):
            for sl in (1, -1):
                for sr in (1, -1):
                    if not swap:
                        flipped = [side for side, sign in (("left", sl), ("right", sr)) if sign < 0]
                        one = f"the {flipped[0] if flipped else ''} channel's sign flipped"
                        words = {0: "as given", 1: one, 2: "both channels' signs flipped"}[len(flipped)]
                    else:
                        negated = [side for side, sign in (("left", sr), ("right", sl)) if sign < 0]
                        words = "left and right swapped" + {
                            0: "", 1: f", with the {negated[0] if negated else ''} channel also negated",
                            2: ", with both channels also negated"}[len(negated)]
                    out.append((words, {"swap": swap, "left": sl, "right": sr}))
        return out
    # Any other vehicle: the sign of its distance channel and of its turn channel.
    turn = next((c for c in ("steer", "yaw_rate", "heading") if c in log.channels), None)
    what = {"steer": "steering", "yaw_rate": "yaw-rate", "heading": "heading", None: "turn"}[turn]
    dist = "traction" if isinstance(robot, Tricycle) else "distance"
    return [(d, {"distance": sd, **({turn: st} if turn else {})}) for d, sd, st in (
        ("as given", 1, 1), (f"the {what} sign flipped", 1, -1),
        (f"the {dist} sign flipped", -1, 1), ("both signs flipped", -1, -1)) if turn or st > 0]


def _remapped(log: OdometryLog, change: dict[str, Any]) -> OdometryLog:
    ch = dict(log.channels)
    if "swap" in change:
        for base in ("ticks", "dist"):
            left, right = f"{base}_left", f"{base}_right"
            if left in ch and right in ch:
                a, b = ch[left], ch[right]
                if change["swap"]:
                    a, b = b, a
                ch[left], ch[right] = change["left"] * a, change["right"] * b
    else:
        for name in ("ticks", "dist", "speed"):
            if name in ch:
                ch[name] = change["distance"] * ch[name]
        for name in ("steer", "yaw_rate", "heading"):
            if name in change and name in ch:
                ch[name] = change[name] * ch[name]
    return OdometryLog(log.t, ch, None, log.source, log.meta)


def _reversed(change: dict[str, Any]) -> dict[str, Any]:
    """The mapping that drives ``change``'s steps backwards with the same turn per step.

    A differential drive's wheels swapped and both negated; a distance sign flipped, and
    with it a steering angle's (whose turn is distance × tan δ / L), not a yaw rate's or
    heading's (whose turn does not depend on the distance).
    """
    if "swap" in change:
        return {"swap": not change["swap"], "left": -change["right"], "right": -change["left"]}
    out = dict(change, distance=-change["distance"])
    if "steer" in out:
        out["steer"] = -out["steer"]
    return out


def _motion(log: OdometryLog, robot: Robot, every: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(Δd, Δθ) over windows of ``every`` steps; for a measured heading, its change."""
    from odomkit.kinematics import body_steps

    steps = body_steps(robot, log)
    n = (len(steps) // every) * every
    dd = steps.dd[:n].reshape(-1, every).sum(axis=1)
    dth = steps.dtheta[:n].reshape(-1, every).sum(axis=1)
    return dd, dth


def _truth_motion(truth: Truth, t: NDArray[np.float64], every: int, max_gap: float | None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """A heading truth's forward travel and turn over the same windows (zero where not valid)."""
    n = ((t.size - 1) // every) * every
    times = t[: n + 1 : every]
    s = truth_at(truth, times, max_gap)
    p = s.poses
    d = np.diff(p[:, :2], axis=0)
    mid = 0.5 * (p[:-1, 2] + p[1:, 2])
    forward = d[:, 0] * np.cos(mid) + d[:, 1] * np.sin(mid)
    turn = np.diff(p[:, 2])
    ok = s.valid[:-1] & s.valid[1:]
    return np.where(ok, forward, 0.0), np.where(ok, turn, 0.0), ok


def check_channels(log: OdometryLog, robot: Robot, truth: Truth | None = None, *, spin: str | None = None,
                   max_gap: float | None = 0.5) -> list[Finding]:
    """Are the channels mapped right (left/right, signs)?

    With truth: every mapping a robot's log can get wrong (differential: swapped, either
    sign flipped; otherwise each sign) is compared with the truth, and a mapping that fits
    it clearly better (under half the misfit) than the one given is reported; the one given
    passes only if every other misfits at least 4 times as much (else a warning: the log
    cannot tell them apart). A truth with heading: each mapping dead-reckoned over
    half-second windows against the truth's travel and turn. A position-only truth (a GPS):
    each mapping's path dead-reckoned and, stretch by stretch of the fixes (a few seconds to
    tens, long enough that the fixes' noise is small against the path and that it turns),
    turned and shifted onto the fixes (Umeyama's SE(2) alignment); its misfit is the
    residual sum of squares over the fixes' spread about each stretch's centre. Such a
    truth cannot tell which way the robot drove, so each mapping and its twin driving the
    same path backwards (a car's distance and steering signs both flipped, a unicycle's
    speed sign, a differential drive's wheels swapped and both negated) count as one, named
    by the one driving forwards. With ``spin``
    ("ccw" or "cw": the log is a spin in place that way) a differential robot's wheels
    must turn opposite ways, the right one forward for ccw. With neither, only the mark a
    flipped wheel sign leaves is looked for: wheels turning opposite ways almost all the
    time.
    """
    if truth is not None:
        return _channels_against_truth(log, robot, truth, max_gap)
    if spin is not None:
        return _channels_from_spin(log, robot, spin)
    if isinstance(robot, DiffDrive):
        left, right = _wheel_travel(log, robot)
        moving = (left != 0) | (right != 0)
        if moving.sum() >= 10:
            opposite = float(np.mean(np.sign(left[moving]) * np.sign(right[moving]) < 0))
            if opposite > 0.8:
                return [Finding("channels", "warn", "the wheels turn opposite ways in "
                                f"{100 * opposite:.0f} % of moving rows: the robot spins in place almost all "
                                "the time, or one wheel's sign is flipped",
                                "give --truth, or record a spin and check it with --spin ccw")]
    return [Finding("channels", "ok", "not checked against anything: without truth (or, for a differential "
                    "drive, a spin) the channel mapping and signs cannot be told",
                    "give --truth, or record a spin in place and run odomkit check --spin ccw|cw")]


def _wheel_travel(log: OdometryLog, robot: DiffDrive) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from odomkit.kinematics import body_steps

    s = body_steps(robot, log)
    return s.inputs["d_left"], s.inputs["d_right"]


def _channels_from_spin(log: OdometryLog, robot: Robot, spin: str) -> list[Finding]:
    if spin not in ("ccw", "cw"):
        from odomkit.errors import InputError

        raise InputError(f"--spin must be ccw or cw, got {spin!r}")
    if not isinstance(robot, DiffDrive):
        return [Finding("channels", "ok", f"a spin checks a differential drive's wheels; this is a "
                        f"{robot.type_name} robot")]
    left, right = (float(np.sum(x)) for x in _wheel_travel(log, robot))
    if not (math.isfinite(left) and math.isfinite(right)):
        return [Finding("channels", "warn", f"the wheels' travel over the spin is not a number (left {left}, "
                        f"right {right}): channels not checked", "check the log's values")]
    sign = 1.0 if spin == "ccw" else -1.0  # ccw: right wheel forward, left backward
    r_ok, l_ok = sign * right > 0, sign * left < 0
    said = f"over the {spin} spin the left wheel travels {left:+.4g} m and the right {right:+.4g} m"
    if r_ok and l_ok:
        return [Finding("channels", "ok", said + ", as a " + spin + " spin should")]
    if not r_ok and not l_ok:
        return [Finding("channels", "fail", said + ": left and right look swapped (or both signs flipped, "
                        "which a spin cannot tell apart)", "swap the left and right columns; then drive "
                        "forward: if that reads backwards, flip both signs instead")]
    wrong = "left" if not l_ok else "right"
    return [Finding("channels", "fail", said + f": the {wrong} wheel's sign looks flipped",
                    f"negate the {wrong} channel")]


def _channels_against_truth(log: OdometryLog, robot: Robot, truth: Truth,
                            max_gap: float | None) -> list[Finding]:
    if not truth.has_heading:
        return _channels_against_positions(log, robot, truth, max_gap)
    dt = np.diff(log.t)
    period = float(np.median(dt[dt > 0])) if np.any(dt > 0) else 1.0
    every = max(1, int(round(0.5 / period)))
    fwd, turn, ok = _truth_motion(truth, log.t, every, max_gap)
    if ok.sum() < 4 or np.sum(np.abs(fwd[ok])) < 0.05:
        return [Finding("channels", "warn", "the truth barely moves while it overlaps the log: channels not "
                        "checked", "record motion inside the truth's coverage")]
    scores = []
    for words, change in _hypotheses(robot, log):
        dd, dth = _motion(_remapped(log, change), robot, every)
        dd, dth = dd[ok], dth[ok]
        # Each misfit relative to the motion itself, plus a floor of 5 mm and 0.01 rad a
        # window so that a log that hardly turns is not judged on the truth's jitter.
        m = int(ok.sum())
        e_d = np.sum((dd - fwd[ok]) ** 2) / (np.sum(fwd[ok] ** 2) + m * 0.005**2)
        e_t = np.sum((dth - turn[ok]) ** 2) / (np.sum(turn[ok] ** 2) + m * 0.01**2)
        scores.append((float(e_d + e_t), words, ""))
    return [_verdict(scores[0][0], scores[1:], floor=0.05, what="the truth",
                     close_why="the log turns too little to tell the mappings apart",
                     close_advice="drive turns both ways, then check again",
                     poor_advice="check the robot file (wheel size, wheel base) and the truth's clock")]


def _verdict(given: float, others: list[tuple[float, str, str]], *, floor: float, what: str, close_why: str,
             close_advice: str, poor_advice: str, detail: str = "") -> Finding:
    """The one decision rule of the channel check, for either kind of truth.

    ``given`` is the misfit of the mapping as given and ``others`` (misfit, words, note)
    those of the other mappings (0 is a perfect match, 1 as large as the motion itself;
    the note is said where that mapping is named). A mapping under half the given one's
    misfit is named (fail); else a given misfit above 0.5 is a poor match (warn); else the
    given mapping passes only when every other misfits at least 4 times as much (and at
    least 4 × ``floor``): closer than that, this log and truth cannot tell them apart
    (warn, never ok). A misfit that is not a number is a warn that says so.
    """
    if math.isnan(given) or any(math.isnan(m) for m, _, _ in others):
        return Finding("channels", "warn", f"the channel mappings' misfits against {what} could not be "
                       f"computed (not a number){detail}: channels not checked",
                       "check the log's and the truth's values")
    if not others:
        return Finding("channels", "warn", f"{what} cannot tell any other channel mapping from the one "
                       f"given (misfit {given:.3g}){detail}", close_advice, given)
    best, words, note = min(others)
    if best < 0.5 * given:
        return Finding("channels", "fail", f"the channels look mapped wrong: with {words} the odometry "
                       f"matches {what} (misfit {best:.3g}) far better than as given ({given:.3g}){detail}"
                       f"{note}", f"fix the channel mapping ({words}) and check again", given)
    if given > 0.5:
        return Finding("channels", "warn", f"the odometry matches {what} poorly (misfit {given:.3g}; 0 "
                       f"is a perfect match) and no other channel mapping does better{detail}", poor_advice,
                       given)
    if best < 4 * max(given, floor):
        return Finding("channels", "warn", f"the channels as given match {what} (misfit {given:.3g}), but "
                       f"the best other mapping, {words}, misfits only {best:.3g}{detail}: {close_why}",
                       close_advice, given)
    return Finding("channels", "ok", f"the channels as given match {what} (misfit {given:.3g}; the best "
                   f"other mapping, {words}, misfits {best:.3g}){detail}", value=given)


# --- channels against position-only truth -------------------------------------------------

# A stretch of truth that a mapping's path is aligned to holds at least this many fixes.
_MIN_FIXES = 5
# The stretch lengths tried [s], shortest first (see _stretches): the shortest whose fixes
# spread _EXTENT_PER_SIGMA times their noise σ (RMS distance about the centre, so the noise,
# 2σ² a fix, adds at most 0.02 to a misfit) and whose path turns _TURN_PER_STRETCH rad. On
# simulated cars (10 m/s, 1-5 Hz GPS, 0.5-3 m noise) and small robots (50 Hz, 1 cm) that
# picked 2-33 s, where a flipped turn sign or swapped wheels misfit 10-150 times the right
# mapping; 2 s stretches everywhere gave as little as 2 times, 32 s ones 6 (drift).
_STRETCHES = (2.0, 4.0, 8.0, 16.0, 32.0, 64.0)
_EXTENT_PER_SIGMA = 10.0
_TURN_PER_STRETCH = 1.0  # [rad]


def _runs(truth: Truth, t: NDArray[np.float64], max_gap: float | None) -> list[NDArray[np.intp]]:
    """Indices of the fixes inside the log's span, cut where truth_at would not bridge a gap."""
    inside = np.flatnonzero((truth.t >= t[0]) & (truth.t <= t[-1]))
    if inside.size < 2:
        return []
    bridged = truth_at(truth, 0.5 * (truth.t[inside[:-1]] + truth.t[inside[1:]]), max_gap).valid
    return [run for run in np.split(inside, np.flatnonzero(~bridged) + 1) if run.size >= _MIN_FIXES]


def _stretches(truth: Truth, runs: list[NDArray[np.intp]], sigma: float, heading: NDArray[np.float64]
               ) -> tuple[list[NDArray[np.intp]], float]:
    """The fixes cut into stretches of one length, and that length [s].

    Short stretches keep the odometry's own drift (a wrong wheel base, a steering offset)
    small. Long ones make the truth's noise small against the path, and turn more, which
    is what tells a turn sign: a path and its mirror image differ only where it bends. Of
    :data:`_STRETCHES`, the shortest is taken whose stretches (by their median) have fixes
    spread :data:`_EXTENT_PER_SIGMA` σ RMS about their centre and turn :data:`_TURN_PER_STRETCH`
    (the odometry's ``heading`` at the fixes, summed absolute changes); failing the turn, the
    shortest that spreads; failing both, the longest.
    """
    spreads, turns = [], []
    tried: list[list[NDArray[np.intp]]] = []
    for length in _STRETCHES:
        chosen = []
        for run in runs:
            span = truth.t[run[-1]] - truth.t[run[0]]
            pieces = max(1, min(int(round(span / length)), run.size // _MIN_FIXES))
            cut = np.minimum(((truth.t[run] - truth.t[run[0]]) / span * pieces).astype(int), pieces - 1)
            chosen += [run[cut == k] for k in range(pieces) if np.count_nonzero(cut == k) >= _MIN_FIXES]
        tried.append(chosen)
        extent = [math.sqrt(_spread(truth.xy[s]) / s.size) for s in chosen]
        spreads.append(bool(extent) and float(np.median(extent)) >= _EXTENT_PER_SIGMA * sigma)
        turns.append(bool(chosen) and float(np.median([np.sum(np.abs(np.diff(heading[s]))) for s in chosen]))
                     >= _TURN_PER_STRETCH)
    k = next((k for k, ok in enumerate(zip(spreads, turns, strict=True)) if all(ok)),
             next((k for k, ok in enumerate(spreads) if ok), len(_STRETCHES) - 1))
    durations = [truth.t[s[-1]] - truth.t[s[0]] for s in tried[k]]
    return tried[k], float(np.median(durations)) if durations else 0.0


def _aligned_rss(source: NDArray[np.float64], target: NDArray[np.float64]) -> float:
    """Σ |target − (R source + c)|² [m²] after the best rotation and shift
    (:func:`odomkit.evaluate.align_track`, Umeyama's SE(2) alignment)."""
    from odomkit.errors import ModelError
    from odomkit.evaluate import align_track

    n = source.shape[0]
    if not np.all(np.isfinite(source)):
        return math.inf  # a path that overflowed fits nothing (and would stop the SVD)
    try:
        moved, _ = align_track(np.column_stack((source, np.zeros(n))),
                               np.column_stack((target, np.full(n, np.nan))), "se2")
    except ModelError:
        # One of the two does not spread (or they are perpendicular in every pair): no
        # rotation helps, the centres meet and each keeps its own spread.
        return _spread(source) + _spread(target)
    return float(np.sum((moved[:, :2] - target) ** 2))


def _spread(points: NDArray[np.float64]) -> float:
    return float(np.sum((points - points.mean(axis=0)) ** 2))


def _channels_against_positions(log: OdometryLog, robot: Robot, truth: Truth,
                                max_gap: float | None) -> list[Finding]:
    """The channel check against position-only truth: each mapping's dead-reckoned path,
    stretch by stretch, turned and shifted onto the fixes (the truth has no heading to
    compare turns with, and the direction of travel between noisy fixes is mostly noise)."""
    from odomkit.track import dead_reckon_log

    runs = _runs(truth, log.t, max_gap)
    if not runs:
        return [Finding("channels", "warn", f"the truth has no {_MIN_FIXES} fixes in a row (without a gap) "
                        "inside the log's time span: channels not checked",
                        "record truth that covers the log, or check --max-gap and the truth's clock")]
    hypotheses = _hypotheses(robot, log)
    words = [w for w, _ in hypotheses]
    at_fixes, forward = [], []
    for _, change in hypotheses:
        track = dead_reckon_log(_remapped(log, change), robot, pose0=np.zeros(3))
        at_fixes.append(np.column_stack([np.interp(truth.t, log.t, track.poses[:, k]) for k in range(3)]))
        travel = float(np.sum(np.abs(track.steps.dd)))
        forward.append(float(np.sum(track.steps.dd)) / travel if travel > 0 else 0.0)
    # The fixes' own noise (odomkit.truth.scatter_sigma), no less than the stated σ.
    noise = max(truth.sigma, scatter_sigma(truth) or 0.0)
    stretches, length = _stretches(truth, runs, noise, at_fixes[0][:, 2])
    fixes = [truth.xy[s] for s in stretches]
    spread = sum(_spread(x) for x in fixes)
    if spread == 0.0:  # no stretch, or fixes all in one place
        return [Finding("channels", "warn", "the truth does not move while it overlaps the log: channels not "
                        "checked", "record motion inside the truth's coverage")]
    misfit = [sum(_aligned_rss(path[s, :2], x) for s, x in zip(stretches, fixes, strict=True)) / spread
              for path in at_fixes]
    # A position-only truth cannot tell which way the robot drove: each mapping's twin that
    # drives the same steps backwards, turning alike, draws the same path turned by π. Of
    # each pair the one driving forwards (net) stands for both.
    twin = [next(k for k, (_, c) in enumerate(hypotheses) if c == _reversed(change))
            for _, change in hypotheses]
    named = sorted({max((h, twin[h]), key=lambda i: (forward[i], -i))
                    for h in range(len(hypotheses)) if h not in (0, twin[0])})
    others = [(misfit[h], words[h], f"; a position-only truth cannot tell {words[h]} from {words[twin[h]]}"
               if twin[h] != h else "") for h in named]
    # The residual RMS per axis of the best mapping: RSS over 2n − 3 degrees of freedom a stretch.
    best, n = min(misfit), sum(x.shape[0] for x in fixes)
    leaves = (f"the best leaves {math.sqrt(best * spread / (2 * n - 3 * len(fixes))):.3g} m RMS per axis, "
              if math.isfinite(best) else "")
    detail = (f" (each mapping's path turned and shifted onto {len(fixes)} stretch(es) of about {length:.2g} "
              f"s of fixes: {leaves}the fixes spread {math.sqrt(spread / n):.3g} m RMS)")
    found = _verdict(misfit[0], others, floor=0.0, what="the truth's positions", detail=detail,
                     close_why="the log turns too little, or the truth is too short or too noisy, to "
                     "tell the mappings apart",
                     close_advice="drive turns both ways inside the truth's coverage (or give a truth with "
                     "heading), then check again",
                     poor_advice="check the robot file and the truth's clock; a truth whose noise is as "
                     "large as the path it covers cannot check the channels")
    if found.status == "ok" and twin[0] != 0 and forward[0] < 0 < forward[twin[0]]:
        other = words[twin[0]]
        return [Finding("channels", "warn", found.message + f"; but as given the odometry drives backwards "
                        f"({-100 * forward[0]:.0f} % of its travel, net), and with {other} it would match as "
                        "well driving forwards: a position-only truth cannot tell the two apart",
                        f"if the robot drove forwards, fix the channel mapping ({other})", found.value)]
    return [found]


# --- motion and identifiability ----------------------------------------------------------

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
        found.append(Finding("turning", "warn", f"{turns}: almost all one way",
                             f"also drive at least a half turn {way}: turning one way lets a wheel-size "
                             "ratio and a wheel-base error mimic each other at the run's end, so an endpoint "
                             "fit (UMBmark, --from endpoints) needs both ways; a fit to the whole trajectory "
                             "copes if 'identifiable' says so"))
    else:
        found.append(Finding("turning", "ok", turns))
    return found


@dataclass(frozen=True)
class _Parameter:
    """How one calibration parameter's standard error is shown and judged.

    ``kind``: ``ratio`` a dimensionless correction near 1 (its standard error, shown in %),
    ``relative`` a length (its standard error over its value, in %), ``angle`` [rad],
    ``rate`` [rad/s]; ``_LIMITS`` gives each kind's thresholds.
    """

    label: str
    kind: Literal["ratio", "relative", "angle", "rate"]
    advice: str


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
             _Parameter("wheel base E_b", "ratio", "turn more: spins in place or a square driven both ways")),
    "tricycle": (_Parameter("traction scale c_scale", "ratio",
                            "drive longer straight runs away from the start"),
                 _Parameter("steering offset", "angle", "drive straight and gentle curves both ways"),
                 _Parameter("wheel-to-axle distance", "relative", "drive tight curves both ways")),
    "car": (_Parameter("wheel scale c_scale", "ratio", _SCALE_ADVICE),
            _Parameter("steering offset", "angle", "drive straight and gentle curves both ways"),
            _Parameter("wheel base L", "relative", "drive tight curves both ways")),
    "unicycle": (_Parameter("speed scale c_scale", "ratio", _SCALE_ADVICE),
                 _Parameter("yaw-rate bias", "rate", _BIAS_ADVICE),
                 _Parameter("yaw-rate scale", "ratio", _YAW_SCALE_ADVICE)),
    "gyro": (_Parameter("metres per tick m_per_tick", "relative", _SCALE_ADVICE),
             _Parameter("gyro bias", "rate", _BIAS_ADVICE),
             _Parameter("gyro scale", "ratio", _YAW_SCALE_ADVICE)),
}


def _design(log: OdometryLog, robot: CalibratedRobot
            ) -> tuple[NDArray[np.float64], list[tuple[_Parameter, float]], dict[str, str]]:
    """The sensitivity of the positions to the calibration parameters, (2n, P).

    The calibration model's own Jacobian (:func:`odomkit.calibrate.residuals.calibration_model`,
    the one :func:`~odomkit.calibrate.exact.calibrate_exact` fits with) at the robot's
    values, integrated from a known start pose; x and y (as the default calibration fits) of
    rows k, 2k, ... with k rows about 1 s, interleaved. A differential drive's columns of
    (c_left, c_right) become E_s (both wheels) and E_d (right against left). Returned with
    the parameters the columns stand for, each with the value its standard error is
    relative to (a length's own value, else 1), and {label: why} of the parameters the
    log's channels do not use (left out: the calibration holds them).
    """
    from odomkit.calibrate.residuals import (
        DiffCalibrationModel,
        calibration_model,
        integrate_with_sensitivity,
    )

    model = calibration_model(robot, [log])
    dd, dth, ddd, ddt = model.steps(model.p0, 0)
    _, dposes = integrate_with_sensitivity(dd, dth, ddd, ddt, np.zeros(3))
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
    return np.ascontiguousarray(J[..., keep]).reshape(-1, len(keep)), per, unused


def _identifiability_sigma(truth: Truth | None) -> float | None:
    """The position noise the identifiability figures assume: the truth's stated σ, else the
    larger of the default and the fixes' own scatter (a 1 m GPS must not be taken for 5 mm),
    else None (the default)."""
    if truth is None:
        return None
    if truth.sigma > 0:
        return truth.sigma
    return max(_DEFAULT_SIGMA, scatter_sigma(truth) or 0.0)


def check_identifiable(log: OdometryLog, robot: Robot, sigma: float | None = None) -> list[Finding]:
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
    odometry's drift is, make the true scatter larger: the figure is a lower bound.

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
    """
    from odomkit.calibrate.residuals import CALIBRATED_ROBOTS

    if not isinstance(robot, CALIBRATED_ROBOTS):
        return [Finding("identifiable", "ok", f"a {robot.type_name} robot's calibration is not checked here: "
                        "odomkit calibrate does not calibrate it")]
    sigma = _DEFAULT_SIGMA if not sigma else float(sigma)
    A, params, unused = _design(log, robot)
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
    norms = np.linalg.norm(A, axis=0)
    for i, (par, value) in enumerate(params):
        others = np.delete(A, i, axis=1)
        coef, *_ = np.linalg.lstsq(others, A[:, i], rcond=None)
        unique = float(np.linalg.norm(A[:, i] - others @ coef))
        se = math.inf if unique == 0 else sigma / unique / value
        unit, weak, unidentified = _LIMITS[par.kind]
        shown = f"±{100 * se:.2g} %" if unit == "%" else f"±{se:.2g} {unit}"
        shown = "unbounded" if not math.isfinite(se) else shown
        if math.isnan(se):
            found.append(Finding("identifiable", "warn", f"{par.label}: its standard error could not be "
                                 "computed (not a number): not checked", "check the log's values"))
            continue
        ratio = unique / norms[i] if norms[i] > 0 else 0.0
        why = (" (its effect on the track is almost all one that the other parameters can mimic)"
               if ratio < 0.1 and norms[i] > 0 else "")
        if se > unidentified:
            found.append(Finding("identifiable", "fail", f"{par.label}: not identifiable from this log "
                                 f"(standard error {shown} with {1000 * sigma:g} mm position noise){why}",
                                 par.advice, se))
        elif se > weak:
            found.append(Finding("identifiable", "warn", f"{par.label}: weakly identified (standard error "
                                 f"{shown}){why}", par.advice, se))
        else:
            found.append(Finding("identifiable", "ok", f"{par.label}: identified (standard error {shown})",
                                 value=se))
    return found


def check_log(log: OdometryLog, robot: Robot, truth: Truth | None = None, *, spin: str | None = None,
              max_gap: float | None = 0.5) -> list[Finding]:
    """Every check, in the order a user fixes things: values and time, counters, stuck
    channels, the channel mapping, then what the motion can identify."""
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
    found += check_motion(log, robot)
    found += check_identifiable(log, robot, _identifiability_sigma(truth))
    return found


def next_steps(findings: list[Finding]) -> list[str]:
    """The advice of every finding that is not ok, failures first, without repeats."""
    ordered = sorted((f for f in findings if f.status != "ok" and f.advice),
                     key=lambda f: 0 if f.status == "fail" else 1)
    return list(dict.fromkeys(f.advice for f in ordered if f.advice))
