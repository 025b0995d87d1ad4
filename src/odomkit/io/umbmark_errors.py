"""UMBmark return-error files (CSV): one row per run of the bidirectional square.

The file has a header naming the columns ``direction,x,y`` (any order, any case, extra
columns ignored); ``direction`` is ``cw`` or ``ccw``, x and y are the return position
errors in metres, absolute minus calculated (Borenstein–Feng eq. 3.1)::

    direction,x,y
    cw,-0.30,-0.32
    ccw,0.05,0.21

Each direction needs at least two runs (the 3·SEM rule needs a standard deviation;
Borenstein–Feng used five).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

__all__ = ["MIN_RUNS_PER_DIRECTION", "REQUIRED_COLUMNS", "read_errors_csv"]

REQUIRED_COLUMNS = ("direction", "x", "y")
MIN_RUNS_PER_DIRECTION = 2


def read_errors_csv(path: str | Path) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Read an UMBmark errors CSV -> (errors_cw (n, 2), errors_ccw (m, 2)) [m].

    Raises :class:`~odomkit.errors.InputError` naming the file, line and field for a
    missing file, a header without ``direction``, ``x`` or ``y``, a direction other than
    cw/ccw, a value that is not a finite number, a direction with no runs, or fewer than
    two runs in a direction.
    """
    p = Path(path)
    source = str(p)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError("file not found", source=source) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", source=source) from None
    rows = [(n, r) for n, r in enumerate(csv.reader(text.splitlines()), start=1)
            if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError("empty file; expected a header 'direction,x,y' and one row per run",
                         source=source)
    header_line, header = rows[0]
    names = [c.strip().lower() for c in header]
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise InputError(f"header {','.join(header)!r} lacks column(s) {', '.join(missing)}; "
                         "expected 'direction,x,y'", source=source, line=header_line)
    index = {c: names.index(c) for c in REQUIRED_COLUMNS}
    runs: dict[str, list[tuple[float, float]]] = {"cw": [], "ccw": []}
    for line, row in rows[1:]:
        if len(row) < len(names):
            raise InputError(f"expected {len(names)} fields, got {len(row)}", source=source,
                             line=line)
        direction = row[index["direction"]].strip().lower()
        if direction not in runs:
            raise InputError(f"field 'direction' must be 'cw' or 'ccw', got {direction!r}",
                             source=source, line=line)
        values = []
        for col in ("x", "y"):
            raw = row[index[col]].strip()
            try:
                value = float(raw)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise InputError(f"field {col!r} must be a finite number [m], got {raw!r}",
                                 source=source, line=line)
            values.append(value)
        runs[direction].append((values[0], values[1]))
    for direction, found in runs.items():
        if len(found) < MIN_RUNS_PER_DIRECTION:
            raise InputError(
                f"{len(found)} {direction} run(s); UMBmark needs at least "
                f"{MIN_RUNS_PER_DIRECTION} per direction (Borenstein–Feng used 5)",
                source=source)
    return np.array(runs["cw"]), np.array(runs["ccw"])
