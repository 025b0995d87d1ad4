"""Reading a log in any supported format: the log options every log-reading command shares
(``track``, ``calibrate``, ``calibrate-noise``, ``umbmark --runs``, ``fit-noise``, ``evaluate``,
``check``, ``fit-amcl``). A text log (``csv``: any delimiter, header optional, ``#`` comments,
gzip, :mod:`odomkit.io.csvlog`) and a ROS bag (:mod:`odomkit.io.bag`) are two of the formats.

The readers are imported inside :func:`load_log`, so that a command module may import
:class:`LogOptions` and :data:`LOG_FORMATS` at start-up for nothing (``--help`` stays fast).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING

from odomkit.errors import InputError
from odomkit.progress import NO_PROGRESS, Progress, stage

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.robot import Robot

__all__ = ["COLUMN_EXAMPLES", "LOG_FORMATS", "LogOptions", "detect_format", "load_log",
           "parse_span", "require_log_file"]

LOG_FORMATS = ("auto", "csv", "khepera", "snowhite", "optiodom", "bag")

#: The ``--columns`` mapping a text log without one is asked for, in each vehicle's channels.
COLUMN_EXAMPLES = {
    "diff": "t=time,ticks_left=L,ticks_right=R",
    "tricycle": "t=time,ticks=N,steer=ANGLE",
    "car": "t=time,speed=V,steer=ANGLE",
    "unicycle": "t=time,speed=V,yaw_rate=W",
    "gyro": "t=time,ticks=N,yaw_rate=GYRO",
    "compass": "t=time,ticks=N,heading=COMPASS",
}

# Counter widths whose wrap-around can be undone (odomkit.io.table.COUNTER_BITS, repeated
# here so that importing this module loads no reader; tests/io checks they agree).
_COUNTER_BITS = (8, 16, 24, 32, 64)

# The options each format reads; any other option given for it is an error, not ignored.
_APPLIES = {
    "csv": {"columns", "cumulative", "wrap_bits", "time_unit", "record"},
    "khepera": {"cumulative", "wrap_bits", "period"},  # cumulative counts by definition
    "snowhite": {"period"},
    "optiodom": set(),
    "bag": {"topic", "joints", "bag_time", "truth_topic", "truth_frame", "imu_up"},
}
_FLAGS = {"columns": "--columns", "cumulative": "--cumulative", "wrap_bits": "--wrap-bits",
          "period": "--period", "time_unit": "--time-unit", "topic": "--topic", "joints": "--joints",
          "bag_time": "--bag-time", "truth_topic": "--truth-topic", "truth_frame": "--truth-frame",
          "record": "--record", "imu_up": "--imu-up"}


def require_log_file(path: Path) -> None:
    """Refuse, in one line that says what to give instead, a path that is no log file: a
    missing file; a folder (an OptiOdom experiment's, say), naming the logs in it; an
    OptiOdom experiment's ``*_metadata.csv`` (a shell glob ``*.csv`` picks it up with the
    runs). A user study met both, and was told "no such file" and "a text log needs
    --columns". A ROS 2 bag, a folder with its ``metadata.yaml``, is a log (its reader checks it)."""
    if detect_format(path) == "bag":
        return
    if path.is_dir():
        runs = sorted(p.name for p in path.iterdir() if p.is_file() and detect_format(p) != "csv")
        logs = runs or sorted(p.name for p in path.iterdir() if p.suffix.lower() in (".csv", ".txt", ".gz"))
        shown = ", ".join(logs[:3]) + (f" and {len(logs) - 3} more" if len(logs) > 3 else "")
        hint = (f"give the logs in it ({shown}: e.g. {path}/*_run-*.csv)" if runs else
                f"give the logs in it ({shown})" if logs else "it holds no log files")
        raise InputError(f"is a folder, not a log: {hint}", source=str(path))
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    if re.search(r"_metadata\.csv(\.gz)?$", path.name.lower()):
        raise InputError("is an OptiOdom experiment's metadata, not a run: give its runs "
                         f"({path.name.lower().split('_metadata')[0]}_run-*.csv)", source=str(path))


def detect_format(path: Path) -> str:
    """Guess a log format from its file name (a ``.gz`` suffix is looked through); a ROS bag
    (:func:`odomkit.io.bag.is_bag`) is a ``.bag``/``.db3``/``.mcap`` file, a folder with a
    ``metadata.yaml``, or a file whose first bytes are a ROS 1 bag's or an MCAP file's
    whatever its name (``run``, ``RUN.BAG``). A gzip-compressed bag (``run.bag.gz``, or gzip
    holding a bag) is a bag too, whose reader says to decompress it: read as a text log it
    would only be told that ``--topic`` does not apply.

    Examples
    --------
    >>> detect_format(Path("230620202042_run-01.csv")), detect_format(Path("log.csv.gz"))
    ('optiodom', 'csv')
    >>> detect_format(Path("230620202042_run-01.csv.gz"))
    'optiodom'
    """
    from odomkit.io.bag import is_bag  # here, not at the top: importing this module stays light

    if is_bag(path):
        return "bag"
    name = path.name.lower().removesuffix(".gz")
    if name.startswith("snowhite"):
        return "snowhite"
    if name.startswith("khepera"):
        return "khepera"
    if re.search(r"_run-\d+\.csv$", name):
        return "optiodom"
    return "csv"


@dataclass(frozen=True)
class LogOptions:
    """How to read a log (``odomkit track --help``, "log options"); checked when made.

    Parameters
    ----------
    format : one of :data:`LOG_FORMATS` ("auto": from the file name, :func:`detect_format`)
    columns : which text column holds what (csv only; :func:`odomkit.io.csvlog.parse_columns`):
        in order ``t,ticks_left,_,ticks_right`` (``_`` skips one) or a map of header
        names ``t=time,ticks_left=L,...``
    cumulative : increment channels hold cumulative counters (csv; khepera always does)
    wrap_bits : width of a counter that wraps around: 8, 16, 24, 32 or 64
    period : sample period [s] of a log without a time column (khepera, snowhite)
    time_unit : unit of the text log's time column: s, ms, us, ns, or seconds per unit as
        a number (``--time-unit 1e-4`` for 100 µs ticks; ``--time-scale`` is its old name)
    decimate : use every n-th row (increments summed, rates sampled)
    topic : ROS bag topics, the first giving the rows (bag only; :func:`odomkit.io.bag.read_bag`)
    joints : JointState wheel joints, ``(left, right)`` or one (bag only)
    bag_time : time each message by when the bag received it, not its header stamp (bag only)
    truth_topic : a ROS bag pose topic that is the log's ground truth (bag only)
    span : the part of the log to use, ``START:END`` from its first row, in seconds or in
        percent of its duration (``:50%`` the first half, ``50%:`` the rest; :func:`parse_span`)
    record : a text log of tagged records (every line led by a word naming its type, several
        types in one file): read only the lines of this type, the tag dropped, so that
        ``columns`` count from the field after it (csv only;
        :func:`odomkit.io.text.select_record`)
    imu_up : the axis of a bag's Imu that points up, one of :data:`odomkit.frames.UP_AXES` (bag only): its
        angular velocity about that axis is the yaw rate (``"+y"`` for an IMU on its side
        whose gravity reads along +y; :func:`odomkit.io.bag.read_bag`)
    truth_frame : ``"PARENT:CHILD"``, the transforms of a ``tf2_msgs/TFMessage`` truth topic
        (``/tf``) that are the truth, e.g. ``"world:base_link"`` (bag only; a leading '/' of
        either frame ignored; :func:`odomkit.io.bag.parse_truth_frame`)
    truth_time_offset : how late ``truth_topic``'s clock runs against the log's [s]: its stamps
        are moved by it before they are interpolated at the rows (bag only, with ``truth_topic``;
        :func:`odomkit.workflows.truth.with_truth_topic` moves ``--truth-time-offset`` here)
    """

    format: str = "auto"
    columns: str | None = None
    cumulative: bool = False
    wrap_bits: int | None = None
    period: float | None = None
    time_unit: str | float = "s"
    decimate: int = 1
    topic: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()
    bag_time: bool = False
    truth_topic: str | None = None
    span: str | None = None
    record: str | None = None
    imu_up: str = "+z"
    truth_frame: str | None = None
    truth_time_offset: float = 0.0

    def __post_init__(self) -> None:
        if self.span is not None:
            parse_span(self.span)
        if self.format not in LOG_FORMATS:
            raise InputError(f"--format must be one of {', '.join(LOG_FORMATS)}, got {self.format!r}")
        if self.wrap_bits is not None and self.wrap_bits not in _COUNTER_BITS:
            raise InputError(f"--wrap-bits must be one of {', '.join(map(str, _COUNTER_BITS))}, "
                             f"got {self.wrap_bits!r}")
        if self.period is not None and not _positive(self.period):
            raise InputError(f"--period must be a positive number of seconds, got {self.period!r}")
        if self.time_unit != "s":
            from odomkit.io.text import seconds_per_unit  # no numpy: --help stays fast

            seconds_per_unit(self.time_unit, "--time-unit")
        if isinstance(self.decimate, bool) or not isinstance(self.decimate, int) or self.decimate < 1:
            raise InputError(f"--decimate must be a positive integer, got {self.decimate!r}")
        offset = self.truth_time_offset
        if isinstance(offset, bool) or not isinstance(offset, int | float) or not math.isfinite(offset):
            raise InputError(f"--truth-time-offset must be a finite number of seconds, got {offset!r}")
        if offset and self.truth_topic is None:
            raise InputError("truth_time_offset moves a bag's truth topic (truth_topic); a truth file's "
                             "clock or a log's gt_* columns are moved by TruthOptions.time_offset")
        if self.truth_frame is not None:
            from odomkit.io.bag import parse_truth_frame  # here: no numpy for --help

            parse_truth_frame(self.truth_frame)
        from odomkit.frames import UP_AXES  # lazily: numpy, and LogOptions is made for --help's flags too

        if self.imu_up not in UP_AXES:
            raise InputError(f"--imu-up must be one of {', '.join(UP_AXES)} (the IMU axis that points up), "
                             f"got {self.imu_up!r}")
        if any(not isinstance(name, str) or not name.strip("/ ") for name in self.topic):
            raise InputError(f"--topic must name topics, e.g. /joint_states; got {list(self.topic)!r}")
        if self.joints and (len(self.joints) > 2 or len(set(self.joints)) != len(self.joints)
                            or any(not isinstance(j, str) or not j.strip() for j in self.joints)):
            raise InputError("--joints takes LEFT,RIGHT or one joint name, "
                             f"got {','.join(map(str, self.joints))!r}")

    def given(self) -> list[str]:
        """The flags set to something other than their default, e.g. ``["--cumulative"]``."""
        default = LogOptions()
        return [f"--{f.name.replace('_', '-')}" for f in fields(self)
                if getattr(self, f.name) != getattr(default, f.name)]

    def check_format(self, fmt: str, source: str) -> None:
        """Refuse an option that a log of format ``fmt`` would silently ignore."""
        stray = [flag for name, flag in _FLAGS.items()
                 if name not in _APPLIES[fmt] and getattr(self, name) != getattr(LogOptions(), name)]
        if stray:
            raise InputError(f"{', '.join(stray)} does not apply to a {fmt} log", source=source)
        if self.wrap_bits is not None and fmt == "csv" and not self.cumulative:
            raise InputError("--wrap-bits unwraps cumulative counters: add --cumulative", source=source)


#: One end of a ``--span``: (value, True for percent of the log's duration, False for seconds).
_SpanEnd = tuple[float, bool]


def parse_span(text: str) -> tuple[_SpanEnd | None, _SpanEnd | None]:
    """``--span START:END``: each end seconds from the log's first row or a percentage of
    its duration, either end may be left out (the log's own end).

    Examples
    --------
    >>> parse_span(":50%"), parse_span("120:600"), parse_span("30s:200s")
    ((None, (50.0, True)), ((120.0, False), (600.0, False)), ((30.0, False), (200.0, False)))
    """
    def end(part: str) -> _SpanEnd | None:
        part = part.strip()
        if not part:
            return None
        percent = part.endswith("%")
        # Seconds may carry their unit, as --window's do (30s).
        number = part.removesuffix("%") if percent else part.removesuffix("s")
        try:
            value = float(number)
        except ValueError:
            value = math.nan
        if not math.isfinite(value) or value < 0 or (percent and value > 100):
            raise InputError(f"--span takes START:END, seconds from the log's first row or percent of its "
                             f"duration (:50%, 50%:, 120:600, 120s:600s); {part!r} is neither")
        return value, percent

    if not isinstance(text, str) or text.count(":") != 1:
        raise InputError(f"--span takes START:END, e.g. :50% (the first half), 50%: (the rest) or "
                         f"120:600 (seconds from the log's first row); got {text!r}")
    start, stop = (end(part) for part in text.split(":"))
    if start is not None and stop is not None and start[1] == stop[1] and stop[0] <= start[0]:
        raise InputError(f"--span {text}: its end must come after its start")
    return start, stop


def _span_rows(log: OdometryLog, text: str) -> OdometryLog:
    """The rows of ``log`` inside ``--span text``, half-open [start, end) so that ``:50%``
    and ``50%:`` share no row."""
    import numpy as np

    start, stop = parse_span(text)
    first, duration = float(log.t[0]), float(log.t[-1] - log.t[0])

    def at(end: _SpanEnd | None, default: int) -> int:
        if end is None:
            return default
        seconds = end[0] / 100.0 * duration if end[1] else end[0]
        return int(np.searchsorted(log.t, first + seconds, side="left"))

    a, b = at(start, 0), at(stop, len(log))
    if b - a < 2:
        raise InputError(f"--span {text} leaves {max(b - a, 0)} row(s) of the log, whose rows run over "
                         f"{duration:.6g} s from its first", source=log.source)
    from dataclasses import replace

    # The whole log's clock kept, for what compares it with a truth's (a truth's span against
    # a cut log's is no sign of a time unit: workflows.truth._warn_if_units_off).
    return replace(log.rows(a, b), meta={**log.meta, "uncut_clock": (first, float(log.t[-1]))})


def _positive(value: float) -> bool:
    return (not isinstance(value, bool) and isinstance(value, int | float)
            and math.isfinite(value) and value > 0)


def load_log(path: str | Path, robot: Robot, options: LogOptions | None = None, *,
             progress: Progress = NO_PROGRESS) -> OdometryLog:
    """Read a log in any supported format (plain or gzip), cut it to ``--span`` and decimate
    it as ``options`` say (default: :class:`LogOptions`, the format from the file name).

    ``progress`` (:mod:`odomkit.progress`) gets one stage, ``"reading NAME"``: of the bag's
    messages for a ROS bag, of unknown length for a text log (read at once).

    Raises
    ------
    InputError
        Missing or malformed file, or an option that the log's format does not use.

    Warns
    -----
    UserWarning
        A counter column read as increments that looks cumulative.
    """
    from odomkit.io.csvlog import parse_columns, read_csv_log
    from odomkit.io.halmstad import read_khepera, read_snowhite
    from odomkit.io.optiodom import read_run
    from odomkit.robot import DiffDrive, robot_type_name

    options = options or LogOptions()
    path = Path(path)
    fmt = detect_format(path) if options.format == "auto" else options.format
    if fmt == "bag":
        from odomkit.io.bag import read_bag

        options.check_format(fmt, str(path))
        log = read_bag(path, options.topic, options.joints, options.bag_time, options.truth_topic,
                       progress=progress, imu_up=options.imu_up, truth_frame=options.truth_frame,
                       truth_time_offset=options.truth_time_offset)
    else:
        require_log_file(path)
        options.check_format(fmt, str(path))
        with stage(progress, None, f"reading {path.name}"):
            if fmt == "khepera":
                log = read_khepera(path, period=options.period or 1.0, wrap_bits=options.wrap_bits)
            elif fmt == "snowhite":
                log = read_snowhite(path, **({"period": options.period} if options.period else {}))
            elif fmt == "optiodom":
                log = read_run(path, "diff" if isinstance(robot, DiffDrive) else "tricyc")
            else:
                # Without --columns, a header in odomkit's own names (t,speed,yaw_rate) is enough.
                log = read_csv_log(path, parse_columns(options.columns) if options.columns else None,
                                   cumulative=options.cumulative, wrap_bits=options.wrap_bits,
                                   time_unit=options.time_unit,
                                   example=COLUMN_EXAMPLES[robot_type_name(robot)], record=options.record)
                _warn_if_slow(log, options)
    log = _in_span(log, options)
    _warn_if_too_fast(log, robot)
    return log


def _warn_if_slow(log: OdometryLog, options: LogOptions) -> None:
    """Warn where a text log's rows, its time read in seconds, come slower than any odometry
    logger's (:func:`odomkit.units.period_unit`): a log in ms read as seconds tracked a car
    over 4016 km in 1.5 million seconds, exit 0, without a word where no truth was given."""
    import warnings

    import numpy as np

    from odomkit.units import SLOW_ROWS, SLOWEST_PERIOD, period_unit

    if options.time_unit != "s" or len(log) < 3:
        return
    median = float(np.median(np.diff(log.t)))
    if (unit := period_unit(median)) is not None:
        warnings.warn(f"{log.source}: its rows come every {median:.4g} s (the median), {SLOW_ROWS} "
                      f"({SLOWEST_PERIOD:g} s at most): is its time in {unit}? (--time-unit "
                      f"{unit})", stacklevel=3)


def _warn_if_too_fast(log: OdometryLog, robot: Robot) -> None:
    """Warn where the log, read with ``robot``, moves faster than any wheeled vehicle
    (:func:`odomkit.kinematics.too_fast`): a raw counter read as increments tracked a tricycle
    over 561 km in 113 s, exit 0, without a word. A log the robot cannot convert (its
    channels, a steering angle past 90°) says so where it is converted, not here."""
    import warnings

    from odomkit.errors import OdomkitError
    from odomkit.kinematics import body_steps, too_fast

    if len(log) < 2:
        return
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the conversion's own warnings are said where it runs
            found = too_fast(body_steps(robot, log), log)
    except OdomkitError:
        return
    if found is not None:
        warnings.warn(f"{log.source}: {found[0]}: {found[1]}", stacklevel=3)


def _in_span(log: OdometryLog, options: LogOptions) -> OdometryLog:
    """The log cut to ``--span`` (before decimating: every n-th row counts from the span's
    first), then decimated."""
    if options.span is not None and len(log):
        log = _span_rows(log, options.span)
    return log.decimate(options.decimate)
