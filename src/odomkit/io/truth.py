"""Reading ground-truth files: TUM, KITTI-style pose rows with a time column, and text tables.

Formats (``--truth-format``):

``tum``
    ``t x y z qx qy qz qw`` per line (evo, the TUM RGB-D benchmark); the heading is the
    yaw of the quaternion, atan2(2(q_w q_z + q_x q_y), 1 − 2(q_y² + q_z²)).
``kitti``
    A KITTI pose row (the 3×4 matrix [R | p] row by row, 12 numbers) preceded by its time:
    ``t r11 r12 r13 px r21 r22 r23 py r31 r32 r33 pz`` (13 numbers). The plane is x–y
    with z up (a robot's map frame): x = px, y = py, θ = atan2(r21, r11). KITTI's own
    12-number rows carry no time, and truth must have a clock; put the time first (e.g.
    ``paste -d' ' times.txt poses.txt``). KITTI's camera frame has its ground plane in
    x–z: rotate such poses to z up first.
``csv``
    Text columns ``t,x,y[,theta]`` [s, m, m, rad] (``theta_deg`` for degrees), found by
    header names (``t``/``time``/``timestamp``, ``x``/``gt_x``, ``y``/``gt_y``,
    ``theta``/``yaw``/``heading``/``gt_theta``) or named by ``--truth-columns``: in order
    for a headerless file (``t,x,y,_,theta``; ``_`` skips a column) or as a map of header
    names (``t=stamp,x=px,y=py``). Without a heading column the truth is position-only.
``auto``
    A header means ``csv``; otherwise 8 columns mean ``tum``, 13 (or 12) ``kitti``, 3 or 4
    ``csv``.

Every format: comma, semicolon, tab or whitespace separated, ``#`` comments, plain or gzip
(``.gz``), sniffed as a log's text is (:func:`odomkit.io.text.sniff_layout`); time in s, ms,
us or ns, or seconds per unit as a number (``--truth-time-unit``). Rows are put in time order
(with a warning) and repeated times dropped (with a warning that counts them); a NaN is an
error naming its line: leave such fixes out, and the gap is left out and counted.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io.table import to_seconds
from odomkit.io.text import content_lines, is_number, read_text, seconds_per_unit, sniff_layout, split_fields
from odomkit.truth import Truth

__all__ = ["TRUTH_FORMATS", "parse_truth_columns", "read_truth"]

TRUTH_FORMATS = ("auto", "tum", "kitti", "csv")
_TARGETS = ("t", "x", "y", "theta", "theta_deg")
_HEADER_NAMES = {
    "t": ("t", "time", "timestamp", "stamp", "time_s"),
    "x": ("x", "gt_x", "x_gt", "pos_x", "tx"),
    "y": ("y", "gt_y", "y_gt", "pos_y", "ty"),
    "theta": ("theta", "gt_theta", "theta_gt", "yaw", "heading", "th"),
    "theta_deg": ("theta_deg", "yaw_deg", "heading_deg"),
}


def parse_truth_columns(text: str) -> dict[str, str] | list[str]:
    """``--truth-columns``: ``"t,x,y,_,theta"`` (in order) or ``"t=stamp,x=px,y=py"`` (a map).

    Examples
    --------
    >>> parse_truth_columns("t,x,y,_,theta")
    ['t', 'x', 'y', '_', 'theta']
    >>> parse_truth_columns("t=stamp, x=px, y=py")
    {'t': 'stamp', 'x': 'px', 'y': 'py'}
    """
    items = [s.strip() for s in text.split(",") if s.strip()]
    if any("=" in s for s in items):
        mapping: dict[str, str] = {}
        for item in items:
            key, sep, name = (p.strip() for p in item.partition("="))
            if not sep or key not in _TARGETS or not name:
                raise InputError(f"--truth-columns item {item!r} must look like target=column with "
                                 f"target one of {', '.join(_TARGETS)}")
            mapping[key] = name
        return mapping
    bad = [s for s in items if s not in _TARGETS and s != "_"]
    if bad or len(set(s for s in items if s != "_")) != len([s for s in items if s != "_"]):
        raise InputError(f"--truth-columns {text!r}: name each column once as one of "
                         f"{', '.join(_TARGETS)}, or _ to skip it")
    return items


def _table(path: Path, rows: list[tuple[int, list[str]]], ncols: int) -> NDArray[np.float64]:
    """The fields as an (n, ncols) float array; errors name the line and column."""
    for lineno, fields in rows:
        if len(fields) != ncols:
            raise InputError(f"expected {ncols} columns, found {len(fields)}", source=str(path),
                             line=lineno)
    try:
        data = np.array([f for _, f in rows], dtype=float)
    except ValueError:
        for lineno, fields in rows:
            for col, text in enumerate(fields, start=1):
                if not is_number(text):
                    raise InputError(f"column {col}: {text!r} is not a number", source=str(path),
                                     line=lineno) from None
        raise
    bad = ~np.isfinite(data)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(f"column {col + 1} is {data[row, col]}; truth needs finite numbers (leave "
                         "the fix out: a gap is left out of the scores and counted)",
                         source=str(path), line=rows[row][0])
    return data.reshape(-1, ncols)


def _csv_columns(path: Path, header: list[str] | None, ncols: int,
                 columns: dict[str, str] | list[str] | None) -> dict[str, int]:
    """Target -> column index for a text truth file."""
    if isinstance(columns, list):
        if len(columns) > ncols:
            raise InputError(f"--truth-columns names {len(columns)} columns, the file has {ncols}",
                             source=str(path))
        index = {name: i for i, name in enumerate(columns) if name != "_"}
    elif isinstance(columns, dict):
        if header is None:
            raise InputError("--truth-columns maps header names, but the file has no header; "
                             "name the columns in order instead (t,x,y,theta)", source=str(path))
        index = {}
        for key, name in columns.items():
            if name not in header:
                raise InputError(f"no column named {name!r} in the header (it has {header})",
                                 source=str(path))
            index[key] = header.index(name)
    elif header is not None:
        lower = [h.lower() for h in header]
        index = {}
        for key, names in _HEADER_NAMES.items():
            found = [i for i, h in enumerate(lower) if h in names]
            if found:
                index[key] = found[0]
    elif ncols in (3, 4):
        index = dict(zip(("t", "x", "y", "theta"), range(ncols), strict=False))
    else:
        raise InputError(f"{ncols} columns and no header: name them with --truth-columns "
                         "(e.g. t,x,y,theta) or give --truth-format tum|kitti", source=str(path))
    missing = [k for k in ("t", "x", "y") if k not in index]
    if missing:
        raise InputError(f"no column for {', '.join(missing)} (header {header}); name the columns "
                         "with --truth-columns, e.g. t=time,x=px,y=py,theta=yaw", source=str(path))
    if "theta" in index and "theta_deg" in index:
        raise InputError("give theta or theta_deg, not both", source=str(path))
    return index


def read_truth(
    path: str | Path,
    fmt: str = "auto",
    columns: str | None = None,
    time_unit: str = "s",
    sigma: float = 0.0,
) -> Truth:
    """Read a ground-truth file (formats in the module docstring).

    Parameters
    ----------
    path : the file (``.gz`` read transparently)
    fmt : {"auto", "tum", "kitti", "csv"}
    columns : ``--truth-columns`` text (csv only), see :func:`parse_truth_columns`
    time_unit : {"s", "ms", "us", "ns"} or seconds per unit, unit of the time column
        (:func:`odomkit.io.text.seconds_per_unit`)
    sigma : standard deviation of each truth position per axis [m]

    Returns
    -------
    Truth with strictly increasing times [s] and, unless the file is position-only, a
    continuous heading [rad].
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    if fmt not in TRUTH_FORMATS:
        raise InputError(f"unknown truth format {fmt!r}; expected one of {', '.join(TRUTH_FORMATS)}")
    seconds = seconds_per_unit(time_unit, "--truth-time-unit")
    spec = parse_truth_columns(columns) if columns else None
    if spec is not None and fmt in ("tum", "kitti"):
        raise InputError(f"--truth-columns applies to csv truth, not {fmt}")
    text = read_text(path, kind="truth file")
    layout = sniff_layout(text, str(path))
    delimiter = layout.delimiter
    header = None if layout.header is None else list(layout.header)
    lines = [(n, s) for n, s in content_lines(text) if n > layout.header_line]
    if not lines:
        raise InputError("the file has a header but no data rows", source=str(path))
    ncols = layout.ncols
    if fmt == "auto":
        fmt = ("csv" if header is not None or spec is not None or ncols in (3, 4)
               else {8: "tum", 12: "kitti", 13: "kitti"}.get(ncols, ""))
        if not fmt:
            raise InputError(f"cannot tell the truth format from {ncols} columns; give --truth-format "
                             "tum|kitti|csv (and --truth-columns for csv)", source=str(path))
    if fmt in ("tum", "kitti") and header is not None:
        raise InputError(f"a {fmt} file has no header, but this line is not numbers",
                         source=str(path), line=layout.header_line)
    if fmt == "kitti" and ncols == 12:
        raise InputError("KITTI pose rows carry no time, and truth needs a clock: put the time first "
                         "(13 numbers: t r11 r12 r13 px r21 r22 r23 py r31 r32 r33 pz)", source=str(path))
    want = {"tum": 8, "kitti": 13}.get(fmt, ncols)
    data = _table(path, [(n, split_fields(s, delimiter)) for n, s in lines], want)
    theta: NDArray[np.float64] | None
    if fmt == "tum":
        t, xy = data[:, 0], data[:, 1:3]
        qx, qy, qz, qw = data[:, 4], data[:, 5], data[:, 6], data[:, 7]
        norm = qx**2 + qy**2 + qz**2 + qw**2
        if np.any(norm == 0):
            row = int(np.flatnonzero(norm == 0)[0])
            raise InputError("the quaternion is zero; expected a unit quaternion qx qy qz qw",
                             source=str(path), line=lines[row][0])
        # Yaw (rotation about z) of the quaternion, ZYX convention; scale-free, so an
        # unnormalised quaternion gives the same angle.
        theta = np.arctan2(2 * (qw * qz + qx * qy), qw**2 + qx**2 - qy**2 - qz**2)
    elif fmt == "kitti":
        t, xy = data[:, 0], data[:, [4, 8]]
        theta = np.arctan2(data[:, 5], data[:, 1])  # atan2(r21, r11)
    else:
        index = _csv_columns(path, header, ncols, spec)
        t, xy = data[:, index["t"]], data[:, [index["x"], index["y"]]]
        theta = (data[:, index["theta"]] if "theta" in index
                 else np.radians(data[:, index["theta_deg"]]) if "theta_deg" in index else None)
    t = to_seconds(t, seconds)
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(t) < 0):
        warnings.warn(f"{path}: truth times are not in order; rows were sorted by time", stacklevel=2)
        t, xy = t[order], xy[order]
        theta = None if theta is None else theta[order]
    keep = np.concatenate(([True], np.diff(t) > 0))
    if not keep.all():
        warnings.warn(f"{path}: {int(np.count_nonzero(~keep))} truth rows repeat an earlier time and "
                      "were dropped (the first fix at each time is kept)", stacklevel=2)
        t, xy = t[keep], xy[keep]
        theta = None if theta is None else theta[keep]
    if not math.isfinite(sigma) or sigma < 0:
        raise InputError(f"--truth-sigma must be a non-negative number of metres, got {sigma!r}")
    return Truth(t.copy(), np.ascontiguousarray(xy, dtype=float),
                 None if theta is None else unwrap_angle(theta), float(sigma), str(path))
