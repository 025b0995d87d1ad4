"""Generic CSV logs (plain or gzip) with a header and a column mapping."""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from odomkit import validate
from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io.table import counter_increments, order_by_time, read_table, warn_if_cumulative
from odomkit.io.text import read_text
from odomkit.log import INCREMENT_CHANNELS, KNOWN_CHANNELS, OdometryLog

__all__ = ["GROUND_TRUTH_FIELDS", "parse_column_map", "read_csv_log"]

GROUND_TRUTH_FIELDS = ("gt_x", "gt_y", "gt_theta")


def parse_column_map(text: str) -> dict[str, str]:
    """Parse ``"t=time,ticks_left=enc_l,ticks_right=enc_r"`` into a dict.

    >>> parse_column_map("t=time, ticks_left=L")
    {'t': 'time', 'ticks_left': 'L'}
    """
    mapping: dict[str, str] = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, column = item.partition("=")
        if not sep or not key.strip() or not column.strip():
            raise InputError(f"--columns item {item!r} must look like channel=column")
        mapping[key.strip()] = column.strip()
    return mapping


def _header(text: str, delimiter: str, source: str) -> tuple[int, list[str]]:
    """Line number and names of the header: the first line that is neither blank nor a
    ``#`` comment."""
    for lineno, line in enumerate(io.StringIO(text, newline="\n"), start=1):  # lazily: logs are long
        if line.strip() and not line.lstrip().startswith("#"):
            names = next(csv.reader([line.rstrip("\r\n")], delimiter=delimiter))
            return lineno, [name.strip() for name in names]
    raise InputError("the file is empty: expected a header line", source=source)


def read_csv_log(
    path: str | Path,
    columns: Mapping[str, str],
    *,
    delimiter: str = ",",
    time_scale: float = 1.0,
    cumulative: bool = False,
    wrap_bits: int | None = None,
) -> OdometryLog:
    """Read a CSV log (plain or gzip) whose first line, after any ``#`` comments, names the columns.

    Parameters
    ----------
    path : the CSV file
    columns : mapping from odomkit name to CSV column name. Keys: ``t`` (required), any
        channel of :mod:`odomkit.log` (``ticks_left``, ``speed``, ``steer``, ...), and
        optionally ``gt_x``, ``gt_y``, ``gt_theta`` for ground truth [m, m, rad].
    delimiter : field separator
    time_scale : multiply the time column by this to get seconds (1e-9 for ns stamps)
    cumulative : increment channels hold cumulative counts, differenced here (integer
        counts exactly, in 64-bit integer arithmetic)
    wrap_bits : unwrap cumulative counters of this width (16 or 32 typically; 64 exact)

    Warns
    -----
    UserWarning
        When an increment column read as increments never decreases and takes many
        values: a cumulative counter without ``cumulative`` (:func:`odomkit.io.table.warn_if_cumulative`).
    """
    path = Path(path)
    source = str(path)
    time_scale = validate.positive(time_scale, "time_scale", unit="s per time unit", error=InputError)
    if wrap_bits is not None and not cumulative:
        raise InputError("wrap-around can only be undone on cumulative counters (--cumulative)")
    text = read_text(path)
    header_line, header = _header(text, delimiter, source)
    if "t" not in columns:
        raise InputError("the column mapping needs t=<time column>", source=source)
    index: dict[str, int] = {}
    for key, name in columns.items():
        if key != "t" and key not in KNOWN_CHANNELS and key not in GROUND_TRUTH_FIELDS:
            raise InputError(
                f"unknown target {key!r} in the column mapping; expected t, "
                f"{', '.join(sorted(KNOWN_CHANNELS))} or {', '.join(GROUND_TRUTH_FIELDS)}",
                source=source)
        if name not in header:
            raise InputError(f"no column named {name!r} in the header (it has {header})",
                             source=source, line=header_line)
        index[key] = header.index(name)
    counters = sorted({col for key, col in index.items() if key in INCREMENT_CHANNELS}) if cumulative else []
    table = read_table(path, len(header), delimiter=delimiter, skip_header=header_line,
                       integer_columns=counters, text=text)
    data = table.values
    order = order_by_time(data[:, index["t"]], source)
    if order is not None:
        data = data[order]
    t = data[:, index["t"]] * time_scale
    channels = {}
    for key, col in index.items():
        if key not in KNOWN_CHANNELS:
            continue
        if key in INCREMENT_CHANNELS and cumulative:
            counts = table.counter(col, wrap_bits)
            channels[key] = counter_increments(counts if order is None else counts[order], wrap_bits)
            continue
        channels[key] = data[:, col].copy()
        if key in INCREMENT_CHANNELS:
            warn_if_cumulative(channels[key], source, f"column {columns[key]!r} ({key})")
    truth = None
    gt_keys = [k for k in GROUND_TRUTH_FIELDS if k in index]
    if gt_keys:
        if len(gt_keys) != 3:
            raise InputError("ground truth needs all of gt_x, gt_y, gt_theta", source=source)
        truth = np.column_stack([data[:, index[k]] for k in GROUND_TRUTH_FIELDS])
        truth[:, 2] = unwrap_angle(truth[:, 2])
    return OdometryLog(t, channels, truth, source, {"format": "csv"})
