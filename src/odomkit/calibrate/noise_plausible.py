"""Fitted noise values no real robot or truth has (part of ``odomkit fit-noise``'s warnings).

A maximum-likelihood fit puts error its model does not explain wherever a variance can hold
it: an uncalibrated speed scale into a sample-period jitter, a wrong steering zero into a
run-to-run bias, a truth's clock offset into its time noise. The values then are far beyond
anything physical, and ``evaluate`` scores a covariance tens of times too big. These limits
are physical, not statistical: each constant says why.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from odomkit.robot import Robot
from odomkit.windows import Window

__all__ = ["implausible_truth_clock", "implausible_values", "PLAUSIBLE_BIAS", "PLAUSIBLE_CLOCK_FLOOR",
           "PLAUSIBLE_JITTER", "PLAUSIBLE_TRUTH_CLOCK"]

#: A fitted bias (a parameter drawn once per run) above these is implausible, by field:
#: (limit, unit, why one vehicle's parameter does not change so much between runs); unit ""
#: is relative (a scale, shown in %), and the wheel base's limit is relative to the robot's
#: own (:func:`_wheel_base`). A wheel or speed scale moves by a few % with tyre pressure,
#: load and wear (a car's rolling radius by about 1-3 %), a gyro's scale factor by a few %
#: with temperature: 10 % is well beyond both. A steering zero or a gyro offset that moved
#: by 0.1 rad (5.7°) or 0.1 rad/s (a full turn a minute) between runs would be seen at once
#: driving straight; both are calibrated (odomkit calibrate) or estimated at rest far closer.
#: Beyond these the fit is putting an uncalibrated parameter, or error no model describes,
#: into the bias.
PLAUSIBLE_BIAS: dict[str, tuple[float, str, str]] = {
    "sigma_scale_left": (0.1, "", "a vehicle's wheel or speed scale changes by a few % between runs (tyre "
                         "pressure, load, wear)"),
    "sigma_scale_right": (0.1, "", "a vehicle's wheel scale changes by a few % between runs (tyre pressure, "
                          "load, wear)"),
    "sigma_yaw_rate_scale": (0.1, "", "a gyro's scale factor changes by a few % between runs (temperature)"),
    "sigma_wheel_base": (0.1, "m", "a vehicle's (effective) wheel base changes by a few % between runs"),
    "sigma_steering_offset": (0.1, "rad", "a steering whose zero moved that much between runs would drive a "
                              "circle of {radius:.3g} m radius with its wheel straight"),
    "sigma_yaw_rate_offset": (0.1, "rad/s", "a gyro whose offset moved that much between runs would turn a "
                              "robot driving straight a full circle a minute; an offset is estimated at rest "
                              "far closer"),
}
#: The fitted sample-period jitter (``sigma_dt``) is implausible above this share of the logs'
#: mean sample period T: periods T + e, e ~ N(0, σ²), would be negative in Φ(−T/σ) of the
#: samples, over 2 % beyond σ = T/2 (Φ(−2) = 0.023), while a log's stamps only increase. The
#: fit knows the logs through their windows only, so T is each window's duration over its
#: steps, the median over the windows (a gap in one window does not move it); on a log of
#: mixed steps (the BMW's CAN log: a quarter of its steps under 25 ms, half 86-100 ms) it is below the
#: median step (74 ms against 86 ms), which makes the limit stricter, not looser.
PLAUSIBLE_JITTER = 0.5
#: The fitted ``truth_time_sigma`` is implausible above this share of the shortest window: a
#: fix that far off the log's clock moves a window's end by about that share of the window's
#: travel, more than calibrated odometry drifts over it (a few %), and no truth is stamped so
#: badly (GPS, motion capture: milliseconds to tens of milliseconds). The fit is then putting
#: along-track error there that the model does not explain.
PLAUSIBLE_TRUTH_CLOCK = 0.1
#: The fitted ``truth_time_sigma`` is implausible for a clock above the larger of the truth's
#: median fix spacing and this [s] (:func:`implausible_truth_clock`): fixes whose stamps were
#: off independently by a σ as large as their spacing Δ would come out of order in
#: Φ(−Δ/(σ√2)) ≥ 24 % of consecutive pairs, while a truth's stamps only increase; the floor
#: leaves room for a dense truth stamped on receipt (a bag's --bag-time: tens of ms of jitter
#: against a motion capture's 10 ms spacing).
PLAUSIBLE_CLOCK_FLOOR = 0.5
_CALIBRATE = "calibrate the robot first (odomkit calibrate)"


def _wheel_base(robot: Robot) -> float | None:
    """The length ``sigma_wheel_base`` varies [m]: a differential drive's effective wheel
    base, a car's wheel base, a tricycle's wheel-to-axle distance; None for other robots."""
    for name in ("effective_wheel_base", "wheel_base", "wheel_to_axle"):
        value = getattr(robot, name, None)
        if isinstance(value, int | float) and value > 0:
            return float(value)
    return None


def implausible_truth_clock(value: float, spacing: float | None) -> str | None:
    """A warning where a fitted ``truth_time_sigma`` [s] exceeds the larger of the truth's
    median fix ``spacing`` [s] and :data:`PLAUSIBLE_CLOCK_FLOOR`, else None.

    No clock stamps its fixes so badly; the fit has put something else there that grows with
    the speed along the track: the truth's error correlated in time (a GPS's wander, which
    moves a window's two ends alike only when they are close), a clock offset, or noise the
    robot's model lacks. A user study's 2.5 Hz GPS (0.4 s apart) fitted 1.5–1.95 s, under
    :data:`PLAUSIBLE_TRUTH_CLOCK` of its 30 s windows, and nothing was said.

    Examples
    --------
    >>> implausible_truth_clock(0.02, 0.01) is None
    True
    >>> implausible_truth_clock(1.95, 0.4).split(" (")[0]
    'truth_time_sigma = 1.95 s is implausible for a clock'
    """
    if not math.isfinite(value):
        return None
    limit = max(spacing or 0.0, PLAUSIBLE_CLOCK_FLOOR)
    if value <= limit:
        return None
    floor = f"{PLAUSIBLE_CLOCK_FLOOR:g} s"
    basis = (f"the larger of the truth's median fix spacing, {spacing:.3g} s, and {floor}" if spacing
             else floor)
    return (f"truth_time_sigma = {value:.3g} s is implausible for a clock (limit {limit:.3g} s: "
            f"{basis}): fixes stamped that far off one by one would come out of order, and no receiver or "
            "motion capture stamps so badly; it likely absorbs something else that grows with the speed "
            "along the track: the truth's error correlated in time (a GPS's slow wander), a clock offset "
            "(odomkit calibrate --truth fits it; --truth-time-offset gives it), or noise the robot's model "
            "lacks; give the truth's time noise (--truth-time-sigma, 0 for well-stamped fixes) and fit again")


def implausible_values(fitted: Sequence[tuple[str, str, str, float]], robot: Robot,
                       windows: Sequence[Window]) -> list[str]:
    """Warnings for fitted values no real robot or truth has (BMW user study: sigma_dt 0.498 s
    on a log sampled every 0.086 s, a 42 % run-to-run speed scale, a truth 7.7 s off its
    stamps; ``evaluate`` then scored a covariance 50 times too big), each naming the
    parameter, its value and unit, the limit and why, and what to do.

    Parameters
    ----------
    fitted : (key, field name, kind, value) of each parameter the data fitted (not held, nor
        kept at the robot file's value for want of information: a value the user gives is
        theirs); value in the model's unit (σ, or a variance where the model holds one)
    robot : the robot fitted (its wheel base sets ``sigma_wheel_base``'s limit)
    windows : the windows fitted; the logs' mean sample period is the median over them of
        each one's mean step, and the shortest is the shortest duration
        (:data:`PLAUSIBLE_JITTER`, :data:`PLAUSIBLE_TRUTH_CLOCK`, :data:`PLAUSIBLE_BIAS`)

    Returns
    -------
    list of str, one warning per implausible value
    """
    windows = [w for w in windows if w.end > w.start and w.duration > 0]
    out = []
    for key, name, kind, value in fitted:
        if name == "sigma_dt" and windows:
            period = float(np.median([w.duration / (w.end - w.start) for w in windows]))
            limit = PLAUSIBLE_JITTER * period
            if value > limit:
                out.append(
                    f"{key} = {value:.3g} s is implausible (limit {limit:.3g} s: half the logs' mean "
                    f"sample period, {period:.3g} s): periods that jittered so would be negative in over 2 % "
                    "of the samples; it is error the model does not explain (a speed scale: at a given speed "
                    "a period error moves the robot as a speed error does), put into the jitter; "
                    f"{_CALIBRATE}, then fit again holding it (odomkit fit-noise --fix {key})")
        elif name == "truth_time_sigma" and windows:
            shortest = min(w.duration for w in windows)
            limit = PLAUSIBLE_TRUTH_CLOCK * shortest
            if value > limit:
                out.append(
                    f"{key} = {value:.3g} s is implausible (limit {limit:.3g} s: a tenth of the shortest "
                    f"window, {shortest:.3g} s): fixes stamped that far off would move each window's end by "
                    "over a tenth of its travel, more than odometry drifts, and no truth is stamped so "
                    "badly; it is along-track error the model does not explain (a speed scale, the truth's "
                    "clock offset), put into the truth; calibrate the robot first (odomkit calibrate, which "
                    "fits the truth's clock offset too), or give the truth's time noise (--truth-time-sigma, "
                    "0 for well-stamped fixes)")
        elif kind == "bias" and name in PLAUSIBLE_BIAS:
            limit, unit, why = PLAUSIBLE_BIAS[name]
            base = _wheel_base(robot)
            if name == "sigma_wheel_base":
                if base is None:
                    continue
                rule = f"{limit * base:.3g} m: {100 * limit:g} % of the robot's wheel base, {base:.3g} m"
                limit *= base
            else:
                rule = f"{limit:g} {unit}" if unit else f"{100 * limit:g} %"
            if value <= limit:
                continue
            shown = f"{value:.3g} {unit}" if unit else f"{value:.3g} ({100 * value:.3g} % from run to run)"
            if name == "sigma_steering_offset":  # the circle a steering zero that far off drives
                why = why.format(radius=(base or 0.0) / np.tan(limit))
            out.append(f"{key} = {shown} is implausible (limit {rule}): {why}; it is a calibration error "
                       f"or a model that does not fit, put into the bias; {_CALIBRATE}, or fit white noise "
                       "alone (--kinds white)")
    return out
