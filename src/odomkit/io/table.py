"""Reading numeric text tables with errors that name the file, line and column.

The text comes from :func:`odomkit.io.text.read_text` (plain or gzip). Two parsers read it
and give the same numbers and the same messages: polars (the ``fast`` extra, 10x faster on
large single-character-delimited files) when it accepts the whole table, numpy otherwise.
Counter columns can be read as exact 64-bit integers (:meth:`NumericTable.counter`), so
that a 64-bit encoder count keeps its low bits (a float64 holds 2**63 only to ±1024).

Only the columns asked for (``usecols``) are read as numbers; the others may hold anything
(a wall-clock date, a gear name, nothing), but every row must still have every column: a
delimiter inside a text field would shift the numbers after it into the wrong columns.
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError
from odomkit.io.text import is_number, read_text

__all__ = [
    "check_time_order", "COUNTER_BITS", "counter_increments", "cumulative_to_increments", "NumericTable",
    "polars_module", "read_numeric", "read_table", "to_seconds", "unwrap_counter", "warn_if_cumulative",
]

COUNTER_BITS = (8, 16, 24, 32, 64)
"""Counter widths whose wrap-around can be undone."""

# Leading blanks of a line that holds only a comment or blanks (the line itself stays, so
# that line numbers hold).
_INDENTED_EMPTY = re.compile(r"^[ \t]+(?=#|\r?$)", re.MULTILINE)
# A column that only ever grows is flagged when it takes at least this many distinct values
# (and 1 % of the rows): fewer could be increments that merely rose during a short log.
_MIN_DISTINCT = 16


def _fields(line: str, delimiter: str | None) -> list[str] | None:
    """The fields of a data line, or None for a blank or comment line (as numpy sees them:
    ``#`` starts a comment anywhere on a line)."""
    content = line.split("#", 1)[0]
    if not content.strip():
        return None
    return content.strip().split(delimiter) if delimiter else content.split()


@dataclass(frozen=True)
class NumericTable:
    """A numeric text table as read, with what is needed to name the line of a row.

    Parameters
    ----------
    values : ndarray, shape (N, len(columns))
        The fields of the columns read, as float64 (:meth:`column` finds one by its place
        in the file).
    integers : mapping of int to ndarray of int64, shape (N,)
        Exact integers of the requested columns (0-based, as in the file) that hold
        integers only; a count at or above 2**63 is kept modulo 2**64 (two's complement),
        which is all that differencing and unwrapping need.
    source : str
        The file, for messages.
    columns : tuple of int
        The file's column (0-based) of each column of ``values``, increasing.
    """

    values: NDArray[np.float64]
    integers: Mapping[int, NDArray[np.int64]]
    source: str
    _text: str = field(repr=False)  # the file's text, read again only to name a line
    _skip: int = field(repr=False)
    columns: tuple[int, ...]

    def column(self, column: int) -> NDArray[np.float64]:
        """The values of file column ``column`` (0-based), shape (N,); it must have been read."""
        if column not in self.columns:
            raise ValueError(f"column {column} was not read (read: {self.columns})")
        return self.values[:, self.columns.index(column)]

    def line(self, row: int) -> int:
        """File line number of data row ``row`` (blank and comment lines do not count)."""
        seen = -1
        for lineno, raw in enumerate(self._text.split("\n"), start=1):
            if lineno <= self._skip or _fields(raw, None) is None:
                continue
            seen += 1
            if seen == row:
                return lineno
        return self._skip + row + 1

    def counter(self, column: int, bits: int | None = None) -> NDArray[np.int64] | NDArray[np.float64]:
        """Column ``column`` (0-based) as cumulative counts: exact int64 when it holds
        integers (written as such, or as integral floats below 2**53), else float64.

        With ``bits`` (the counter width, :data:`COUNTER_BITS`) the counts must be integers
        that fit a counter of that width, signed or unsigned; else one error naming the line.
        """
        counts = self.integers.get(column)
        if counts is None:
            column_values = self.column(column)
            whole = np.abs(column_values) <= 2.0**53
            whole &= column_values == np.round(column_values)
            if whole.all():
                counts = column_values.astype(np.int64)
            elif bits is not None:
                row = int(np.argmin(whole))
                raise InputError(
                    f"column {column + 1} holds {column_values[row]!r}, not an integer count; "
                    "--wrap-bits unwraps integer counters", source=self.source, line=self.line(row))
            else:
                return column_values
        if bits is not None and bits < 64:
            bad = (counts < -(2 ** (bits - 1))) | (counts >= 2**bits)
            if bad.any():
                row = int(np.argmax(bad))
                raise InputError(
                    f"column {column + 1} holds the count {counts[row]}, beyond a {bits}-bit "
                    f"counter ({-(2 ** (bits - 1))} .. {2**bits - 1}); check --wrap-bits",
                    source=self.source, line=self.line(row))
        return counts


def read_table(
    path: str | Path, ncols: int, delimiter: str | None = None, skip_header: int = 0, *,
    integer_columns: Sequence[int] = (), text: str | None = None, usecols: Sequence[int] | None = None,
) -> NumericTable:
    """Read a table of ``ncols`` columns, the ones in ``usecols`` as numbers; reject missing
    files, ragged rows, and text or NaN in a column read.

    Parameters
    ----------
    path : path to a text file, plain or gzip-compressed (:func:`odomkit.io.text.read_text`)
    ncols : number of columns every row must have
    delimiter : None for any whitespace, else e.g. ","
    skip_header : lines to skip at the top
    integer_columns : columns (0-based) to read also as exact integers where they hold them
        (they are read whether or not ``usecols`` names them)
    text : the file's text if the caller has read it already
    usecols : columns (0-based) to read as numbers; None: all. The others may hold text or
        nothing: a table of numbers only is read whole (the fast path, which also checks
        every row's field count), any other by these columns only, and its field counts
        checked after.

    Returns
    -------
    NumericTable
        ``values`` of shape (N, number of columns read), in file order (:meth:`NumericTable.column`).
    """
    source = str(path)
    used = tuple(range(ncols)) if usecols is None else tuple(sorted({*usecols, *integer_columns}))
    if not used or used[0] < 0 or used[-1] >= ncols:
        raise ValueError(f"usecols {usecols} must name columns 0 .. {ncols - 1}")
    if text is None:
        text = read_text(path)
    body = text.split("\n", skip_header)[-1] if skip_header else text
    if skip_header and text.count("\n") < skip_header:
        body = ""
    if _INDENTED_EMPTY.search(body):
        # numpy and polars take '  # note' or '   ' for a row when a delimiter is set
        body = _INDENTED_EMPTY.sub("", body)
    # First as a table of numbers only (the fast path of a numeric file, which also checks
    # that every row has every column), then, if some other column holds text, its columns
    # ``used`` only.
    every = tuple(range(ncols))
    found = _read_with_polars(body, ncols, delimiter, integer_columns, every)
    whole = found is not None
    if found is None and used != every:
        found = _read_with_polars(body, ncols, delimiter, integer_columns, used)
    if found is None:
        found, whole = _read_with_numpy(body, ncols, delimiter, integer_columns, source, text,
                                        skip_header, used)
    values, integers = found
    if used != every and whole:
        values = values[:, used]
    elif used != every:
        # Neither parser looked at the other columns, so neither checked that each row has
        # them all: a delimiter inside a text field would shift the numbers after it.
        ragged = _first_bad_line(text, ncols, delimiter, skip_header, source, used=())
        if ragged is not None:
            raise ragged
    table = NumericTable(values, integers, source, text, skip_header, used)
    _check_finite(table)
    return table


def read_numeric(
    path: str | Path, ncols: int, delimiter: str | None = None, skip_header: int = 0
) -> NDArray[np.float64]:
    """The float64 values of :func:`read_table`, shape (N, ncols)."""
    return read_table(path, ncols, delimiter, skip_header).values


def polars_module() -> object | None:
    """polars (part of the ``fast`` extra) if installed, else None."""
    try:
        import polars
    except ImportError:
        return None
    return polars


_Parsed = tuple[NDArray[np.float64], dict[int, NDArray[np.int64]]]


def _read_with_polars(body: str, ncols: int, delimiter: str | None,
                      integer_columns: Sequence[int], used: Sequence[int]) -> _Parsed | None:
    """The fast path. Returns None, so that numpy's path reads the text and names the
    offending line, when polars is missing, the table is whitespace-separated (polars needs
    one separator character), or polars finds anything it cannot read as numbers in the
    columns ``used`` (integers in ``integer_columns``: a count written as ``12.0`` or above
    2**63 is left to numpy, whose rules then decide alike for both paths). The other
    columns are typed as text and not read."""
    pl: Any = polars_module()
    if pl is None or delimiter is None or len(delimiter) != 1:
        return None
    schema = {f"c{i}": pl.Int64 if i in integer_columns else pl.Float64 if i in used else pl.String
              for i in range(ncols)}
    # With text columns, quotes are plain characters, as they are to numpy: a quoted text
    # field could otherwise swallow the delimiters and line ends up to the next quote.
    options = {} if len(used) == ncols else {"columns": list(used), "quote_char": None}
    try:
        frame = pl.read_csv(body.encode(), has_header=False, separator=delimiter,
                            comment_prefix="#", schema=schema, **options)
    except Exception:  # noqa: BLE001 - any refusal: let numpy find and name the problem
        return None
    if frame.height == 0 or frame.null_count().sum_horizontal().item() > 0:
        return None
    integers = {i: frame[f"c{i}"].to_numpy().astype(np.int64, copy=False) for i in integer_columns}
    values = frame.select(pl.all().cast(pl.Float64)).to_numpy().astype(float, copy=False)
    return values.reshape(-1, len(used)), integers


def _loadtxt(body: str, delimiter: str | None, usecols: Sequence[int] | None,
             source: str) -> NDArray[np.float64]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warns on an empty file
            return np.loadtxt(io.StringIO(body), delimiter=delimiter, ndmin=2, dtype=float,
                              comments="#", usecols=usecols)
    except UserWarning:
        raise InputError("the file is empty: no data rows", source=source) from None


def _read_with_numpy(body: str, ncols: int, delimiter: str | None, integer_columns: Sequence[int],
                     source: str, text: str, skip: int,
                     used: Sequence[int]) -> tuple[_Parsed, bool]:
    """The table read by numpy: every column if all are numbers, else the columns ``used``;
    and whether every column was read (so that numpy checked each row's field count)."""
    whole = True
    try:
        try:
            data = _loadtxt(body, delimiter, None, source)
        except ValueError:
            if len(used) == ncols:
                raise
            whole = False  # perhaps a column not read holds text: read the others
            data = _loadtxt(body, delimiter, used, source)
    except ValueError as exc:
        raise (_first_bad_line(text, ncols, delimiter, skip, source, used)
               or InputError(f"could not be read as a numeric table ({exc})", source=source)) from None
    if data.size == 0:
        raise InputError("the file is empty: no data rows", source=source)
    if whole and data.shape[1] != ncols:
        raise InputError(f"expected {ncols} columns, found {data.shape[1]}", source=source,
                         line=skip + 1)
    integers = {}
    for col in integer_columns:
        exact = _exact_integers(body, delimiter, col)
        if exact is not None:
            integers[col] = exact
    return (data, integers), whole


def _exact_integers(body: str, delimiter: str | None, col: int) -> NDArray[np.int64] | None:
    """Column ``col`` parsed as int64 (or uint64 seen as int64 modulo 2**64), or None if
    some field is not an integer (``12.0``, ``1e3``) or the column mixes counts above
    2**63 with negative ones."""
    for dtype in (np.int64, np.uint64):
        try:
            column = np.loadtxt(io.StringIO(body), delimiter=delimiter, usecols=(col,),
                                dtype=dtype, comments="#", ndmin=1)
        except (ValueError, OverflowError):
            continue
        return column.view(np.int64)
    return None


def _first_bad_line(text: str, ncols: int, delimiter: str | None, skip: int, source: str,
                    used: Sequence[int]) -> InputError | None:
    """Re-scan a table to say exactly where and why it cannot be read: the error for the
    first line without ``ncols`` fields or with a field in a column of ``used`` that is not
    a number; None if there is none."""
    for lineno, raw in enumerate(text.split("\n"), start=1):
        fields = None if lineno <= skip else _fields(raw, delimiter)
        if fields is None:
            continue
        if len(fields) != ncols:
            return InputError(f"expected {ncols} columns, found {len(fields)}",
                              source=source, line=lineno)
        for col in used:
            if not is_number(fields[col]):
                return InputError(f"column {col + 1}: {fields[col].strip()!r} is not a number",
                                  source=source, line=lineno)
    return None


def _check_finite(table: NumericTable) -> None:
    bad = ~np.isfinite(table.values)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise InputError(
            f"column {table.columns[col] + 1} is {table.values[row, col]}; odometry needs finite numbers "
            "(drop or interpolate the row first)",
            source=table.source, line=table.line(int(row)),
        )


def _wrapped_steps(counts: NDArray[np.int64], bits: int | None) -> NDArray[np.int64]:
    """Exact steps of an integer counter: each difference taken modulo 2**bits into
    [−2**(bits−1), 2**(bits−1)). int64 arithmetic wraps modulo 2**64, a multiple of
    2**bits, so the result is exact even where an intermediate sum wraps (and for
    ``bits`` = 64 the wrapped difference is the answer)."""
    with np.errstate(over="ignore"):
        steps = np.diff(counts)
        if bits is None or bits == 64:
            return steps
        span = np.int64(1) << np.int64(bits)
        half = span >> np.int64(1)
        return (steps + half) % span - half


def _check_bits(bits: int) -> None:
    if bits not in COUNTER_BITS:
        raise InputError(f"counter width must be 8, 16, 24, 32 or 64 bits, got {bits}")


def unwrap_counter(counts: NDArray[Any], bits: int) -> NDArray[Any]:
    """Undo wrap-around of a ``bits``-bit encoder counter (cumulative counts).

    Each difference is taken modulo 2**bits into [−2**(bits−1), 2**(bits−1)), so the
    counter may move either way (a reversing wheel) by less than half its range per row.
    Integer counts are unwrapped exactly (int64, modulo 2**64); float counts in float64
    (exact below 2**53).

    Examples
    --------
    >>> unwrap_counter(np.array([65530.0, 65535.0, 3.0, 10.0]), 16)
    array([65530., 65535., 65539., 65546.])
    >>> unwrap_counter(np.array([2, 0, 65534]), 16)   # reversing through zero
    array([ 2,  0, -2])
    """
    _check_bits(bits)
    if counts.dtype.kind in "iu":
        ints = counts.view(np.int64) if counts.dtype == np.uint64 else counts.astype(np.int64)
        with np.errstate(over="ignore"):
            return np.concatenate((ints[:1], ints[0] + np.cumsum(_wrapped_steps(ints, bits))))
    span = float(2**bits)
    half = span / 2.0
    steps = np.mod(np.diff(counts) + half, span) - half
    return np.concatenate((counts[:1], counts[0] + np.cumsum(steps)))


def counter_increments(counts: NDArray[Any], bits: int | None = None) -> NDArray[np.float64]:
    """Cumulative counts -> per-row increments [count] as float64 (row 0 gets 0).

    Integer counts (:meth:`NumericTable.counter`) are differenced, and unwrapped if
    ``bits`` is given, in exact integer arithmetic before the conversion to float.

    Examples
    --------
    >>> counter_increments(np.array([2**63 - 2, -(2**63) + 3]), 64).tolist()
    [0.0, 5.0]
    """
    if bits is not None:
        _check_bits(bits)
    if counts.dtype.kind in "iu":
        ints = counts.view(np.int64) if counts.dtype == np.uint64 else counts.astype(np.int64)
        return np.concatenate(([0.0], _wrapped_steps(ints, bits).astype(float)))
    if bits is not None:
        counts = unwrap_counter(counts, bits)
    return cumulative_to_increments(counts)


def cumulative_to_increments(counts: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cumulative counts -> per-row increments (row 0 gets 0)."""
    return np.concatenate(([0.0], np.diff(counts)))


def warn_if_cumulative(values: NDArray[np.float64], source: str, column: str) -> None:
    """Warn when an increment channel looks like a cumulative counter read as increments.

    A column that never decreases over the whole log and takes many distinct values (at
    least 16, and 1 % of the rows) is how a counter looks; increments of a real wheel
    jitter up and down (a result that could silently be wrong is a warning, never silent).
    ``column`` names it in the message, e.g. ``"column 'L' (ticks_left)"``.
    """
    if values.size < _MIN_DISTINCT:
        return
    steps = np.diff(values)
    if np.any(steps < 0):
        return
    distinct = int(np.count_nonzero(steps)) + 1
    if distinct >= max(_MIN_DISTINCT, values.size // 100):
        warnings.warn(
            f"{source}: {column} never decreases over its {values.size} rows ({distinct} "
            "distinct values): it looks like a cumulative counter read as increments; "
            "pass --cumulative if it is one", UserWarning, stacklevel=3)


def check_time_order(t: NDArray[np.float64], table: NumericTable) -> None:
    """Refuse a time column that decreases, naming the line; repeated times are kept (they
    give zero-length steps).

    A row earlier than the one before it is a logger's clock jumping back or rows written
    out of order; sorting would hide either, so the user decides
    (docs/reference/logs-and-truth.md, "Log options").
    ``t`` is the column as read (row ``k`` of ``table``), in the file's own unit.
    """
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        row = int(back[0]) + 1
        raise InputError(
            f"time {float(t[row])!r} is earlier than {float(t[row - 1])!r} on line "
            f"{table.line(row - 1)}: timestamps must not decrease ({back.size} row(s) do; repeated "
            "ones are kept as zero-length steps); sort the rows by time or fix the logger's clock",
            source=table.source, line=table.line(row))


def to_seconds(t: NDArray[np.float64], seconds_per_unit: float) -> NDArray[np.float64]:
    """A time column in seconds.

    Where the unit is 1/n s for a whole n (ms, µs, ns), the column is divided by n rather
    than multiplied by the inexact 1/n: IEEE 754 division is correctly rounded, so a time
    whose value in the file's unit is an exact double (any whole number below 2**53, e.g.
    ns stamps of a day) gives the same double as the same time written in seconds.

    Examples
    --------
    >>> bool(to_seconds(np.array([1234567891.0]), 1e-9)[0] == float("1.234567891"))
    True
    """
    n = round(1.0 / seconds_per_unit)
    if n >= 2 and 1.0 / n == seconds_per_unit:
        return t / float(n)
    return t * seconds_per_unit
