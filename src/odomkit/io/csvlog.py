"""Generic CSV logs with a header and a column mapping."""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from odomkit import validate
from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io.table import cumulative_to_increments, order_by_time, read_numeric, unwrap_counter
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


def read_csv_log(
    path: str | Path,
    columns: Mapping[str, str],
    *,
    delimiter: str = ",",
    time_scale: float = 1.0,
    cumulative: bool = False,
    wrap_bits: int | None = None,
) -> OdometryLog:
    """Read a CSV log whose first line names the columns.

    Parameters
    ----------
    path : the CSV file
    columns : mapping from odomkit name to CSV column name. Keys: ``t`` (required), any
        channel of :mod:`odomkit.log` (``ticks_left``, ``speed``, ``steer``, ...), and
        optionally ``gt_x``, ``gt_y``, ``gt_theta`` for ground truth [m, m, rad].
    delimiter : field separator
    time_scale : multiply the time column by this to get seconds (1e-9 for ns stamps)
    cumulative : increment channels hold cumulative counts (differenced here)
    wrap_bits : unwrap cumulative counters of this width (16 or 32 typically)
    """
    path = Path(path)
    time_scale = validate.positive(time_scale, "time_scale", unit="s per time unit", error=InputError)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    with path.open(newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh, delimiter=delimiter), None)
    if not header:
        raise InputError("the file is empty: expected a header line", source=str(path))
    header = [h.strip() for h in header]
    if "t" not in columns:
        raise InputError("the column mapping needs t=<time column>", source=str(path))
    index: dict[str, int] = {}
    for key, name in columns.items():
        if key != "t" and key not in KNOWN_CHANNELS and key not in GROUND_TRUTH_FIELDS:
            raise InputError(
                f"unknown target {key!r} in the column mapping; expected t, "
                f"{', '.join(sorted(KNOWN_CHANNELS))} or {', '.join(GROUND_TRUTH_FIELDS)}",
                source=str(path))
        if name not in header:
            raise InputError(f"no column named {name!r} in the header (it has {header})",
                             source=str(path), line=1)
        index[key] = header.index(name)
    if wrap_bits is not None and not cumulative:
        raise InputError("wrap-around can only be undone on cumulative counters (--cumulative)")
    data = read_numeric(path, len(header), delimiter=delimiter, skip_header=1)
    order = order_by_time(data[:, index["t"]], str(path))
    if order is not None:
        data = data[order]
    t = data[:, index["t"]] * time_scale
    channels = {}
    for key, col in index.items():
        if key in KNOWN_CHANNELS:
            values = data[:, col].copy()
            if key in INCREMENT_CHANNELS and cumulative:
                if wrap_bits is not None:
                    values = unwrap_counter(values, wrap_bits)
                values = cumulative_to_increments(values)
            channels[key] = values
    truth = None
    gt_keys = [k for k in GROUND_TRUTH_FIELDS if k in index]
    if gt_keys:
        if len(gt_keys) != 3:
            raise InputError("ground truth needs all of gt_x, gt_y, gt_theta", source=str(path))
        truth = np.column_stack([data[:, index[k]] for k in GROUND_TRUTH_FIELDS])
        truth[:, 2] = unwrap_angle(truth[:, 2])
    return OdometryLog(t, channels, truth, str(path), {"format": "csv"})
