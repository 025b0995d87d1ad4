"""Does a calibration from truth positions hold along the drive it came from?

A calibration is a claim about the next drive. One long drive (a car against its GPS) can
be split: each half calibrated alone, and each half's parameters tried on the other half.
Where the halves' parameters differ by many of their standard errors *and* each half's
parameters fit the other half far worse than its own, the model misses something that
changes along the drive, and the calibration may make the next drive worse than the
nominal robot. Measured on a real car (a BMW's CAN speed and steering-wheel angle against
a phone's 1 Hz GPS, 340 s): the steering offset fitted on the first half (0.00168 rad,
± 8e-5) and on the second (0.00027, ± 1.3e-5) differed by 18 standard errors, and the
first half's calibration made the second half's error 4–5× the nominal robot's.

:func:`track_fitted_to_fixes` is the comparison both this check and the calibration plot
draw: a parameter set's track from the start pose that best fits the fixes.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.exact import ExactCalibration
from odomkit.calibrate.residuals import CalibratedRobot
from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog
from odomkit.robot import Robot
from odomkit.truth import Truth

__all__ = ["HalfFit", "calibrate_halves", "halves_disagree", "track_fitted_to_fixes"]

#: The halves' parameters differ "by many standard errors" beyond this many (combined).
DIFFERENT = 5.0
#: Each half's parameters fit the other half "far worse" than its own beyond this ratio of RMS.
WORSE = 2.0


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
    """

    label: str
    calibration: ExactCalibration
    rms_own: float
    rms_other: float

    def to_dict(self) -> dict[str, Any]:
        out = self.calibration.to_dict()
        return {"half": self.label, "parameters": out["parameters"], "std_errors": out["std_errors"],
                "rms_own_m": self.rms_own, "rms_on_other_half_m": self.rms_other}


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


def calibrate_halves(log: OdometryLog, truth: Truth, robot: CalibratedRobot, *,
                     steering_cubic: bool = False) -> list[HalfFit] | None:
    """Each half of one drive calibrated alone from its fixes, and each half's parameters
    tried on the other half.

    Parameters
    ----------
    log : the drive
    truth : Truth
        Its fixes, on the log's clock (a fitted clock offset already applied).
    robot : the nominal robot (:func:`odomkit.calibrate.positions.calibrate_positions`)
    steering_cubic : fit a car's steering_cubic in each half too

    Returns
    -------
    The two :class:`HalfFit`, or None where a half cannot be calibrated alone (too few
    fixes, too little motion).
    """
    from odomkit.calibrate.positions import calibrate_positions

    halves = _split(log, truth)
    fits = []
    for half, fixes in halves:
        if len(fixes.t) < 10:
            return None
        try:
            with warnings.catch_warnings():  # the whole drive's fit has said what they would say
                warnings.simplefilter("ignore")
                fits.append(calibrate_positions([half], [fixes], robot, steering_cubic=steering_cubic))
        except (InputError, ModelError):
            return None
    out = []
    for k, label in enumerate(("first half", "second half")):
        (own_log, own_fixes), (other_log, other_fixes) = halves[k], halves[1 - k]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(HalfFit(label, fits[k], _rms(own_log, fits[k].robot, own_fixes),
                                   _rms(other_log, fits[k].robot, other_fixes)))
        except (InputError, ModelError):
            return None  # one half's parameters cannot drive the other half at all
    return out


def halves_disagree(halves: list[HalfFit]) -> str | None:
    """A warning where the calibration does not hold along the drive: a parameter whose two
    halves differ by more than :data:`DIFFERENT` combined standard errors, while each half's
    parameters fit the other half more than :data:`WORSE` times worse (RMS) than that half's
    own (both: a difference the data see, and one that matters)."""
    first, second = halves
    names = first.calibration.names
    apart = []
    for k, name in enumerate(names):
        a, b = float(first.calibration.values[k]), float(second.calibration.values[k])
        se = math.hypot(float(first.calibration.std_errors[k]), float(second.calibration.std_errors[k]))
        if se > 0 and abs(a - b) > DIFFERENT * se:
            apart.append(f"{name} {a:.4g} and {b:.4g} ({abs(a - b) / se:.0f} standard errors apart)")
    worse = [other.rms_other / own.rms_own if own.rms_own > 0 else math.inf
             for own, other in ((second, first), (first, second))]
    if not apart or min(worse) <= WORSE:
        return None
    return ("the calibration does not hold along this drive: fitted on each half alone, "
            + "; ".join(apart) + f"; each half's parameters fit the other half {worse[0]:.1f}× and "
            f"{worse[1]:.1f}× worse than its own (RMS {first.rms_other:.3g} m against "
            f"{second.rms_own:.3g} m, {second.rms_other:.3g} m against {first.rms_own:.3g} m). "
            "The model misses something that "
            "changes along the drive (a car: a steering ratio that varies with the angle, understeer "
            "at speed, the road's camber; any robot: a floor that makes a wheel slip), so this "
            "calibration may make another drive worse than the nominal robot: calibrate on driving "
            "like the one it is for, and try it on a part it was not fitted to (--span)")
