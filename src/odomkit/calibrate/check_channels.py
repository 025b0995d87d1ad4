"""The channel-mapping check before calibrating (part of ``odomkit check``): are left and
right swapped, a speed and a yaw rate swapped, or a sign flipped?

:func:`check_channels` compares every mapping a robot's log can get wrong with the truth
(a truth with heading: each mapping's travel and turn over half-second windows; a
position-only truth: each mapping's path turned and shifted onto the fixes, stretch by
stretch), or checks a spin in a known direction, or, with neither, looks for the mark a
flipped wheel sign leaves. Everything else here (the mappings, their motion, the one
decision rule) serves it alone; :func:`odomkit.calibrate.check.check_log` runs it with the
other checks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.check_finding import Finding
from odomkit.calibrate.check_ratios import judging_noise
from odomkit.log import WHEEL_PAIRS, OdometryLog
from odomkit.robot import DiffDrive, Robot, Tricycle
from odomkit.truth import Truth, no_overlap, truth_at

__all__ = ["check_channels"]


# --- channels: swapped or sign-flipped -------------------------------------------------

#: The mappings that flip the turn channel alone, which a truth with x and y swapped mimics.
_TURN_FLIPS = frozenset(f"the {what} sign flipped" for what in ("steering", "yaw-rate", "heading", "turn"))
#: The mappings that drive the odometry backwards: against a truth with a heading, a truth
#: whose heading points backwards (π off) reads alike (a lawn mower's RTK truth, its heading
#: offset by π, was told "the distance sign flipped": user study).
_BACKWARDS = frozenset(("the distance sign flipped", "the traction sign flipped",
                        "both channels' signs flipped"))

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
    out = [(d, {"distance": sd, **({turn: st} if turn else {})}) for d, sd, st in (
        ("as given", 1, 1), (f"the {what} sign flipped", 1, -1),
        (f"the {dist} sign flipped", -1, 1), ("both signs flipped", -1, -1)) if turn or st > 0]
    if {"speed", "yaw_rate"} <= set(log.channels):
        # A speed and a yaw rate are both rates, one column apart in most logs (MRCLAM's
        # "t v ω" read as t,yaw_rate,speed): swapped, each possibly with its sign flipped.
        # "swap_rate" reads the speed from the column given as the yaw rate and back; the
        # signs then apply to the channels as swapped.
        for sd, st in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            flipped = [name for name, sign in (("speed", sd), ("yaw rate", st)) if sign < 0]
            words = "speed and yaw rate swapped" + (
                f", with the {' and the '.join(flipped)} also negated" if flipped else "")
            out.append((words, {"swap_rate": True, "distance": sd, "yaw_rate": st}))
    return out


def _remapped(log: OdometryLog, change: dict[str, Any]) -> OdometryLog:
    ch = dict(log.channels)
    if "swap" in change:
        for left, right in WHEEL_PAIRS:
            if left in ch and right in ch:
                a, b = ch[left], ch[right]
                if change["swap"]:
                    a, b = b, a
                ch[left], ch[right] = change["left"] * a, change["right"] * b
    else:
        if change.get("swap_rate"):
            ch["speed"], ch["yaw_rate"] = ch["yaw_rate"], ch["speed"]
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
    heading's (whose turn does not depend on the distance); a speed and yaw rate swapped
    stay swapped.
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
    sign flipped; otherwise each sign, and, for a log with a speed and a yaw rate (a
    unicycle, a gyro), the two swapped with either sign) is compared with the truth, and a mapping that fits
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
    if truth.t[0] > log.t[-1] or truth.t[-1] < log.t[0]:
        # A log in ms against a truth in s: the message names the flag that reads the one off.
        # A failure: nothing of the truth can be checked, as every other command refuses it.
        said = no_overlap(truth, log.t, log.meta.get("time"))
        return [Finding("channels", "fail", f"{said}: channels not checked",
                        "read both clocks in seconds (the time unit named), or shift the truth's "
                        "(--truth-time-offset)")]
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
    # Named only where that mapping itself matches: a log read wrong (a cumulative counter
    # read as increments, a robot 250x too fast) misfits every mapping, and the least absurd
    # of them is no fix (a user study's LEGO robot was told "the right channel's sign
    # flipped" at a best misfit of 0.975, against 9.15e+03 as given).
    if best < 0.5 * given and best <= 0.5:
        advice = f"fix the channel mapping ({words}) and check again"
        if words in _TURN_FLIPS:
            # A mirrored truth turns the other way, as a flipped turn channel does (a KITTI
            # drive's lat and lon given swapped was told "the yaw-rate sign flipped": user study).
            advice += ("; if that channel's sign is right, the truth is mirrored: its x and y (lat and lon) "
                       "swapped")
        elif words in _BACKWARDS and what == "the truth":
            advice += ("; if the distance's sign is right, the truth's heading points backwards (π off: a "
                       "motion-capture body's axis reversed, a heading offset by π)")
        return Finding("channels", "fail", f"the channels look mapped wrong: with {words} the odometry "
                       f"matches {what} (misfit {best:.3g}) far better than as given ({given:.3g}){detail}"
                       f"{note}", advice, given)
    if given > 0.5:
        others_said = ("no other channel mapping does better" if best >= given else
                       f"no other channel mapping matches it either (the best, {words}, misfits {best:.3g})")
        return Finding("channels", "warn", f"the odometry matches {what} poorly (misfit {given:.3g}; 0 "
                       f"is a perfect match) and {others_said}{detail}", poor_advice, given)
    if best < 4 * max(given, floor):
        return Finding("channels", "warn", f"the channels as given match {what} (misfit {given:.3g}), but "
                       f"the best other mapping, {words}, misfits {best:.3g}, "
                       f"{best / given if given > 0 else math.inf:.2g}x as much, under the 4x that tells "
                       f"them apart{detail}: {close_why}", close_advice, given)
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
    # The fixes' own noise, no less than the σ given, or the σ they state (a GPS's scatter
    # misses its error correlated in time), as the ratio check takes it.
    noise = judging_noise(truth)[0]
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
    rms = math.sqrt(best * spread / (2 * n - 3 * len(fixes))) if math.isfinite(best) else math.nan
    leaves = f"the best leaves {rms:.3g} m RMS per axis, " if math.isfinite(rms) else ""
    detail = (f" (each mapping's path turned and shifted onto {len(fixes)} stretch(es) of about {length:.2g} "
              f"s of fixes: {leaves}the fixes spread {math.sqrt(spread / n):.3g} m RMS)")
    # Why two mappings tie, from what was measured (UWB user study: "the log turns too
    # little" of a robot that turned 52 rad, whose robot file halved its wheel base).
    turned = sum(float(np.sum(np.abs(np.diff(at_fixes[0][s, 2])))) for s in stretches)
    if math.isfinite(rms) and rms > 3.0 * noise and turned > math.pi:
        close_why = (f"the log turns {turned:.3g} rad over those stretches, but the best mapping leaves "
                     f"{rms / max(noise, 1e-12):.3g}x the truth's noise ({1000 * noise:.3g} mm): the "
                     "odometry's drift, a robot-file error (wheel base, wheel size) or a clock offset "
                     "misfits every mapping alike")
    else:
        close_why = (f"the log turns {turned:.3g} rad over those stretches: too little, or the truth too "
                     "short or too noisy, to tell the mappings apart")
    found = _verdict(misfit[0], others, floor=0.0, what="the truth's positions", detail=detail,
                     close_why=close_why,
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
