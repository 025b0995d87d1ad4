"""The truth's own heading against its own motion (part of ``odomkit check``).

A motion capture's rigid body is defined by its markers, seldom along the robot's axis: its
heading is then off the robot's by a constant. While the robot drives straight its
reference point moves along its axis (a wheel rolls where it points), so the direction in
which the truth's positions move is the robot's heading, and the truth's heading should
agree with it. A constant difference δ is the body's misalignment (or a crab angle). It
matters wherever the odometry is restarted from the truth's heading: every window of
``fit-noise`` and ``evaluate --window``, and a whole run aligned at its start. Each then
drives δ off the true direction and drifts δ metres across its track per metre;
``fit-noise`` takes that as the truth's heading noise (its ``truth_heading_sigma`` holds at
least δ), and :mod:`odomkit.calibrate` bends its parameters towards it.

Measured on OptiOdom (docs/results/honesty.md): the tricycle's body is 19 mrad off, the
differential robot's 6–9 mrad.

:func:`check_truth_interpolated` says when the truth is no measurement at all but a
reference interpolated between sparse keyframes (:mod:`odomkit.truth_knots`).
"""

from __future__ import annotations

import math

import numpy as np

from odomkit.calibrate.check_finding import Finding
from odomkit.log import OdometryLog
from odomkit.robot import Robot
from odomkit.truth import HEADING_OFF_CAUSES, Truth, heading_off_motion, truth_at
from odomkit.truth_knots import INTERPOLATED_ADVICE, truth_knots

__all__ = ["check_truth_heading", "check_truth_interpolated", "heading_misalignment"]

#: Half-width [s] of the stretch over which the truth's direction of motion is taken.
HALF_SPAN = 0.5
#: A stretch counts as straight where the odometry turns less than :data:`STRAIGHT_TURN`
#: plus :data:`STRAIGHT` per metre (a circle of 50 m radius; the turn allowance covers an
#: encoder's quantisation, whose turn signs scatter both ways and leave the median), and it
#: must move at least :data:`MIN_TRAVEL` [m] (a slow base moves a few centimetres a second).
STRAIGHT = 0.02
STRAIGHT_TURN = 0.005
MIN_TRAVEL = 0.02
#: Fewer straight stretches than this tell nothing.
MIN_STRETCHES = 10
#: A misalignment below this (5 mm across the track per metre) is not worth a warning.
MATERIAL = 0.005


def heading_misalignment(log: OdometryLog, robot: Robot, truth: Truth,
                         max_gap: float | None = 0.5) -> tuple[float, float, int]:
    """The truth's heading minus its direction of motion while the odometry drives straight.

    Parameters
    ----------
    log : the odometry log; its travel and turn (``robot``'s body steps) pick the straight
        stretches and which way the robot drives in them
    robot : the robot the log is read with
    truth : Truth with heading
    max_gap : stretches reaching into a truth gap longer than this are left out [s]

    Returns
    -------
    (δ, standard error, stretches) : δ [rad], the median over non-overlapping stretches of
        2·:data:`HALF_SPAN` seconds, with its standard error (1.2533 σ/√n, a median's for
        normal scatter); NaN and NaN when fewer than :data:`MIN_STRETCHES` are straight.
    """
    from odomkit.kinematics import body_steps

    if truth.theta is None:
        raise ValueError("heading_misalignment needs a truth with heading")
    t = np.asarray(log.t, dtype=float)
    centres = np.arange(max(t[0], truth.t[0]) + HALF_SPAN, min(t[-1], truth.t[-1]) - HALF_SPAN, 2 * HALF_SPAN)
    if centres.size == 0:
        return math.nan, math.nan, 0
    before = truth_at(truth, centres - HALF_SPAN, max_gap)
    after = truth_at(truth, centres + HALF_SPAN, max_gap)
    steps = body_steps(robot, log)
    travelled = np.concatenate([[0.0], np.cumsum(steps.dd)])  # signed: backwards is negative
    turned = np.concatenate([[0.0], np.cumsum(steps.dtheta)])
    travel = np.interp(centres + HALF_SPAN, t, travelled) - np.interp(centres - HALF_SPAN, t, travelled)
    turn = np.interp(centres + HALF_SPAN, t, turned) - np.interp(centres - HALF_SPAN, t, turned)
    moved = after.poses[:, :2] - before.poses[:, :2]
    straight = (before.valid & after.valid & (np.abs(travel) >= MIN_TRAVEL)
                & (np.abs(turn) <= STRAIGHT_TURN + STRAIGHT * np.abs(travel))
                & (np.linalg.norm(moved, axis=1) >= MIN_TRAVEL))
    if np.count_nonzero(straight) < MIN_STRETCHES:
        return math.nan, math.nan, int(np.count_nonzero(straight))
    backwards = np.where(travel[straight] < 0, math.pi, 0.0)
    direction = np.arctan2(moved[straight, 1], moved[straight, 0]) + backwards
    heading = 0.5 * (before.poses[straight, 2] + after.poses[straight, 2])
    off = np.angle(np.exp(1j * (heading - direction)))
    n = off.size
    return float(np.median(off)), float(1.2533 * np.std(off, ddof=1) / math.sqrt(n)), n


def check_truth_heading(log: OdometryLog, robot: Robot, truth: Truth | None,
                        max_gap: float | None = 0.5) -> list[Finding]:
    """The ``truth_heading`` finding (none for a position-only truth or none at all)."""
    if truth is None or truth.theta is None:
        return []
    if note := heading_off_motion(truth, max_gap):  # no robot heading at all: nothing finer to tell
        return [Finding("truth_heading", "fail", note + ": every window or start taken from it starts off "
                        "the robot's heading", f"check the truth's heading: likely {HEADING_OFF_CAUSES}")]
    delta, se, n = heading_misalignment(log, robot, truth, max_gap)
    if not math.isfinite(delta):
        return [Finding("truth_heading", "ok", f"only {n} straight stretch(es) of {2 * HALF_SPAN:g} s: too "
                        "little straight driving to compare the truth's heading with its motion")]
    said = (f"the truth's heading is {1000 * delta:+.1f} ± {1000 * se:.1f} mrad "
            f"({math.degrees(delta):+.2f}°) "
            f"off the direction its positions move in while the odometry drives straight ({n} stretches "
            f"of {2 * HALF_SPAN:g} s)")
    if abs(delta) > max(MATERIAL, 3 * se):
        return [Finding(
            "truth_heading", "warn",
            said + f": a rigid body not aligned with the robot's axis (or a crab angle). Restarted from the "
            "truth's heading (windows, a run aligned at its start) the odometry drifts "
            f"{1000 * abs(delta):.0f} mm across its track per metre",
            "align the motion capture's rigid body with the robot's axis, or know that fit-noise's "
            f"truth_heading_sigma will hold at least {abs(delta):.3g} rad of it", delta)]
    return [Finding("truth_heading", "ok", said, value=delta)]


def check_truth_interpolated(truth: Truth | None) -> list[Finding]:
    """The ``truth_interpolated`` finding: a warning where the truth's fixes lie on straight
    lines between sparse knots (:func:`odomkit.truth_knots.truth_knots`; its ``value`` the
    share of the moving fixes on them), none otherwise (a measured truth, or none)."""
    if truth is None:
        return []
    knots = truth_knots(truth)
    if not knots.interpolated:
        return []
    return [Finding("truth_interpolated", "warn", knots.describe(), INTERPOLATED_ADVICE, knots.share)]
