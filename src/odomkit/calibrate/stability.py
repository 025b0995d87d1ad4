"""Does a calibration from truth positions hold along the drive it came from?

A calibration is a claim about the next drive. One long drive (a car against its GPS) can
be split: each half calibrated alone, and each half's parameters tried on the other half,
beside the nominal robot's (the robot file's). Where the halves' parameters differ by many
of their standard errors, each half's parameters fit the other half materially worse than
its own, *and* a half's calibration fits the other half worse than the nominal robot does,
the model misses something that changes along the drive, and the calibration may make the
next drive worse than the nominal robot (:func:`halves_disagree` gives the rule and its
numbers). Measured on a real car (a BMW's CAN speed and steering-wheel angle against a
phone's 1 Hz GPS, 340 s): the steering offset fitted on the first half (0.00168 rad, ± 8e-5)
and on the second (0.00027, ± 1.3e-5) differed by 18 standard errors, and the first half's
calibration made the second half's error 4–5× the nominal robot's. A half that cannot be
calibrated alone (its fit runs to the edge of a parameter's range) is said by
:func:`calibrate_halves` raising, not passed over.

:func:`track_fitted_to_fixes` is the comparison both this check and the calibration plot
draw: a parameter set's track from the start pose that best fits the fixes.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Collection
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.exact import ExactCalibration
from odomkit.calibrate.positions import MAX_STEERING_OFFSET, scale_range
from odomkit.calibrate.residuals import CalibratedRobot
from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog
from odomkit.robot import Robot
from odomkit.truth import Truth

__all__ = ["DIFFERENT", "HalfFit", "MATERIAL", "MIN_HALF_FIXES", "calibrate_halves", "halves_disagree",
           "track_fitted_to_fixes", "weakly_pinned", "WORSE"]

#: The halves' parameters differ "by many standard errors" beyond this many (combined).
DIFFERENT = 5.0
#: Each half's parameters fit the other half "far worse" than its own beyond this ratio of RMS.
WORSE = 2.0
#: A half's parameters fit the other half "materially worse" than the nominal robot (the
#: robot file's) does beyond this ratio of RMS (:func:`halves_disagree`).
MATERIAL = 1.5


def track_fitted_to_fixes(log: OdometryLog, robot: Robot, t: NDArray[np.float64], xy: NDArray[np.float64]
                          ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The log dead-reckoned with ``robot`` from the start pose that best fits the fixes.

    The track from the origin, interpolated linearly at the fix times (as
    :mod:`odomkit.calibrate.positions` compares them), is aligned to the fixes by SE(2)
    least squares (Umeyama 1991, :func:`odomkit.evaluate.umeyama_se2`): for a fixed
    parameter set that is the start pose ``calibrate --truth`` fits. A start pose moves the
    whole track rigidly, so the aligned track is integrated again from it.

    Parameters
    ----------
    log : OdometryLog, N rows
    robot : the parameter set
    t : ndarray, shape (K,)
        Fix times on the log's clock [s], inside its span.
    xy : ndarray, shape (K, 2)
        Fix positions [m].

    Returns
    -------
    poses : ndarray, shape (N, 3)
        The fitted track [m, m, rad].
    error : ndarray, shape (K, 2)
        Track minus fix at each fix [m].
    """
    from odomkit.evaluate import umeyama_se2
    from odomkit.track import dead_reckon_log

    log_t = np.asarray(log.t, dtype=float)

    def at_fixes(poses: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.column_stack([np.interp(t, log_t, poses[:, 0]), np.interp(t, log_t, poses[:, 1])])

    origin = dead_reckon_log(log, robot, "exact", np.zeros(3)).poses
    phi, shift = umeyama_se2(at_fixes(origin), xy[:, :2])
    poses = dead_reckon_log(log, robot, "exact", (float(shift[0]), float(shift[1]), phi)).poses
    return poses, at_fixes(poses) - xy[:, :2]


@dataclass(frozen=True)
class HalfFit:
    """One half of a drive calibrated alone.

    Parameters
    ----------
    label : str
        ``"first half"`` or ``"second half"``.
    calibration : ExactCalibration
        Its own fit (``names``, ``values``, ``std_errors``).
    rms_own : float
        RMS distance [m] of its track from its fixes with its own parameters.
    rms_other : float
        RMS distance [m] of the *other* half's track from the other half's fixes with these
        parameters (each from the start pose that fits best).
    rms_nominal_other : float
        The same with the nominal robot's parameters (the robot file's, uncalibrated): what
        the other half's error is without any calibration (NaN: not known).
    """

    label: str
    calibration: ExactCalibration
    rms_own: float
    rms_other: float
    rms_nominal_other: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        out = self.calibration.to_dict()
        return {"half": self.label, "parameters": out["parameters"], "std_errors": out["std_errors"],
                "rms_own_m": self.rms_own, "rms_on_other_half_m": self.rms_other,
                "rms_nominal_on_other_half_m": self.rms_nominal_other}


def _split(log: OdometryLog, truth: Truth) -> list[tuple[OdometryLog, Truth]]:
    """The log cut at its middle time (the halves share the boundary row, no step) and the
    fixes inside each half."""
    t = np.asarray(log.t, dtype=float)
    middle = int(np.searchsorted(t, 0.5 * (t[0] + t[-1])))
    halves = [log.rows(0, middle + 1), log.rows(middle, len(t))]
    out = []
    for half in halves:
        inside = (truth.t >= half.t[0]) & (truth.t <= half.t[-1])
        out.append((half, replace(truth, t=truth.t[inside], xy=truth.xy[inside],
                                  theta=None if truth.theta is None else truth.theta[inside])))
    return out


def _rms(log: OdometryLog, robot: Robot, truth: Truth) -> float:
    _, error = track_fitted_to_fixes(log, robot, truth.t, truth.xy)
    return float(np.sqrt(np.mean(np.sum(error**2, axis=1))))


#: Fewest fixes a half is calibrated from.
MIN_HALF_FIXES = 10
_LABELS = ("first half", "second half")
# The parameters with a plausible range of calibrate_positions' that a half's fit may run to
# (odomkit.calibrate.positions.scale_range, MAX_STEERING_OFFSET) besides the c_* and *_scale.
_LENGTHS = ("wheel_base", "wheel_to_axle", "m_per_tick")


def weakly_pinned(joint: ExactCalibration, start: Robot) -> list[str]:
    """The parameters one drive pins too weakly for a half's failure to mean anything.

    A half holds about half the fixes, so its standard errors are about √2 times the whole
    drive's (``joint``): where the whole drive's value lies within :data:`DIFFERENT` of those
    of the edge of its plausible range (a scale or a length half to twice ``start``'s value, a
    steering offset ±0.5 rad about it; the halves do not fit the truth's clock), a half alone
    may run to that edge by chance, and its failure says nothing of whether the calibration holds
    (OptiOdom's 20–33 s runs pin c_wheel_base to ±16–120 %, and a half ran it to its edge
    on 8 of them; one run that pins it to ±4.6 % is told that its calibration may not hold).
    A steering_cubic counts where its value is within as many standard errors
    of 0; a bias (no range) never does.

    Parameters
    ----------
    joint : the whole drive's calibration from ``start``
    start : the robot the fits start from (its values set the ranges)

    Returns
    -------
    list of str, each ``"NAME ± SE"`` in the calibration's own units
    """
    reach = DIFFERENT * math.sqrt(2.0)
    out = []
    for name, value, se in zip(joint.names, joint.values, joint.std_errors, strict=True):
        v, e = float(value), float(se)
        if name == "steering_offset":
            room = MAX_STEERING_OFFSET - abs(v - float(getattr(start, name, 0.0)))
        elif name == "steering_cubic":
            room = abs(v)
        elif name.startswith("c_") or name.endswith("_scale") or name in _LENGTHS:
            low, high = scale_range(float(getattr(start, name, math.nan)))
            room = min(v - low, high - v)
        else:  # a bias: no range to run to
            continue
        if not room > reach * e:
            out.append(f"{name} {v:.4g} ± {e:.2g}")
    return out


def calibrate_halves(log: OdometryLog, truth: Truth, robot: CalibratedRobot, *,
                     steering_cubic: bool = False, nominal: Robot | None = None,
                     heading_weight: float = 0.0, fixed: Collection[str] = ()) -> list[HalfFit]:
    """Each half of one drive calibrated alone from its fixes, and each half's parameters
    tried on the other half, beside the nominal robot's.

    Parameters
    ----------
    log : the drive
    truth : Truth
        Its fixes, on the log's clock (a fitted clock offset already applied).
    robot : the robot each half's fit starts from
        (:func:`odomkit.calibrate.positions.calibrate_positions`)
    steering_cubic : fit a car's steering_cubic in each half too
    nominal : the uncalibrated robot (the robot file's) that each half's calibration is
        held against on the other half (default ``robot``)
    heading_weight : W [m/rad] comparing the truth's heading in each half's fit as in the
        whole drive's (:func:`odomkit.calibrate.positions.calibrate_positions`)
    fixed : parameter names each half holds at ``robot``'s values, as the whole drive's fit
        held them (``calibrate --fix``)

    Returns
    -------
    The two :class:`HalfFit`.

    Raises
    ------
    InputError
        A half has too few fixes (:data:`MIN_HALF_FIXES`) or motion to be calibrated alone;
        the message names the half.
    ModelError
        A half's fit fails (runs to the edge of a parameter's range, diverges) or its
        parameters cannot drive the other half: itself a sign that the calibration does not
        hold along the drive (a Husky's first quarter ran its yaw-rate scale to the range's
        edge where the whole first half fitted 1.21, which then made the second half worse
        than the nominal robot's 1.0); the message names the half.
    """
    from odomkit.calibrate.positions import calibrate_positions

    halves = _split(log, truth)
    fits = []
    for label, (half, fixes) in zip(_LABELS, halves, strict=True):
        if len(fixes.t) < MIN_HALF_FIXES:
            raise InputError(f"the {label} holds {len(fixes.t)} truth fixes; a half is calibrated alone from "
                             f"{MIN_HALF_FIXES} or more")
        try:
            with warnings.catch_warnings():  # the whole drive's fit has said what they would say
                warnings.simplefilter("ignore")
                fits.append(calibrate_positions([half], [fixes], robot, steering_cubic=steering_cubic,
                                                heading_weight=heading_weight, fixed=fixed))
        except (InputError, ModelError) as exc:
            raise type(exc)(f"the {label} alone: {exc}") from exc
    base = robot if nominal is None else nominal
    out = []
    for k, label in enumerate(_LABELS):
        (own_log, own_fixes), (other_log, other_fixes) = halves[k], halves[1 - k]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(HalfFit(label, fits[k], _rms(own_log, fits[k].robot, own_fixes),
                                   _rms(other_log, fits[k].robot, other_fixes),
                                   _rms(other_log, base, other_fixes)))
        except (InputError, ModelError) as exc:
            raise ModelError(f"the {label}'s parameters cannot drive the {_LABELS[1 - k]}: {exc}") from exc
    return out


def halves_disagree(halves: list[HalfFit]) -> str | None:
    """A warning where the calibration does not hold along the drive, else None.

    Both must hold:

    1. the data see a difference: a parameter's two halves differ by more than
       :data:`DIFFERENT` combined standard errors;
    2. it does harm, and matters: one half's parameters fit the other half more than
       :data:`WORSE` times worse (RMS) than that half's own fit does, *and* more than
       :data:`MATERIAL` times worse than the nominal robot (the robot file's) does there.
       Where the nominal robot's fit is not known (``rms_nominal_other`` NaN), each half's
       parameters must fit the other half more than :data:`WORSE` times worse than its own.

    Why: the standard errors assume independent fixes, so with a 100 Hz motion capture or a
    wandering GPS the halves lie many of them apart on most drives, and (1) says little alone;
    the misfit against a half's own fit is large wherever that fit is near perfect (OptiOdom's
    halves fit their motion capture to 1–2 mm and each other's to 2–20 mm), so the rule before
    this one, (1) and each way more than :data:`WORSE`, warned on 16 of 143 OptiOdom runs, on
    13 of which each half's calibration fitted the other half better than the robot file. The
    warning claims that this calibration may make another drive worse than the robot file: the
    nominal robot on the other half is the measure of that. It also catches what a high
    threshold on the misfit both ways missed: a Husky's 395 s drive against a 0.8 m GPS, its
    halves 17–49 standard errors apart, whose first half's parameters fitted the second half
    2.5× worse than its own and 1.8× worse than the robot file (4.29 m against 1.74 m and
    2.43 m), the other way only 1.6× and better than the file: the first half's calibration made
    the second half's error 4.7× the robot file's (ATE), and nothing was said. On OptiOdom this
    rule warns on 4 of 143 runs (each a half whose calibration fitted the other half 1.5–4.6×
    worse than the robot file).
    """
    first, second = halves
    names = first.calibration.names
    apart = []
    for k, name in enumerate(names):
        a, b = float(first.calibration.values[k]), float(second.calibration.values[k])
        se = math.hypot(float(first.calibration.std_errors[k]), float(second.calibration.std_errors[k]))
        if se > 0 and abs(a - b) > DIFFERENT * se:
            apart.append(f"{name} {a:.4g} and {b:.4g} ({abs(a - b) / se:.0f} standard errors apart)")
    pairs = ((first, second), (second, first))
    # How much worse each half's parameters fit the other half than that half's own fit.
    worse = [half.rms_other / other.rms_own if other.rms_own > 0 else math.inf for half, other in pairs]
    known = all(math.isfinite(half.rms_nominal_other) for half in (first, second))
    harmful = [w > WORSE and half.rms_other > MATERIAL * half.rms_nominal_other
               for w, (half, _) in zip(worse, pairs, strict=True)]
    matters = any(harmful) if known else min(worse) > WORSE
    if not apart or not matters:
        return None
    nominal = "; ".join(
        f"the {half.label}'s parameters leave the {other.label} {half.rms_other:.3g} m from its fixes, "
        f"{half.rms_other / half.rms_nominal_other:.1f}× the robot file's {half.rms_nominal_other:.3g} m"
        for (half, other), bad in zip(pairs, harmful, strict=True) if known and bad)
    return ("the calibration does not hold along this drive: fitted on each half alone, "
            + "; ".join(apart) + f"; each half's parameters fit the other half {worse[0]:.1f}× and "
            f"{worse[1]:.1f}× worse than its own (RMS {first.rms_other:.3g} m against "
            f"{second.rms_own:.3g} m, {second.rms_other:.3g} m against {first.rms_own:.3g} m)"
            + (f", and worse than the uncalibrated robot file ({nominal})" if nominal else "") + ". "
            "The model misses something that "
            "changes along the drive (a car: a steering ratio that varies with the angle, understeer "
            "at speed, the road's camber; any robot: a floor that makes a wheel slip), so this "
            "calibration may make another drive worse than the nominal robot: calibrate on driving "
            "like the one it is for, and try it on a part it was not fitted to (--span)")
