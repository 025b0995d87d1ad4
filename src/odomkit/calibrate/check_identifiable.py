"""The identifiability check before calibrating (part of ``odomkit check``): how well each
calibration parameter of every robot ``odomkit calibrate`` calibrates is pinned by a log's
motion.

:func:`check_identifiable` takes the calibration model's own Jacobian
(:mod:`odomkit.calibrate.residuals`) at the robot's values, finds the part of each
parameter's effect on the track that no other parameter can mimic, and turns it into a
standard error with the position noise :func:`identifiability_sigma` assumes (an
:class:`AssumedSigma`, which every message states with where it came from: the figure is a
lower bound, the odometry's drift being correlated along the run); each parameter's label,
thresholds and advice are kept here with it.
:func:`odomkit.calibrate.check.check_log` runs it with the other checks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from odomkit.calibrate.check_finding import Finding
from odomkit.log import OdometryLog
from odomkit.robot import Robot
from odomkit.truth import Truth, scatter_sigma

if TYPE_CHECKING:
    from odomkit.calibrate.residuals import CalibratedRobot

__all__ = ["AssumedSigma", "check_identifiable", "identifiability_sigma"]

# Position noise assumed for the identifiability figures when the truth states none [m]:
# motion-capture noise plus the odometry's own random drift between samples.
_DEFAULT_SIGMA = 0.005


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


#: Where an assumed σ came from, as the messages say it.
_SOURCES = {
    "stated": "the truth's --truth-sigma",
    "scatter": "the fixes' scatter",
    "default": "the default",
    "given": "as given",
}


@dataclass(frozen=True)
class AssumedSigma:
    """The position noise the identifiability figures assume, and where it came from.

    ``value`` [m per axis]; ``source``: ``"stated"`` the truth's own σ (``--truth-sigma``),
    ``"scatter"`` its fixes' scatter about a smooth path (:func:`odomkit.truth.scatter_sigma`),
    ``"default"`` the 5 mm default (no truth, or one that states no σ and scatters less),
    ``"given"`` a number the caller passed.
    """

    value: float
    source: Literal["stated", "scatter", "default", "given"]

    def describe(self) -> str:
        """``"σ = 26.5 mm per axis (the fixes' scatter)"``: the σ and its source."""
        shown = f"{1000 * self.value:.3g} mm" if self.value < 1 else f"{self.value:.3g} m"
        return f"σ = {shown} per axis ({_SOURCES[self.source]})"


def identifiability_sigma(truth: Truth | None) -> AssumedSigma:
    """The position noise the identifiability figures assume: the truth's stated σ, else the
    larger of the default and the fixes' own scatter (a 1 m GPS must not be taken for 5 mm),
    else (no truth) the default."""
    if truth is None:
        return AssumedSigma(_DEFAULT_SIGMA, "default")
    if truth.sigma > 0:
        return AssumedSigma(float(truth.sigma), "stated")
    scatter = scatter_sigma(truth) or 0.0
    if scatter > _DEFAULT_SIGMA:
        return AssumedSigma(scatter, "scatter")
    return AssumedSigma(_DEFAULT_SIGMA, "default")


def check_identifiable(log: OdometryLog, robot: Robot, sigma: float | AssumedSigma | None = None
                       ) -> list[Finding]:
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
    odometry's drift is, make the true scatter larger: the figure is a lower bound, and each
    message says so, with the σ it assumed and where that came from (``sigma``: an
    :class:`AssumedSigma`, from :func:`identifiability_sigma`; a number is taken as given;
    None is the default). A finding's ``value`` is the standard error alone.

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
    if isinstance(sigma, AssumedSigma):
        assumed = sigma
    else:
        assumed = AssumedSigma(float(sigma), "given") if sigma else identifiability_sigma(None)
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
        se = math.inf if unique == 0 else assumed.value / unique / value
        unit, weak, unidentified = _LIMITS[par.kind]
        shown = f"±{100 * se:.2g} %" if unit == "%" else f"±{se:.2g} {unit}"
        # The σ behind the figure, and why it is a lower bound (BMW user study: ±8.9e-09 rad
        # at the fixes' 26.5 mm scatter, beside an odometry that drifts metres).
        # (Why a lower bound is the docs' and the docstring's: the drift is correlated along the run.)
        shown = (f"{shown} at {assumed.describe()}, a lower bound" if math.isfinite(se)
                 else f"unbounded at {assumed.describe()}")
        if math.isnan(se):
            found.append(Finding("identifiable", "warn", f"{par.label}: its standard error could not be "
                                 "computed (not a number): not checked", "check the log's values"))
            continue
        ratio = unique / norms[i] if norms[i] > 0 else 0.0
        why = (" (its effect on the track is almost all one that the other parameters can mimic)"
               if ratio < 0.1 and norms[i] > 0 else "")
        if se > unidentified:
            found.append(Finding("identifiable", "fail", f"{par.label}: not identifiable from this log "
                                 f"(standard error {shown}){why}",
                                 par.advice, se))
        elif se > weak:
            found.append(Finding("identifiable", "warn", f"{par.label}: weakly identified (standard error "
                                 f"{shown}){why}", par.advice, se))
        else:
            found.append(Finding("identifiable", "ok", f"{par.label}: identified (standard error {shown})",
                                 value=se))
    return found
