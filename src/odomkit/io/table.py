"""Reading numeric text tables with errors that name the file, line and column."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

__all__ = ["cumulative_to_increments", "order_by_time", "polars_module", "read_numeric", "unwrap_counter"]


def _first_bad_line(path: Path, ncols: int, delimiter: str | None, skip: int) -> InputError:
    """Re-scan a file that numpy refused, to say exactly where and why."""
    with path.open("r", encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, start=1):
            if lineno <= skip or not raw.strip() or raw.lstrip().startswith("#"):
                continue
            fields = raw.strip().split(delimiter) if delimiter else raw.split()
            if len(fields) != ncols:
                return InputError(f"expected {ncols} columns, found {len(fields)}",
                                  source=str(path), line=lineno)
            for col, text in enumerate(fields, start=1):
                try:
                    float(text)
                except ValueError:
                    return InputError(f"column {col}: {text.strip()!r} is not a number",
                                      source=str(path), line=lineno)
    return InputError("could not be read as a numeric table", source=str(path))


def read_numeric(
    path: str | Path, ncols: int, delimiter: str | None = None, skip_header: int = 0
) -> NDArray[np.float64]:
    """Read an ``(N, ncols)`` float table; reject missing files, ragged rows, text, NaN.

    Parameters
    ----------
    path : path to a text file
    ncols : number of columns every row must have
    delimiter : None for any whitespace, else e.g. ","
    skip_header : lines to skip at the top
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    data = _read_with_polars(path, ncols, delimiter, skip_header)
    if data is not None:
        return _check_finite(path, data, skip_header)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warns on an empty file
            data = np.loadtxt(path, delimiter=delimiter, skiprows=skip_header, ndmin=2,
                              dtype=float, comments="#")
    except UserWarning:
        raise InputError("the file is empty: no data rows", source=str(path)) from None
    except ValueError:
        raise _first_bad_line(path, ncols, delimiter, skip_header) from None
    if data.size == 0:
        raise InputError("the file is empty: no data rows", source=str(path))
    if data.shape[1] != ncols:
        raise InputError(f"expected {ncols} columns, found {data.shape[1]}", source=str(path),
                         line=skip_header + 1)
    return _check_finite(path, data, skip_header)


def polars_module() -> object | None:
    """polars (part of the ``fast`` extra) if installed, else None."""
    try:
        import polars
    except ImportError:
        return None
    return polars


def _read_with_polars(path: Path, ncols: int, delimiter: str | None,
                      skip_header: int) -> NDArray[np.float64] | None:
    """The fast path for large single-character-delimited files (10x numpy's parser).

    Returns None, so that numpy's path reads the file and names the offending line, when
    polars is missing, the file is whitespace-separated (polars needs one separator
    character), or polars finds anything it cannot read as ``ncols`` floats.
    """
    pl: Any = polars_module()
    if pl is None or delimiter is None or len(delimiter) != 1:
        return None
    try:
        frame = pl.read_csv(path, has_header=False, separator=delimiter, skip_rows=skip_header,
                            comment_prefix="#", schema={f"c{i}": pl.Float64 for i in range(ncols)})
    except Exception:  # noqa: BLE001 - any refusal: let numpy find and name the problem
        return None
    if frame.height == 0 or frame.null_count().sum_horizontal().item() > 0:
        return None
    return frame.to_numpy().astype(float, copy=False).reshape(-1, ncols)


def _check_finite(path: Path, data: NDArray[np.float64], skip_header: int) -> NDArray[np.float64]:
    bad = ~np.isfinite(data)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(
            f"column {col + 1} is {data[row, col]}; odometry needs finite numbers "
            "(drop or interpolate the row first)",
            source=str(path), line=_data_line(path, int(row), skip_header),
        )
    return data


def _data_line(path: Path, row: int, skip: int) -> int:
    """File line number of data row ``row`` (blank and comment lines do not count)."""
    seen = -1
    with path.open("r", encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, start=1):
            if lineno <= skip or not raw.strip() or raw.lstrip().startswith("#"):
                continue
            seen += 1
            if seen == row:
                return lineno
    return skip + row + 1


def unwrap_counter(counts: NDArray[np.float64], bits: int) -> NDArray[np.float64]:
    """Undo wrap-around of a ``bits``-bit encoder counter (cumulative counts).

    Each difference is taken modulo 2**bits into [−2**(bits−1), 2**(bits−1)), so the
    counter may move either way (a reversing wheel) by less than half its range per row.

    >>> unwrap_counter(np.array([65530.0, 65535.0, 3.0, 10.0]), 16)
    array([65530., 65535., 65539., 65546.])
    >>> unwrap_counter(np.array([2.0, 0.0, 65534.0]), 16)   # reversing through zero
    array([ 2.,  0., -2.])
    """
    if bits not in (8, 16, 24, 32, 64):
        raise InputError(f"counter width must be 8, 16, 24, 32 or 64 bits, got {bits}")
    span = float(2**bits)
    half = span / 2.0
    steps = np.mod(np.diff(counts) + half, span) - half
    return np.concatenate((counts[:1], counts[0] + np.cumsum(steps)))


def cumulative_to_increments(counts: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cumulative counts -> per-row increments (row 0 gets 0)."""
    return np.concatenate(([0.0], np.diff(counts)))


def order_by_time(t: NDArray[np.float64], source: str) -> NDArray[np.intp] | None:
    """Row order that makes time non-decreasing, or None if it already is.

    Out-of-order rows (e.g. a logger that flushed buffers late) are put back in time
    order with a warning; repeated timestamps are kept (they give zero-length steps).
    """
    if t.size < 2 or np.all(np.diff(t) >= 0):
        return None
    warnings.warn(f"{source}: timestamps are not monotonic; rows were sorted by time",
                  stacklevel=3)
    return np.argsort(t, kind="stable")
