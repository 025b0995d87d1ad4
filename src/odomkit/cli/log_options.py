"""The log options shared by every command that reads a log (docs/reference/logs-and-truth.md):
``--format --columns --cumulative --wrap-bits --period --time-unit --decimate --topic --joints
--bag-time --truth-topic --truth-frame --imu-up --span --record``, declared once here and parsed
into :class:`odomkit.workflows.logs.LogOptions`; and the warnings that reading (or the work after
it) raises, shown as one line each.

``track``, ``calibrate``, ``calibrate-noise``, ``umbmark --runs``, ``fit-noise``, ``evaluate``,
``check`` and ``fit-amcl`` take these options alike (``tests/cli/test_log_options.py`` checks
that no command lacks one).

``--time-scale F`` (seconds per unit), the flag before ``--time-unit``, is kept as a second
name of ``--time-unit``, which takes a unit (s, ms, us, ns) or such a number: old scripts
run unchanged.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated, Any

import typer

from odomkit.cli.shared_flags import Flag, with_flags
from odomkit.workflows.logs import LOG_FORMATS, LogOptions

__all__ = [
    "BagTimeOption", "ColumnsOption", "CumulativeOption", "DecimateOption", "FormatOption", "ImuUpOption",
    "JointsOption",
    "LOG_FLAGS", "log_options", "PeriodOption", "reported_warnings", "TimeUnitOption", "TopicOption",
    "RecordOption", "SpanOption", "TruthFrameOption", "TruthTopicOption", "with_log_options", "with_warnings",
    "WrapBitsOption",
]

FormatOption = Annotated[str, typer.Option(
    "--format", help=f"Log format: {', '.join(LOG_FORMATS)} (auto: from the file name; a .bag, "
                     ".db3, .mcap or ROS 2 bag folder is a bag). Plain or gzip (.gz) text.")]
ColumnsOption = Annotated[str | None, typer.Option(
    "--columns", help="Text log columns: header names t=time,ticks_left=L,ticks_right=R, or in order "
                      "for a headerless file t,ticks_left,_,ticks_right (_ skips a column). Comma, "
                      "semicolon, tab or whitespace separated; # comments; columns not named may hold "
                      "text. Angles are radians and speeds m/s; steer_deg, yaw_rate_deg, heading_deg read "
                      "degrees, speed_kmh and speed_mph km/h and mph.")]
CumulativeOption = Annotated[bool, typer.Option(
    "--cumulative/--no-cumulative",
    help="CSV ticks_*/dist_* columns are cumulative counters (differenced, integers exactly).")]
WrapBitsOption = Annotated[int | None, typer.Option(
    "--wrap-bits", help="Unwrap cumulative counters of this width: 8, 16, 24, 32 or 64.")]
PeriodOption = Annotated[float | None, typer.Option(
    "--period", help="Sample period [s] of a log without time (khepera, snowhite).")]
TimeUnitOption = Annotated[str, typer.Option(
    "--time-unit", "--time-scale",
    help="Unit of the text log's time column: s, ms, us, ns, or seconds per unit (1e-4 for 100 µs "
         "ticks). --time-scale is its old name.")]
DecimateOption = Annotated[int, typer.Option(
    "--decimate", help="Use every n-th row (increments summed, rates sampled).")]
TopicOption = Annotated[list[str] | None, typer.Option(
    "--topic", help="ROS bag topic (JointState, Odometry, Twist, TwistStamped, TwistWithCovarianceStamped, "
                    "Imu, AckermannDriveStamped); repeat it: the first gives the rows, a later one's "
                    "channels replace an earlier one's.")]
JointsOption = Annotated[str | None, typer.Option(
    "--joints", help="ROS bag JointState wheel joints LEFT,RIGHT (or one); positions in rad, so the "
                     "robot file's m_per_tick is the wheel radius.")]
BagTimeOption = Annotated[bool, typer.Option(
    "--bag-time", help="ROS bag: time messages by when the bag received them, not their header stamps.")]
TruthTopicOption = Annotated[str | None, typer.Option(
    "--truth-topic", help="ROS bag pose topic (Odometry, PoseStamped, PoseWithCovarianceStamped, "
                          "TransformStamped, or /tf with --truth-frame) that is the log's ground truth, e.g. "
                          "motion capture; or a GPS NavSatFix topic (position-only, east-north metres from "
                          "the first fix).")]
TruthFrameOption = Annotated[str | None, typer.Option(
    "--truth-frame", help="ROS bag: PARENT:CHILD, the transforms of a tf2_msgs/TFMessage --truth-topic "
                          "(/tf) that are the truth, e.g. world:base_link (direct transforms only; not "
                          "needed where the topic carries one pair).")]

SpanOption = Annotated[str | None, typer.Option(
    "--span", help="Use part of the log: START:END from its first row, in seconds or percent of its "
                   "duration (:50% the first half, 50%: the rest, 120:600); a drive calibrated on one "
                   "part is judged on another.")]

ImuUpOption = Annotated[str, typer.Option(
    "--imu-up", help="ROS bag: the Imu axis that points up, +z (default), -z, +x, -x, +y or -y; its "
                     "angular velocity about it is the yaw rate (an IMU mounted on its side).")]
RecordOption = Annotated[str | None, typer.Option(
    "--record", help="Text log of tagged records (each line led by a word naming its type, several types "
                     "in one file: libRSF's odom2/loop, CARMEN's ODOM/FLASER): read only the lines of this "
                     "type. The tag is dropped: --columns counts from the field after it.")]


def log_options(format: str, columns: str | None, cumulative: bool, wrap_bits: int | None,
                period: float | None, time_unit: str, decimate: int, topic: list[str] | None = None,
                joints: str | None = None, bag_time: bool = False,
                truth_topic: str | None = None, span: str | None = None,
                record: str | None = None, imu_up: str = "+z", truth_frame: str | None = None) -> LogOptions:
    """The parsed log options; a bad value is one line naming its flag (exit 2). ``--topic``
    may also be comma-separated; ``--joints`` is."""
    topics = tuple(name.strip() for text in topic or () for name in text.split(","))
    joint_names = tuple(name.strip() for name in joints.split(",")) if joints is not None else ()
    up = imu_up.strip()
    up = f"+{up}" if up in ("x", "y", "z") else up  # "y" is "+y"
    return LogOptions(format, columns, cumulative, wrap_bits, period, time_unit, decimate,
                      topics, joint_names, bag_time, truth_topic, span, record, up, truth_frame)


#: The log flags every command that reads a log takes, in the order of their help.
LOG_FLAGS: tuple[Flag, ...] = (
    ("format", FormatOption, "auto"), ("columns", ColumnsOption, None),
    ("cumulative", CumulativeOption, False), ("wrap_bits", WrapBitsOption, None),
    ("period", PeriodOption, None), ("time_unit", TimeUnitOption, "s"), ("decimate", DecimateOption, 1),
    ("topic", TopicOption, None), ("joints", JointsOption, None), ("bag_time", BagTimeOption, False),
    ("truth_topic", TruthTopicOption, None), ("truth_frame", TruthFrameOption, None),
    ("imu_up", ImuUpOption, "+z"), ("span", SpanOption, None),
    ("record", RecordOption, None),
)
#: Decorator: the command takes :data:`LOG_FLAGS` and is called with ``log_opts``, the
#: parsed :class:`~odomkit.workflows.logs.LogOptions` (:func:`odomkit.cli.shared_flags.with_flags`).
with_log_options = with_flags(LOG_FLAGS, "log_opts", lambda values: log_options(**values))


@contextmanager
def reported_warnings(noun: str = "logs") -> Iterator[list[str]]:
    """Collect the warnings raised inside the block, and print each on stderr as one line
    ``odomkit: warning: ...`` when it ends (also when it ends in an error, which a warning
    may explain); those that say the same of several files (``PATH: text``) are one line,
    ``3 logs (a.csv, b.csv, c.csv): text`` (``noun`` names the files;
    :func:`odomkit.workflows.results.grouped_warnings`). The yielded list holds their texts
    as raised, for the JSON ``warnings`` key (:func:`with_warnings` groups them alike)."""
    from odomkit.workflows.results import collected_warnings, grouped_warnings

    messages: list[str] = []
    try:
        with collected_warnings() as messages:
            yield messages
    finally:
        for text in grouped_warnings(messages, noun):
            print(f"odomkit: warning: {text}", file=sys.stderr)


def with_warnings(out: dict[str, Any], messages: list[str], noun: str = "logs") -> dict[str, Any]:
    """``out`` with ``messages`` added to its ``warnings`` list (made if there are any), once
    each, and those that say the same of several files grouped into one line as on stderr
    (:func:`reported_warnings`)."""
    if messages or "warnings" in out:
        from odomkit.workflows.results import grouped_warnings

        known = list(out.get("warnings", []))
        out["warnings"] = grouped_warnings(known + [m for m in messages if m not in known], noun)
    return out
