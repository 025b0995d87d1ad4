"""What the log and truth readers say about a table's column names and its time column.

A logger's header is written by hand or by a tool (``Speed (MPH)``, ``Latitude / Y Position
(Degrees)``, a wall-clock ``Time`` beside ``Seconds``), and users retype those names in
``--columns`` and ``--truth-columns``. Both readers (:mod:`odomkit.io.csvlog`,
:mod:`odomkit.io.truth`) answer a name that misses the header, and a time column that holds
date or clock text, with the same words, here.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from odomkit.io.text import is_number

__all__ = ["clock_text", "no_such_column", "time_like", "time_text_error"]

# A calendar date (2018-04-08, 2018/04/08, 08.04.2018) and a time of day (10:31:37.005628).
_DATE = r"\d{4}[-/.]\d{1,2}[-/.]\d{1,2}|\d{1,2}[-/.]\d{1,2}[-/.]\d{2,4}"
_CLOCK = r"\d{1,2}:\d{2}(?::\d{2})?(?:[.,]\d+)?(?:\s*[AaPp][Mm])?"
_ZONE = r"(?:\s*(?:Z|[+-]\d{2}:?\d{2}|[A-Z]{2,5}))?"
_DATE_TIME = re.compile(rf"(?:{_DATE})(?:[ T_]+{_CLOCK})?{_ZONE}")
_TIME_OF_DAY = re.compile(rf"{_CLOCK}{_ZONE}")


def _folded(name: str) -> str:
    """A name without its case and spacing (``"Speed (MPH)"`` and ``"speed(mph)"`` fold alike)."""
    return "".join(name.split()).casefold()


def no_such_column(name: str, header: Sequence[str], flag: str, key: str, whose: str) -> str:
    """The message for a ``flag`` item ``key=name`` that names no column of ``header``, in
    ``whose`` file ("the log", "the truth file"): with the header's own spelling where a name
    differs from it only in case or spacing (a header name is matched exactly).

    Examples
    --------
    >>> no_such_column("Speed (mph)", ["t", "Speed (MPH)"], "--columns", "speed_mph", "the log")
    "--columns speed_mph=Speed (mph): the log has no column named 'Speed (mph)' in its header; did \
you mean 'Speed (MPH)'? (names match exactly, case and spaces included; it has ['t', 'Speed (MPH)'])"
    """
    near = [h for h in header if _folded(h) == _folded(name)]
    shown = f"it has {list(header)}"
    said = f"{flag} {key}={name}: {whose} has no column named {name!r} in its header"
    if near:
        return (f"{said}; did you mean {' or '.join(map(repr, near))}? (names match exactly, case and "
                f"spaces included; {shown})")
    return f"{said} ({shown})"


def time_like(name: str) -> bool:
    """Whether a header name may hold a time (``Seconds``, ``time_s``, ``Timestamp (ns)``).

    Examples
    --------
    >>> [time_like(n) for n in ("Seconds", "time_s", "Engine RPM", "stamp")]
    [True, True, False, True]
    """
    words = set(re.findall(r"[a-z]+", name.lower()))
    return "time" in name.lower() or "stamp" in name.lower() or bool(
        words & {"t", "sec", "secs", "second", "seconds"})


def clock_text(field: str) -> str | None:
    """What a time field that is not a number holds: ``"date and time text"``, ``"date
    text"`` or ``"time-of-day text"``; None for anything else.

    Examples
    --------
    >>> clock_text("2018-04-08 10:31:37.005628"), clock_text("10:31:37"), clock_text("fast")
    ('date and time text', 'time-of-day text', None)
    """
    field = field.strip().strip("\"'")
    if is_number(field):
        return None
    if _DATE_TIME.fullmatch(field):
        return "date and time text" if ":" in field else "date text"
    if _TIME_OF_DAY.fullmatch(field):
        return "time-of-day text"
    return None


def time_text_error(field: str, row: Sequence[str], header: Sequence[str] | None, column: int,
                    flag: str, unit_flag: str, others: dict[str, int] | None = None) -> str | None:
    """The message for a time column (``column``, 0-based) whose first data ``row`` holds
    ``field``, date or clock text rather than a number: it says so and names the header's
    other columns that look like a time (:func:`time_like`) and hold a number in that row,
    to map as t with ``flag`` (``--columns``, ``--truth-columns``); None where ``field`` is
    no date or clock text (the reader's own "is not a number" then stands).

    ``others`` (name -> column index of the other columns read) is for a reader that chose
    the columns itself (from the header's names) or was given them in order: the hint then
    maps them all, as ``flag`` must; without it the user's own map needs only t changed."""
    kind = clock_text(field)
    if kind is None:
        return None
    said = (f"column {column + 1}{'' if header is None else f' ({header[column]!r})'}, read as the time t: "
            f"{field!r} is {kind}, not a number (t is seconds, or {unit_flag}'s unit)")
    numeric = [] if header is None else [
        name for i, name in enumerate(header)
        if i != column and i < len(row) and time_like(name) and is_number(row[i])]
    if numeric:
        assert header is not None
        how = (f"as t={numeric[0]} in {flag}" if others is None else f"with {flag} " + ",".join(
            [f"t={numeric[0]}", *(f"{k}={header[i]}" for k, i in others.items() if k != "t")]))
        return (f"{said}; the header's numeric time column{'s are' if len(numeric) > 1 else ' is'} "
                f"{', '.join(map(repr, numeric))}: map {'one' if len(numeric) > 1 else 'it'} {how}")
    return (f"{said}; give the times as seconds in a column of their own (e.g. seconds since the first "
            f"row) and map that as t in {flag}")
