"""Text logs as users have them: comma, semicolon, tab or whitespace separated, with or
without a header, ``#`` comments, plain or gzip (docs/reference/logs-and-truth.md, "Log options").

The layout (delimiter, header) is sniffed from the first data lines
(:func:`odomkit.io.text.sniff_layout`); the columns are named by ``--columns``, either in
order for a headerless file (``t,ticks_left,_,ticks_right``; ``_`` skips a column) or as a
map of header names (``t=time,ticks_left=L``). Timestamps may repeat (zero-length steps) but
never decrease; the time column may be in s, ms, µs or ns (``--time-unit``).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from odomkit import units
from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io._headers import no_such_column, time_like, time_text_error
from odomkit.io.table import (
    check_time_order,
    counter_increments,
    read_table,
    to_seconds,
    warn_if_cumulative,
)
from odomkit.io.text import (
    TextLayout,
    check_record_columns,
    content_lines,
    is_number,
    read_text,
    record_error,
    seconds_per_unit,
    select_record,
    sniff_layout,
    split_fields,
)
from odomkit.log import INCREMENT_CHANNELS, KNOWN_CHANNELS, SPEED_CHANNELS, OdometryLog, wheel_channels

__all__ = ["GROUND_TRUTH_FIELDS", "parse_columns", "read_csv_log", "SKIP_COLUMN", "UNIT_COLUMNS"]

GROUND_TRUTH_FIELDS = ("gt_x", "gt_y", "gt_theta")
SKIP_COLUMN = "_"
"""The name that skips a column in ``--columns`` given in order."""
UNIT_COLUMNS: dict[str, tuple[str, float]] = {
    "steer_deg": ("steer", units.DEGREE), "yaw_rate_deg": ("yaw_rate", units.DEGREE),
    "heading_deg": ("heading", units.DEGREE),
    "speed_kmh": ("speed", units.KMH), "speed_mph": ("speed", units.MPH),
}
"""Column names that read a channel in another unit: name -> (channel, SI units per unit).
odomkit's channels are radians and metres per second (:mod:`odomkit.log`), but a CAN steering angle
or a gyro is often logged in degrees (°/s for the yaw rate, as the truth's ``theta_deg``)
and a car's speed in km/h or mph (the factors: :mod:`odomkit.units`)."""
#: A bicycle or tricycle steering angle beyond ±90° (and a little more: OptiOdom's tricycle
#: logs exactly ±π/2 when it turns in place) is no radians a vehicle steers by.
STEER_LIMIT = np.pi / 2 + 0.01
#: A steering column beyond this is no angle in degrees either (a truck's steering wheel
#: turns up to about 3 turns lock to lock, ±540°): an encoder's raw ticks (a tricycle's
#: 8192-per-turn steering encoder read 8156 and was called degrees).
RAW_STEER = 1080.0
#: A base turning faster than a revolution a second for 1 % of a log is rarer than a gyro
#: logged in °/s read as rad/s (a 30 °/s turn would read as 4.8 revolutions a second).
YAW_RATE_LIMIT = 2 * np.pi
#: 60 m/s is 216 km/h: a wheeled robot or a road car logging faster for 1 % of its log is rarer
#: than a speed in km/h (a car at 100 km/h reads as 100 m/s) or mph read as m/s.
SPEED_LIMIT = 60.0


def parse_columns(text: str) -> dict[str, str] | list[str]:
    """``--columns``: channel names in column order, or a map from channel to header name.

    Examples
    --------
    >>> parse_columns("t=time, ticks_left=L")
    {'t': 'time', 'ticks_left': 'L'}
    >>> parse_columns("t, speed, _, yaw_rate")
    ['t', 'speed', '_', 'yaw_rate']
    """
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items:
        raise InputError("--columns is empty; name the columns, e.g. t,ticks_left,ticks_right")
    mapped = ["=" in item for item in items]
    if any(mapped) and not all(mapped):
        raise InputError(f"--columns {text!r} mixes the two forms: name every column in order "
                         "(t,ticks_left,_,ticks_right) or map every channel to a header name "
                         "(t=time,ticks_left=L)")
    if not all(mapped):
        return items
    mapping: dict[str, str] = {}
    for item in items:
        key, _, column = (p.strip() for p in item.partition("="))
        if not key or not column:
            raise InputError(f"--columns item {item!r} must look like channel=column")
        mapping[key] = column
    return mapping


#: Header names taken as the time column when a log's header names its columns itself.
TIME_NAMES = ("t", "time", "timestamp", "stamp")


#: Header names of other tools read as odomkit's channel (a ROS Twist's forward speed and
#: turn rate, as ``rostopic echo -p`` or a bag export writes them): unambiguous, unlike a
#: bare ``v`` or ``w``, which still ask for ``--columns``.
HEADER_ALIASES = {"linear_x": "speed", "linear.x": "speed", "twist.linear.x": "speed",
                  "field.linear.x": "speed", "angular_z": "yaw_rate", "angular.z": "yaw_rate",
                  "twist.angular.z": "yaw_rate", "field.angular.z": "yaw_rate"}


def _commented_names(text: str, ncols: int) -> list[str] | None:
    """The column names of a header written as the last ``#`` comment line before the data
    (``# Time [s]    forward velocity [m/s]    angular velocity[rad/s]``, the MRCLAM logs),
    split at tabs or runs of two or more spaces, where they are as many as the columns;
    else None. Only shown in the ``--columns`` hint: a comment is not read as a header."""
    import io
    import re

    last = None
    for line in io.StringIO(text):  # lazily: the data's first line ends the search
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            break
        last = stripped.lstrip("#").strip()
    if not last:
        return None
    names = [n for n in re.split(r"\t+|\s{2,}", last) if n]
    return names if len(names) == ncols else None


def _columns_from_header(header: Sequence[str] | None, source: str,
                         example: str = "t=time,ticks_left=L,ticks_right=R",
                         commented: Sequence[str] | None = None) -> dict[str, str]:
    """The ``columns`` mapping of a header that names every column by odomkit's own names
    (a time column of :data:`TIME_NAMES`, channels such as ``speed``, ``yaw_rate``,
    ``ticks_left``, and ``gt_x``, ``gt_y``, ``gt_theta``); otherwise the error asking for
    ``--columns``. Only a header wholly in these names is read so: a column it does not
    know could be a misspelt channel, which guessing would silently drop."""
    in_order = ",".join(part.split("=")[0] for part in example.split(","))
    hint = f"a text log needs --columns: header names ({example}) or the columns in order ({in_order})"
    if header is None:
        said = (f"; this log has no header (its last comment line names its {len(commented)} columns "
                f"{', '.join(repr(n) for n in commented)}: map them in order)" if commented
                else "; this log has no header")
        raise InputError(hint + said, source=source)
    times = [name for name in header if name.lower() in TIME_NAMES]
    known = [name for name in header
             if name in KNOWN_CHANNELS or name in UNIT_COLUMNS or name in GROUND_TRUTH_FIELDS
             or name.lower() in HEADER_ALIASES]
    unknown = [name for name in header if name not in times and name not in known]
    if (labelled := _labelled_fields(header)) is not None:
        raise InputError(f"{hint}; {labelled}", source=source)
    if len(times) != 1 or not known or unknown:
        raise InputError(f"{hint}; {_why_not_read(times, known, unknown)}", source=source)
    return {"t": times[0], **{HEADER_ALIASES.get(name.lower(), name): name for name in known}}


def _labelled_fields(header: Sequence[str]) -> str | None:
    """What a first line of numbers after labels says (``time: 1668091584.8 ticks: 290
    4294859756 ...``: a line of data, each value after its label), else None: such a line is
    no header, and mapping its labels as header names fails on the next line (a user study
    was told "map it as t=time:"). The labels and the fields after each are listed, for
    ``--columns`` in order."""
    labels = [k for k, name in enumerate(header) if name.endswith(":") and not is_number(name[:-1])]
    if not labels or not any(is_number(name) for name in header):
        return None
    parts = []
    for at, label in enumerate(labels):
        end = labels[at + 1] if at + 1 < len(labels) else len(header)
        first, last = label + 2, end  # fields count from 1; the values follow the label
        where = ("no field" if first > last else f"field {first}" if first == last
                 else f"fields {first}-{last}")
        parts.append(f"{header[label]!r} ({where})")
    return (f"its first line is data, each value after a label, not a header: {', '.join(parts)} of "
            f"{len(header)}; give the columns in order, _ for each label and each value not read "
            "(e.g. --columns _,t,_,... for a time in field 2)")


def _why_not_read(times: Sequence[str], known: Sequence[str], unknown: Sequence[str]) -> str:
    """Why a header is not read by its own names: every name odomkit does not know, and
    which time column it has (none, several, or one beside other names that look like a
    time, e.g. a CAN log's wall-clock ``Time`` and its ``Seconds``)."""
    def names(found: Sequence[str]) -> str:
        return ", ".join(repr(n) for n in found)

    said = [f"its header names {names(unknown)}, not odomkit's own names"] if unknown else []
    other = [n for n in unknown if time_like(n)]
    pick = "map the one that holds the time as t=<header name>"
    if len(times) > 1:
        said.append(f"it names {len(times)} time columns, {names([*times, *other])}: {pick}")
    elif not times:
        said.append("it names no time column (t, time, timestamp or stamp)"
                    + (f"; {names(other)} may be one: map it as t=<header name>" if other else ""))
    elif other:
        said.append(f"it names more than one time column, {times[0]!r} (odomkit's name for t) and "
                    f"{names(other)}: {pick}")
    elif unknown:
        said.append(f"{times[0]!r} would be taken as the time column t")
    if not known and not unknown:
        said.append("it names no channel")
    return "; ".join(said)


def _check_targets(targets: Sequence[str], source: str) -> None:
    named = [k for k in targets if k != SKIP_COLUMN]
    for key in named:
        if key != "t" and key not in KNOWN_CHANNELS | UNIT_COLUMNS.keys() | set(GROUND_TRUTH_FIELDS):
            raise InputError(
                f"unknown target {key!r} in --columns; expected t, "
                f"{', '.join(sorted(KNOWN_CHANNELS))} (steer_deg, yaw_rate_deg, heading_deg in degrees; "
                f"speed_kmh, speed_mph), "
                f"{', '.join(GROUND_TRUTH_FIELDS)} or _ (skip)",
                source=source)
    twice = sorted({k for k in named if named.count(k) > 1})
    if twice:
        raise InputError(f"--columns names {', '.join(twice)} more than once", source=source)
    def channel_of(name: str) -> str:
        return UNIT_COLUMNS[name][0] if name in UNIT_COLUMNS else name

    by_channel = {channel_of(name): [other for other in named if channel_of(other) == channel_of(name)]
                  for name in named}
    both = sorted(" or ".join(names) for names in by_channel.values() if len(names) > 1)
    if both:
        raise InputError(f"--columns names one channel twice, in two units: give {'; '.join(both)}, "
                         "not more than one", source=source)
    if "t" not in named:
        raise InputError("--columns needs the time column t (t=<header name>, or t in its place)",
                         source=source)
    try:  # ticks_left beside speed_right, or a wheel alone: no robot reads that
        wheel_channels(named)
    except InputError as exc:
        raise InputError(f"--columns: {exc}", source=source) from None


def _in_order(columns: Sequence[str], layout: TextLayout, text: str,
              source: str) -> tuple[TextLayout, dict[str, int]]:
    """Column index of each channel named in order (and the layout: a first line taken for
    a header, because a column not read holds text, is a data row when every column read
    holds a number there)."""
    index = {key: i for i, key in enumerate(columns) if key != SKIP_COLUMN}
    if layout.header is not None and len(columns) <= layout.ncols:
        read = [layout.header[i] for i in index.values()]
        if all(map(is_number, read)):
            layout = sniff_layout(text, source, header=False)
        elif any(map(is_number, read)):
            t, first = index.get("t"), layout.header
            assert first is not None  # the branch above reads it
            # A first row whose time is date or clock text is data, not a header: say that (with a
            # header the same file is told so; without, it was "mixes names and numbers": user study).
            if t is not None and (said := time_text_error(first[t], first, None, t, "--columns",
                                                          "--time-unit")):
                raise InputError(said, source=source, line=layout.header_line)
            raise InputError("this line mixes names and numbers: a header holds names only, a data row "
                             "numbers in the columns --columns reads; fix the row, or delete it if it "
                             "is a header", source=source, line=layout.header_line)
    if len(columns) > layout.ncols:
        raise InputError(f"--columns names {len(columns)} columns, the file has {layout.ncols} "
                         f"({layout.delimiter_name}-separated)", source=source,
                         line=layout.header_line or None)
    return layout, index


def _by_header(columns: Mapping[str, str], layout: TextLayout, text: str,
               source: str) -> tuple[TextLayout, dict[str, int]]:
    """Column index of each channel mapped to a header name (and the layout, whose first
    line is taken as the header when it holds exactly the names asked for: pandas writes
    ``0,1,2``)."""
    if layout.header is None:
        lineno, first = next(content_lines(text))
        if not set(columns.values()) <= set(split_fields(first, layout.delimiter)):
            raise InputError("--columns maps header names, but the file has no header (this line is "
                             "numbers); name the columns in order instead, e.g. --columns "
                             "t,ticks_left,ticks_right (_ skips a column)", source=source, line=lineno)
        layout = sniff_layout(text, source, header=True)
    header = list(layout.header or ())
    index = {}
    for key, name in columns.items():
        if name not in header:
            raise InputError(no_such_column(name, header, "--columns", key, "the log"),
                             source=source, line=layout.header_line)
        index[key] = header.index(name)
    return layout, index


def _check_time_text(text: str, layout: TextLayout, index: Mapping[str, int], source: str,
                     chosen: bool) -> None:
    """Refuse a time column whose first data row holds a date or a clock time (a CAN logger's
    wall-clock ``Time``), naming the header's numeric time columns to read instead (in a whole
    ``--columns`` map where the user gave none, or gave the columns in order: ``chosen``)."""
    column = index["t"]
    for lineno, content in content_lines(text):
        if lineno <= layout.header_line:
            continue
        row = split_fields(content, layout.delimiter)
        said = None if column >= len(row) else time_text_error(
            row[column], row, layout.header, column, "--columns", "--time-unit",
            others=dict(index) if chosen else None)
        if said:
            raise InputError(said, source=source, line=lineno)
        return


def _warn_if_other_unit(values: np.ndarray, key: str, source: str, label: str) -> None:
    """Warn where a steering angle or yaw rate read as radians looks like degrees
    (:data:`STEER_LIMIT`, :data:`YAW_RATE_LIMIT`), or a speed read as m/s like km/h or mph
    (:data:`SPEED_LIMIT`): read so, they give a wrong track silently."""
    finite = np.abs(values[np.isfinite(values)])
    if not finite.size:
        return
    if key == "steer":
        seen, limit, what = float(finite.max()), STEER_LIMIT, "reaches"
    else:
        seen, what = float(np.percentile(finite, 99)), "has a 99th percentile of"
        limit = YAW_RATE_LIMIT if key == "yaw_rate" else SPEED_LIMIT
    if key == "steer" and seen > RAW_STEER:
        warnings.warn(
            f"{source}: {label} ({key}) reaches {seen:.4g}, beyond any angle in degrees a steering wheel "
            f"turns ({RAW_STEER:g}°): is it an encoder's raw ticks? odomkit reads rad (steer_deg reads "
            "degrees); give the robot file's steering_ratio (ticks per radian of the wheel), or convert "
            "the ticks to the angle first", UserWarning, stacklevel=3)
        return
    if seen > limit:
        unit, other = {"steer": ("rad", "degrees"), "yaw_rate": ("rad/s", "degrees")}.get(
            key, ("m/s", "km/h or mph"))
        columns = f"{key}_deg" if key not in SPEED_CHANNELS else "speed_kmh or speed_mph"
        # Wheel speeds have no column in another unit (UNIT_COLUMNS): they are converted first.
        fix = (f"{columns} in --columns reads {other} ({columns.split(' or ')[0]}=<header name>, or in "
               "its place)" if key in ("steer", "yaw_rate", "speed")
               else f"convert the wheel speeds to {unit}")
        warnings.warn(
            f"{source}: {label} ({key}) {what} {seen:.3g} {unit}, beyond {limit:.3g} {unit}: "
            f"is it in {other}? odomkit reads {unit}; {fix}",
            UserWarning, stacklevel=3)


def read_csv_log(
    path: str | Path,
    columns: str | Mapping[str, str] | Sequence[str] | None,
    *,
    time_unit: str | float = "s",
    cumulative: bool = False,
    wrap_bits: int | None = None,
    example: str = "t=time,ticks_left=L,ticks_right=R",
    record: str | None = None,
) -> OdometryLog:
    """Read a text log (plain or gzip): delimiter and header found by
    :func:`odomkit.io.text.sniff_layout`, columns named by ``columns``.

    Parameters
    ----------
    path : the file
    columns : which column holds what; None: the header's own names, where it names every
        column by odomkit's (``t,speed,yaw_rate``; :data:`TIME_NAMES` for time; a ROS Twist's
        ``linear_x``, ``angular_z``: :data:`HEADER_ALIASES`). A string is ``--columns``'s
        text (``"t,speed,yaw_rate"``, ``"t=time,ticks_left=L"``), read by
        :func:`parse_columns` as the command line reads it, as ``read_truth`` and
        :class:`~odomkit.workflows.logs.LogOptions` take theirs. A sequence
        names the columns in order
        (``["t", "ticks_left", "_", "ticks_right"]``; ``_`` skips one; columns after the
        last name are ignored; a header line, if any, is skipped); a mapping goes from
        odomkit name to header name (``{"t": "time", "ticks_left": "L"}``). Names: ``t``
        (required), any channel of :mod:`odomkit.log` (``ticks_left``, ``speed``,
        ``steer``, ...), the channels in other units (:data:`UNIT_COLUMNS`:
        ``steer_deg``, ``yaw_rate_deg``, ``heading_deg`` in degrees, ``speed_kmh``,
        ``speed_mph``), and ``gt_x``, ``gt_y``,
        ``gt_theta`` for ground truth [m, m, rad].
    time_unit : unit of the time column: ``"s"``, ``"ms"``, ``"us"``, ``"ns"``, or seconds
        per unit as a number (:func:`odomkit.io.text.seconds_per_unit`)
    cumulative : increment channels hold cumulative counts, differenced here (integer
        counts exactly, in 64-bit integer arithmetic)
    wrap_bits : unwrap cumulative counters of this width (16 or 32 typically; 64 exact)
    example : the ``--columns`` mapping a missing-columns error suggests (the robot's own
        channels: :data:`odomkit.workflows.logs.COLUMN_EXAMPLES`)
    record : read only the lines whose first field is this word (``--record``: a file of
        tagged records such as libRSF's ``odom2 t vx vy yaw_rate ...`` beside ``loop ...``,
        or CARMEN's ``ODOM ...`` beside ``FLASER ...``), the tag dropped: ``columns`` then
        name the fields after it, in order (:func:`odomkit.io.text.select_record`). None:
        every line, and a file whose lines are records of several types is refused, naming
        them.

    Raises
    ------
    InputError
        Naming the file and line: no such column, a field that is not a number, decreasing
        time (repeated times are kept: zero-length steps), decimal commas, and so on.

    Warns
    -----
    UserWarning
        When an increment column read as increments never decreases and takes many
        values: a cumulative counter without ``cumulative`` (:func:`odomkit.io.table.warn_if_cumulative`);
        when a steering angle beyond ±(π/2 + 0.01) rad or a yaw rate whose 99th percentile
        is beyond 2π rad/s looks like degrees read as radians.
    """
    path = Path(path)
    source = str(path)
    seconds = seconds_per_unit(time_unit)
    if wrap_bits is not None and not cumulative:
        raise InputError("wrap-around can only be undone on cumulative counters (--cumulative)")
    if isinstance(columns, str):  # --columns text, as the command line gives it
        columns = parse_columns(columns)
    text = read_text(path)
    try:
        return _log_of_text(path, select_record(text, source, record), columns, seconds, cumulative,
                            wrap_bits, example, record, text)
    except InputError as exc:
        raise record_error(exc, text, record) from None


def _log_of_text(path: Path, text: str, columns: Mapping[str, str] | Sequence[str] | None, seconds: float,
                 cumulative: bool, wrap_bits: int | None, example: str, record: str | None,
                 whole: str) -> OdometryLog:
    """The log in ``text``, the lines of the file (``whole``) that :func:`read_csv_log` reads."""
    source = str(path)
    layout = sniff_layout(text, source)
    if record is not None:
        check_record_columns(columns, layout.ncols, record, source, whole=whole, selected=text,
                             delimiter=layout.delimiter)
    given = columns
    if columns is None:
        commented = _commented_names(text, layout.ncols) if layout.header is None else None
        columns = _columns_from_header(layout.header, source, example, commented)
    _check_targets(list(columns), source)
    if isinstance(columns, Mapping):
        layout, index = _by_header(columns, layout, text, source)
        labels = {key: f"column {name!r}" for key, name in columns.items()}
    else:
        layout, index = _in_order(columns, layout, text, source)
        labels = {key: f"column {i + 1}" for key, i in index.items()}
    _check_time_text(text, layout, index, source, chosen=given is None or not isinstance(given, Mapping))
    counters = sorted({col for key, col in index.items() if key in INCREMENT_CHANNELS}) if cumulative else []
    # Only the columns named are read as numbers: the others may hold text (a CAN log's date).
    table = read_table(path, layout.ncols, delimiter=layout.delimiter, skip_header=layout.header_line,
                       integer_columns=counters, text=text, usecols=sorted(set(index.values())))
    check_time_order(table.column(index["t"]), table)
    t = to_seconds(table.column(index["t"]), seconds)
    channels = {}
    for key, col in index.items():
        if key in UNIT_COLUMNS:
            channel, si_per_unit = UNIT_COLUMNS[key]
            channels[channel] = table.column(col) * si_per_unit
            continue
        if key not in KNOWN_CHANNELS:
            continue
        if key in INCREMENT_CHANNELS and cumulative:
            channels[key] = counter_increments(table.counter(col, wrap_bits), wrap_bits)
            continue
        channels[key] = table.column(col).copy()
        if key in INCREMENT_CHANNELS:
            warn_if_cumulative(channels[key], source, f"{labels[key]} ({key})")
        elif key in ("steer", "yaw_rate") or key in SPEED_CHANNELS:
            _warn_if_other_unit(channels[key], key, source, labels[key])
    truth = None
    gt_keys = [k for k in GROUND_TRUTH_FIELDS if k in index]
    if gt_keys:
        if len(gt_keys) != 3:
            raise InputError("ground truth needs all of gt_x, gt_y, gt_theta", source=source)
        truth = np.column_stack([table.column(index[k]) for k in GROUND_TRUTH_FIELDS])
        truth[:, 2] = unwrap_angle(truth[:, 2])
    return OdometryLog(t, channels, truth, source, {"format": "csv", "delimiter": layout.delimiter_name})
