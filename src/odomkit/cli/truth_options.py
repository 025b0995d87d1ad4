"""The truth options shared by every command that takes ground truth
(docs/reference/logs-and-truth.md): ``--truth --truth-format --truth-columns --truth-time-unit
--truth-sigma --truth-heading-sigma --truth-time-sigma --truth-time-offset --max-gap --truth-record
--truth-up``, parsed into :class:`odomkit.workflows.truth.TruthOptions`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from odomkit.cli.shared_flags import Flag, with_flags
from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.truth import TruthOptions

__all__ = [
    "MaxGapOption", "parse_initial_cov", "TRUTH_FLAGS", "truth_options", "TruthColumnsOption",
    "TruthFormatOption", "TruthHeadingSigmaOption", "TruthListOption", "TruthOption", "TruthRecordOption",
    "TruthSigmaOption",
    "TruthTimeOffsetOption", "TruthTimeSigmaOption", "TruthTimeUnitOption", "TruthUpOption",
    "with_truth_options",
]

_TRUTH_HELP = ("Ground-truth file: TUM (t x y z qx qy qz qw), KITTI pose rows with the time first, "
               "or text t,x,y[,theta] or GPS t,lat,lon[,alt] (degrees) or t,ecef_x,ecef_y,ecef_z "
               "(ECEF metres), as east-north metres from the first fix; default: the log's own gt_* "
               "columns.")
TruthOption = Annotated[Path | None, typer.Option("--truth", help=_TRUTH_HELP)]
TruthListOption = Annotated[list[Path] | None, typer.Option(
    "--truth", help=_TRUTH_HELP + " Repeat it: the i-th --truth belongs to the i-th log.")]
TruthFormatOption = Annotated[str, typer.Option(
    "--truth-format", help="auto | tum | kitti | csv")]
TruthColumnsOption = Annotated[str | None, typer.Option(
    "--truth-columns", help="Text truth columns: in order (t,x,y,_,theta; _ skips one; theta_deg "
    "for degrees) or a header map (t=stamp,x=px,y=py,theta=yaw); GPS: lat, lon, alt (or ecef_x, "
    "ecef_y, ecef_z), heading_deg_north (clockwise from north) for x, y, theta.")]
TruthTimeUnitOption = Annotated[str, typer.Option(
    "--truth-time-unit", help="Unit of the truth's time column: s | ms | us | ns.")]
TruthSigmaOption = Annotated[float | None, typer.Option(
    "--truth-sigma", help="Standard deviation of the truth positions per axis [m]; default 0, or "
    "the robot file's [truth] sigma where a robot's covariance is scored; fit-noise fits it if not given.")]
TruthHeadingSigmaOption = Annotated[float | None, typer.Option(
    "--truth-heading-sigma", help="Standard deviation of the truth headings [rad]; default as "
    "--truth-sigma's.")]
TruthTimeSigmaOption = Annotated[float | None, typer.Option(
    "--truth-time-sigma", help="Standard deviation of the truth fixes' times against the log's clock "
    "[s] (jitter, latency); default as --truth-sigma's.")]
TruthTimeOffsetOption = Annotated[float | None, typer.Option(
    "--truth-time-offset", help="How late the truth's clock runs against the log's [s]: a fix stamped t "
    "is the pose at log time t - OFFSET. Default: the robot file's [truth] time_offset, else 0; "
    "calibrate --truth fits it if not given.")]
MaxGapOption = Annotated[float, typer.Option(
    "--max-gap", help="Rows inside a truth gap longer than this [s] (and than twice the "
                      "truth's median spacing) are left out and counted (0: no limit).")]
TruthRecordOption = Annotated[str | None, typer.Option(
    "--truth-record", help="Truth file of tagged records (each line led by a word naming its type: libRSF's "
    "point2/angle, CARMEN's TRUEPOS): read only the lines of this type. The tag is dropped: "
    "--truth-columns counts from the field after it.")]

TruthUpOption = Annotated[str, typer.Option(
    "--truth-up", help="The axis of a TUM or KITTI truth file's frame that points up: +z (default), -z, "
    "+x, -x, +y (a motion capture's Y-up frame), -y (KITTI's camera frame).")]


def truth_options(truth: Path | None, fmt: str, columns: str | None, time_unit: str, sigma: float | None,
                  max_gap: float, heading_sigma: float | None = None,
                  time_sigma: float | None = None, time_offset: float | None = None,
                  record: str | None = None, up: str = "+z") -> TruthOptions:
    """The parsed truth options (``--max-gap 0`` means no limit; a noise or offset not given is None)."""
    from odomkit.workflows.truth import TruthOptions

    for flag, value, unit in (("--truth-sigma", sigma, "metres"), ("--truth-heading-sigma", heading_sigma,
                                                                   "radians"),
                              ("--truth-time-sigma", time_sigma, "seconds")):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise InputError(f"{flag} must be a non-negative number of {unit}, got {value!r}")
    if not (math.isfinite(max_gap) and max_gap >= 0):
        raise InputError(f"--max-gap must be a non-negative number of seconds, got {max_gap!r}")
    if time_offset is not None and not math.isfinite(time_offset):
        raise InputError(f"--truth-time-offset must be a finite number of seconds, got {time_offset!r}")
    from odomkit.frames import UP_AXES

    up = up.strip()
    up = f"+{up}" if up in ("x", "y", "z") else up  # "y" is "+y", as --imu-up reads it
    if up not in UP_AXES:
        raise InputError(f"--truth-up must be one of {', '.join(UP_AXES)} (the truth file's axis that points "
                         f"up), got {up!r}")
    return TruthOptions(truth, fmt, columns, time_unit, sigma, max_gap or None, heading_sigma, time_sigma,
                        time_offset, record, up)


#: The truth flags besides ``--truth`` itself (one file, or one per log, as the command
#: needs), in the order of their help.
TRUTH_FLAGS: tuple[Flag, ...] = (
    ("truth_format", TruthFormatOption, "auto"), ("truth_columns", TruthColumnsOption, None),
    ("truth_time_unit", TruthTimeUnitOption, "s"), ("truth_sigma", TruthSigmaOption, None),
    ("truth_heading_sigma", TruthHeadingSigmaOption, None), ("truth_time_sigma", TruthTimeSigmaOption, None),
    ("truth_time_offset", TruthTimeOffsetOption, None), ("max_gap", MaxGapOption, 0.5),
    ("truth_record", TruthRecordOption, None), ("truth_up", TruthUpOption, "+z"),
)
#: Decorator: the command takes :data:`TRUTH_FLAGS` and is called with ``truth_base``, the
#: parsed :class:`~odomkit.workflows.truth.TruthOptions` without a path
#: (:func:`odomkit.cli.shared_flags.with_flags`).
with_truth_options = with_flags(TRUTH_FLAGS, "truth_base", lambda values: truth_options(
    None, values["truth_format"], values["truth_columns"], values["truth_time_unit"],
    values["truth_sigma"], values["max_gap"], values["truth_heading_sigma"], values["truth_time_sigma"],
    values["truth_time_offset"], values["truth_record"], values["truth_up"]))


def parse_initial_cov(text: str | None) -> list[list[float]] | None:
    """``--initial-cov``: 3 variances (x, y, θ) or 9 numbers (the 3×3 matrix row by row)."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.replace(";", ",").replace(" ", "").split(",") if v]
    except ValueError:
        values = []
    if len(values) not in (3, 9) or not all(math.isfinite(v) for v in values):
        raise InputError(f"--initial-cov expects 3 variances var_x,var_y,var_theta or 9 numbers "
                         f"(a 3x3 matrix row by row), got {text!r}")
    if len(values) == 3:
        if min(values) < 0:
            raise InputError(f"--initial-cov variances must be >= 0, got {text!r}")
        return [[values[0], 0.0, 0.0], [0.0, values[1], 0.0], [0.0, 0.0, values[2]]]
    return [values[0:3], values[3:6], values[6:9]]
