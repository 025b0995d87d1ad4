"""Reading a text file as users have it: plain or gzip-compressed, UTF-8 or an older encoding,
comma, semicolon, tab or whitespace separated, with or without a header.

Every text reader of :mod:`odomkit.io` starts here, so that a compressed log, a byte-order
mark, a comment written in Latin-1 or a binary file handed over by mistake behave the same
in every format, and a problem is one line naming the file and line
(docs/reference/logs-and-truth.md).
The layout of a table (:func:`sniff_layout`: delimiter, header) and the unit of its time
column (:func:`seconds_per_unit`) are decided here once, for logs and truth files alike.

Decoding rule (decided for issue 10): text is UTF-8 (a leading byte-order mark is dropped).
A log line that is not valid UTF-8 is read as Latin-1, which maps every byte to one
character: such a line can only be a comment or a header written by an older logger (the
column names then read as that logger meant them, e.g. ``vitesse_é``); in a data row the
odd character cannot pass for a number, so the row is refused with its line and column.
Robot files are TOML, which is UTF-8 by definition: there any other byte is an error.
"""

from __future__ import annotations

import codecs
import csv
import gzip
import itertools
import math
import re
import zlib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from odomkit import units
from odomkit.errors import InputError

__all__ = ["check_record_columns", "content_lines", "DELIMITERS", "GZIP_MAGIC", "is_number",
           "mixed_records_at", "read_text", "record_counts", "record_error", "RECORD_FLAGS",
           "seconds_per_unit", "select_record", "sniff_layout", "split_fields", "TextLayout", "TIME_UNITS"]

GZIP_MAGIC = b"\x1f\x8b"
"""The first two bytes of a gzip file (RFC 1952, section 2.3.1)."""


def _line_of(raw: bytes, offset: int) -> int:
    """1-based line number of byte ``offset``."""
    return raw.count(b"\n", 0, offset) + 1


def _decode_lines(raw: bytes) -> str:
    """UTF-8 where a line is valid UTF-8, Latin-1 where it is not (module docstring)."""
    parts = []
    for line in raw.split(b"\n"):
        try:
            parts.append(line.decode("utf-8"))
        except UnicodeDecodeError:
            parts.append(line.decode("latin-1"))
    return "\n".join(parts)


def read_text(path: str | Path, *, compressed: bool = True, strict_utf8: bool = False,
              kind: str = "text table") -> str:
    """The text of a file, decompressed and decoded.

    Parameters
    ----------
    path : the file; gzip is recognised by its first bytes, whatever the file is called.
    compressed : accept a gzip-compressed file (logs: yes; robot files: no).
    strict_utf8 : refuse a byte that is not UTF-8 instead of reading its line as Latin-1.
    kind : what the file should hold, for the messages ("text table", "TOML robot file").

    Returns
    -------
    str
        The whole text, lines separated by ``"\\n"`` (``"\\r\\n"`` is left as it is).

    Raises
    ------
    InputError
        Missing file, damaged gzip, binary data (a NUL byte), or (``strict_utf8``) a byte
        that is not UTF-8; the message names the file and, where it can, the line.
    """
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise InputError("no such file", source=source)
    raw = path.read_bytes()
    if raw.startswith(GZIP_MAGIC):
        if not compressed:
            raise InputError(f"is gzip-compressed; a {kind} is plain text (gunzip it first)",
                             source=source)
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError, zlib.error) as exc:
            raise InputError(f"is a damaged gzip file ({exc})", source=source) from None
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise InputError(f"binary data (a NUL byte), not a {kind}", source=source,
                         line=_line_of(raw, nul))
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        if strict_utf8:
            byte = raw[exc.start:exc.start + 1].hex()
            raise InputError(f"byte 0x{byte} is not UTF-8 text; a {kind} must be saved as UTF-8",
                             source=source, line=_line_of(raw, exc.start)) from None
    return _decode_lines(raw)


# --- what a text table looks like --------------------------------------------------------

DELIMITERS: tuple[str | None, ...] = (",", ";", "\t", None)
"""The field separators a text table may use, tried in this order: comma, semicolon, tab,
and any run of whitespace (None)."""

TIME_UNITS = units.TIME_UNITS
"""Seconds per unit of a time column (``--time-unit``, ``--truth-time-unit``):
:data:`odomkit.units.TIME_UNITS`."""

_NAMES = {",": "comma", ";": "semicolon", "\t": "tab", None: "whitespace"}
# What numpy's parser takes as a float: Python's float() also takes '1_000' and Unicode
# digits, which numpy refuses, so both parsers agree on this grammar.
_NUMBER = re.compile(r"\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)\s*",
                     re.IGNORECASE | re.ASCII)
_DECIMAL_COMMA = re.compile(r"[+-]?\d+,\d+(?:[eE][+-]?\d+)?", re.ASCII)
_SAMPLE = 64  # data lines the delimiter is sniffed from


def is_number(field: str) -> bool:
    """Whether ``field`` is a number as numpy and polars read one (``1.5``, ``-2e-3``,
    ``nan``, ``inf``; not ``1_000``, ``0x1f`` or non-ASCII digits).

    Examples
    --------
    >>> is_number(" 1.5e3 "), is_number("1_000"), is_number("1,5")
    (True, False, False)
    """
    return _NUMBER.fullmatch(field) is not None


def content_lines(text: str) -> Iterator[tuple[int, str]]:
    """(1-based line number, content) of every line that holds something: ``#`` starts a
    comment anywhere on a line (as numpy reads it), blank and comment-only lines are left
    out, and the content is stripped of surrounding whitespace (``\\r`` included)."""
    start, lineno = 0, 0
    while start <= len(text):  # lazily: a log may be long, and only its first lines are sniffed
        end = text.find("\n", start)
        end = len(text) if end < 0 else end
        lineno += 1
        content = text[start:end].split("#", 1)[0].strip()
        if content:
            yield lineno, content
        start = end + 1


def split_fields(content: str, delimiter: str | None) -> list[str]:
    """The fields of one line's content: split at ``delimiter`` (None: any whitespace),
    each stripped."""
    if delimiter is None:
        return content.split()
    return [f.strip() for f in content.split(delimiter)]


def _header_fields(content: str, delimiter: str | None) -> list[str]:
    """Column names: like :func:`split_fields`, but a quoted name (``"left ticks"``) is
    read as the CSV module reads it."""
    if delimiter is None:
        return content.split()
    return [name.strip() for name in next(csv.reader([content], delimiter=delimiter))]


@dataclass(frozen=True)
class TextLayout:
    """How a text table is laid out (:func:`sniff_layout`).

    Parameters
    ----------
    delimiter : {",", ";", "\\t", None}
        The field separator; None is any run of whitespace.
    header : tuple of str, optional
        The column names, or None for a headerless table.
    header_line : int
        1-based line number of the header; 0 without one. Every line up to it (comments
        included) is skipped before the data.
    ncols : int
        Columns of the table (the header's names, or the first data line's fields).
    """

    delimiter: str | None
    header: tuple[str, ...] | None
    header_line: int
    ncols: int

    @property
    def delimiter_name(self) -> str:
        """``"comma"``, ``"semicolon"``, ``"tab"`` or ``"whitespace"``, for messages."""
        return _NAMES[self.delimiter]


def _candidate(sample: list[tuple[int, str]], delimiter: str | None,
               header: bool | None) -> tuple[TextLayout, int, int, int, int]:
    """The layout ``delimiter`` gives the sample; how many data lines it reads as ``ncols``
    numbers (at least two); how many as ``ncols`` fields of any kind (a column that is not
    read may hold text) and how many numbers those lines hold; and how many fields the
    first data line has."""
    first_line, first = sample[0]
    fields = split_fields(first, delimiter)
    has_header = not all(map(is_number, fields)) if header is None else header
    data = sample[1:] if has_header else sample
    names = tuple(_header_fields(first, delimiter)) if has_header else None
    width = len(split_fields(data[0][1], delimiter)) if data else 0
    ncols = len(names) if names is not None else width
    fits = even = numbers = 0
    for _, content in data:
        row = split_fields(content, delimiter)
        if ncols >= 2 and len(row) == ncols:
            even += 1
            count = sum(map(is_number, row))
            numbers += count
            fits += count == ncols
    layout = TextLayout(delimiter, names, first_line if has_header else 0, ncols)
    return layout, fits, even, numbers, width


def _decimal_comma(sample: list[tuple[int, str]], source: str) -> InputError | None:
    """The error for a table of decimal-comma numbers (``1,5;2,25``), or None: some
    non-comma separator splits every sampled line into the same two or more fields, each a
    number or a number with a decimal comma, and at least one has the comma."""
    def numeric(field: str) -> bool:
        return is_number(field) or _DECIMAL_COMMA.fullmatch(field) is not None

    for delimiter in (";", "\t", None):
        rows = [(n, split_fields(c, delimiter)) for n, c in sample]
        data = rows if all(map(numeric, rows[0][1])) else rows[1:]
        if not data or len(data[0][1]) < 2 or any(len(r) != len(data[0][1]) for _, r in data):
            continue
        if not all(numeric(f) for _, r in data for f in r):
            continue
        for lineno, row in data:
            comma = next((f for f in row if _DECIMAL_COMMA.fullmatch(f)), None)
            if comma is not None:
                return InputError(
                    f"{comma!r} has a decimal comma: odomkit reads numbers with a decimal point "
                    f"only (decimal-comma files are not supported); convert the file first, e.g. "
                    f"tr ',' '.' for this {_NAMES[delimiter]}-separated one", source=source,
                    line=lineno)
    return None


def sniff_layout(text: str, source: str, *, header: bool | None = None) -> TextLayout:
    """Find the delimiter and the header of a text table from its first data lines.

    Comment (``#``) and blank lines are skipped. Each separator of :data:`DELIMITERS` is
    tried on the first 64 lines that hold something; the first line is a header when some
    of its fields are not numbers (or as ``header`` says). The first separator that reads
    every sampled data line as the same number (two or more) of numbers wins. When none
    does, the one that reads the most lines so (then: splits the most lines into as many
    fields as the table has columns, as a column of text leaves it doing, with the most
    numbers among them; where none does, splits the first data line into the most fields,
    then the most names) is returned, so that the table reader reads the columns asked for
    or names the line and field that is wrong.

    Parameters
    ----------
    text : the file's text (:func:`read_text`)
    source : the file, for messages
    header : True: the first line is the header whatever it holds (a header of numbers,
        ``0,1,2``, as pandas writes one); False: there is none; None: decide as above

    Raises
    ------
    InputError
        No data at all; one column only; decimal commas (out of scope, said so); a header
        whose names do not match the data's fields in number.

    Examples
    --------
    >>> sniff_layout("# robot 3\\nt;L;R\\n0;0;0\\n0.1;2;3\\n", "log.csv")
    TextLayout(delimiter=';', header=('t', 'L', 'R'), header_line=2, ncols=3)
    >>> sniff_layout("0.0 1 2\\n0.1\\t3   4\\n", "log.txt").delimiter is None
    True
    """
    sample = list(itertools.islice(content_lines(text), _SAMPLE + 1))
    if not sample:
        raise InputError("the file is empty: no data rows", source=source)
    candidates = [_candidate(sample, d, header) for d in DELIMITERS]
    for layout, fits, *_ in candidates:
        data_lines = len(sample) - (layout.header_line > 0)
        if data_lines and fits == data_lines:
            return layout
    problem = _decimal_comma(sample, source)
    if problem is not None:
        raise problem
    # max() keeps the first of equals: the order of DELIMITERS breaks ties. After the lines
    # of numbers, the lines of as many fields as columns count, then their numbers: a column
    # of text (a date, a note) leaves no line all numbers, but its own separator still
    # splits every line alike, and whitespace splitting a date in two gains no number.
    # Only where no separator splits a line so do the most fields decide.
    layout, fits, _, _, width = max(candidates, key=lambda c: (
        c[1], c[2], c[3], 0 if c[2] else c[4], 0 if c[2] else c[0].ncols))
    if layout.ncols < 2 and width < 2:
        raise InputError("one column only: expected columns separated by commas, semicolons, tabs "
                         "or whitespace (t and at least one channel)", source=source,
                         line=sample[0][0])
    if layout.header is not None and not fits and width and width != layout.ncols:
        raise InputError(f"the header has {layout.ncols} name(s) but the next line has {width} "
                         f"{layout.delimiter_name}-separated fields", source=source,
                         line=layout.header_line)
    return layout


# --- tagged records: lines led by a word naming their type --------------------------------
#
# Robot datasets often mix record types in one file, each line led by its type: libRSF's
# ``odom2 t vx vy yaw_rate ...`` beside ``loop t1 t2 score``, CARMEN's ``ODOM x y theta ...``
# beside ``FLASER ...`` and ``TRUEPOS ...``. One type is read by keeping its lines only
# (``--record``, ``--truth-record``); the other lines become comments, so that every line
# keeps its number and every message names the file's own line. The tag is dropped: the
# columns count from the field after it, as the datasets' documentation lists a record's
# fields. Without the flag, a file that mixes types is refused with the types and their
# counts, rather than read as a header and data or failing at the first line of another type.

RECORD_FLAGS = {"log": "--record", "truth": "--truth-record"}
"""The flag that keeps one record type, by the kind of file read ("log", "truth")."""

# The type a message suggests first, by kind of file: the first whose name holds one of these.
_LIKELY = {"log": ("odom",), "truth": ("point", "pos", "gt", "truth")}
# A record's tag is a word: a letter or _ first (a date or a number is data, not a tag).
_TAG = re.compile(r"[A-Za-z_][\w.\-]*", re.ASCII)
_LEAD = re.compile(r"[^\s,;#]+")
_FIELDS = re.compile(r"[\s,;]+")


def _tag_of(content: str) -> str | None:
    """The first field of a line's content when it is a word that can name a record type
    (not a number such as ``nan``), else None."""
    match = _LEAD.match(content)
    word = None if match is None else match.group()
    return word if word is not None and _TAG.fullmatch(word) and not is_number(word) else None


def record_counts(text: str, after: int = 0) -> dict[str, int]:
    """How many lines each record type leads, in the order the types first appear.

    Parameters
    ----------
    text : the file's text (:func:`read_text`)
    after : only lines after this 1-based line number count (a header's)

    Returns
    -------
    dict of str to int
        Record type (a line's first field where it is a word, :func:`select_record`) ->
        number of lines it leads; lines led by a number are not counted.

    Examples
    --------
    >>> record_counts("# libRSF\\nodom2 0 1\\nloop 0 0.1 0.9\\nodom2 0.1 1\\n")
    {'odom2': 2, 'loop': 1}
    """
    counts: dict[str, int] = {}
    for lineno, content in content_lines(text):
        word = None if lineno <= after else _tag_of(content)
        if word is not None:
            counts[word] = counts.get(word, 0) + 1
    return counts


def _listed(counts: dict[str, int]) -> str:
    return ", ".join(f"{word}: {n} line{'' if n == 1 else 's'}" for word, n in counts.items())


def _mixed(counts: dict[str, int], source: str, kind: str) -> InputError:
    likely = next((w for w in counts if any(k in w.lower() for k in _LIKELY[kind])), next(iter(counts)))
    return InputError(f"its lines are tagged records of {len(counts)} types ({_listed(counts)}): keep one "
                      f"with {RECORD_FLAGS[kind]} {likely} (its tag is dropped: the columns count from the "
                      "field after it)", source=source)


def _named_first(sample: list[tuple[int, str]], words: list[str | None]) -> bool:
    """Whether the first of the ``sample`` lines (their record types ``words``) is a header:
    a word leads it and no other line, and none of its other fields is a number (a record
    holds numbers; a header names columns, so a word under it is text, not a type)."""
    first = words[0]
    return first is not None and words.count(first) == 1 and not any(
        map(is_number, _FIELDS.split(sample[0][1])[1:]))


def _check_untagged(text: str, source: str, kind: str) -> None:
    """Refuse a file of several record types read without the flag that keeps one.

    Only the first data lines are looked at unless they look tagged: a word leads two of
    them, or two words lead them (a header's first name aside, :func:`_named_first`).
    """
    sample = list(itertools.islice(content_lines(text), _SAMPLE + 1))
    words = [_tag_of(content) for _, content in sample]
    if not sample or _named_first(sample, words):
        return
    tags = [w for w in words if w is not None]
    if len(set(tags)) < 2 and len(tags) == len(set(tags)):
        return
    counts = record_counts(text)
    if len(counts) > 1:
        raise _mixed(counts, source, kind)


def select_record(text: str, source: str, record: str | None, kind: str = "log") -> str:
    """The text with only the lines of one record type, their tag dropped.

    The one place where both text readers (:mod:`odomkit.io.csvlog`, :mod:`odomkit.io.truth`)
    choose lines by their type. A line is kept when its first field is ``record`` exactly
    (case included), followed by a delimiter (comma, semicolon, tab or spaces) or the end
    of the line; the tag and that delimiter are dropped, so the columns count from the
    field after the tag. Every other line that holds something becomes a comment (``#``),
    so that line numbers stay the file's own; comment and blank lines stay as they are.

    Parameters
    ----------
    text : the file's text (:func:`read_text`)
    source : the file, for messages
    record : the record type to keep (``--record``, ``--truth-record``); None: keep every
        line, but refuse a file whose lines are tagged records of several types
    kind : "log" or "truth": which flag (:data:`RECORD_FLAGS`) the messages name

    Returns
    -------
    str
        The text as the table readers read it: as many lines as ``text``.

    Raises
    ------
    InputError
        ``record`` None and the lines are records of several types (each type with its
        line count, and the flag to give); ``record`` leads no line (naming the types that do).

    Examples
    --------
    >>> select_record("odom2 0 1 2\\nloop 0 1 0.9\\nodom2,0.1,1,2\\n", "f.txt", "odom2")
    '0 1 2\\n#\\n0.1,1,2\\n'
    """
    flag = RECORD_FLAGS[kind]
    if record is None:
        _check_untagged(text, source, kind)
        return text
    word = record.strip()
    if not word or _LEAD.fullmatch(word) is None:
        raise InputError(f"{flag} takes the one word that leads the lines to read (e.g. odom2), "
                         f"got {record!r}")
    tag = re.compile(rf"[ \t]*{re.escape(word)}(?:[ \t]*[,;]|[ \t]+|(?=[\r#]|$))")
    lines = text.split("\n")
    kept = 0
    for i, line in enumerate(lines):
        match = tag.match(line)
        if match is not None:
            lines[i] = line[match.end():]
            kept += 1
        elif line.split("#", 1)[0].strip():
            lines[i] = "#"
    if not kept:
        counts = record_counts(text)
        if not counts:
            raise InputError(f"no line is a {word!r} record: the lines start with numbers, not with a "
                             f"record type (leave out {flag})", source=source)
        near = [w for w in counts if w.lower() == word.lower()]
        said = f"; did you mean {near[0]}? (types match exactly, case included)" if near else ""
        raise InputError(f"no line is a {word!r} record ({flag} {word}); its lines start with "
                         f"{_listed(counts)}{said}", source=source)
    return "\n".join(lines)


def check_record_columns(columns: object, ncols: int, record: str, source: str, kind: str = "log", *,
                         whole: str | None = None, selected: str | None = None,
                         delimiter: str | None = None) -> None:
    """Refuse, saying why, columns for a read of one record type (:func:`select_record`)
    that cannot be meant: a map of header names (the record's lines have no header), or a
    leading ``_`` that counts the tag, which is dropped: one more column than the fields
    after the tag; given the texts, a ``record`` that leads every line of the file (the flag
    then changes nothing but the count; without it the ``_`` skips the tag), or a skipped
    field 1 that advances at every row over :data:`_STANDING` steps in a row where the named
    time (``t``) stands still (a wheel's tick counter read as the clock: a user study's LEGO
    robot log, ``M t left ... right``, tracked 278 poses "over 22.094 s" of left ticks), unless
    field 1 is a message counter (whole steps of 1 as a rule).

    Parameters
    ----------
    columns : the columns as parsed: a sequence of names in order, a mapping of header
        names, or None
    ncols : fields after the tag in the records read
    record : the record type read
    source : the file, for messages
    kind : "log" (``--record``, ``--columns``) or "truth" (``--truth-record``, ``--truth-columns``)
    whole : the file's whole text as read (:func:`read_text`); None: not checked against it
    selected : the text :func:`select_record` made of it, and ``delimiter`` its field separator
        (:class:`TextLayout`); None: the fields are not looked at
    """
    flag, columns_flag = RECORD_FLAGS[kind], {"log": "--columns", "truth": "--truth-columns"}[kind]
    if isinstance(columns, Mapping):
        raise InputError(f"{flag} keeps lines without a header: name the columns in order in {columns_flag}, "
                         "counted from the field after the tag (e.g. t,speed,_,yaw_rate)", source=source)
    if not isinstance(columns, Sequence) or isinstance(columns, str) or not columns or columns[0] != "_":
        return
    shown = list(columns[1:])
    while shown and shown[-1] == "_":
        shown.pop()
    word = record.strip()
    said = f"{flag} {word} drops the tag: {columns_flag} counts from the field after it"
    if len(columns) > ncols:
        raise InputError(f"{said}; leave out the leading _ ({','.join(shown)})", source=source)
    rows = [] if selected is None else [(n, split_fields(c, delimiter)) for n, c in content_lines(selected)]
    if whole is not None and list(record_counts(whole)) == [word]:
        first = ", ".join(fields[0] for _, fields in rows[:3] if fields)
        raise InputError(f"{said}; its leading _ skips field 1 ({first}, ...), not the tag; give "
                         f"{columns_flag} {','.join(shown)}, or leave out {flag} (every line is led by "
                         f"{word}) and keep the _ for the tag", source=source)
    time = list(columns).index("t") if "t" in columns else None
    if time is not None and (standing := _standing_time(rows, time)) is not None:
        a, b = standing
        advance = ", ".join(fields[0] for _, fields in rows[a:a + 4])
        raise InputError(f"{said}; its leading _ skips field 1, which advances ({advance}, ...) over lines "
                         f"{rows[a][0]}-{rows[b][0]}, where t (field {time + 1}) stands still at "
                         f"{rows[a][1][time]}: a counter, not the time. If the _ was meant for the tag, "
                         f"leave out the leading _ ({','.join(shown)})", source=source)


#: Steps in a row over which a named time stands still while the field before it advances
#: (:func:`check_record_columns`): a logger writes a line twice now and then (a LEGO robot's
#: log: 61 of 277 steps, never two in a row), a counter at rest stands for as long as the robot.
_STANDING = 3


def _standing_time(rows: list[tuple[int, list[str]]], time: int) -> tuple[int, int] | None:
    """The first and last row of the first stretch of more than :data:`_STANDING` steps where
    field ``time`` stands still and field 0 advances at every step, in rows whose field 0
    never decreases and is no message counter (every step a whole number, most of them 1);
    None where there is none, or a field is missing or not a number."""
    try:
        pairs = [(float(fields[0]), float(fields[time])) for _, fields in rows
                 if is_number(fields[0]) and is_number(fields[time])]
    except IndexError:
        return None
    if len(pairs) < len(rows) or len(pairs) < _STANDING + 1:
        return None
    steps = [(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(pairs)]
    ones = sum(s == 1 for s, _ in steps)
    if any(s < 0 for s, _ in steps) or (all(s == int(s) for s, _ in steps) and 2 * ones > len(steps)):
        return None
    run = 0
    for i, (ahead, still) in enumerate(steps):
        run = run + 1 if ahead > 0 and still == 0 else 0
        if run >= _STANDING and (i + 1 == len(steps) or not (steps[i + 1][0] > 0 and steps[i + 1][1] == 0)):
            return i + 1 - run, i + 1
    return None


def mixed_records_at(text: str, source: str, line: int | None, kind: str = "log") -> InputError | None:
    """The error of a file of several record types, for a reader that failed at ``line``
    (a column count, a field that is not a number) where that line is led by another
    record type than the data line before it; else None (the reader's own error stands).

    Parameters
    ----------
    text : the file's text as read (:func:`read_text`)
    source : the file, for messages
    line : the 1-based line of the reader's error (None: no line, no answer)
    kind : "log" or "truth" (:data:`RECORD_FLAGS`)
    """
    if line is None:
        return None
    lines = list(itertools.takewhile(lambda item: item[0] <= line, content_lines(text)))
    if len(lines) < 2 or lines[-1][0] != line:
        return None
    at, before = _tag_of(lines[-1][1]), _tag_of(lines[-2][1])
    if at is None or before in (None, at):
        return None
    counts = record_counts(text)
    first = next(iter(counts))
    head = list(itertools.islice(content_lines(text), _SAMPLE + 1))
    if counts[first] == 1 and _named_first(head, [_tag_of(c) for _, c in head]):
        del counts[first]  # a header's first name, not a record type
    return _mixed(counts, source, kind) if len(counts) > 1 else None


def record_error(error: InputError, text: str, record: str | None, kind: str = "log") -> InputError:
    """A text reader's ``error``, said in terms of record types.

    With ``record``, an error at a line of the file says that the columns count from the
    field after the tag (the user may have counted the tag); without, an error at a line
    led by another record type than the line before it becomes the error naming the file's
    types (:func:`mixed_records_at`). Any other error is returned as it is.

    Parameters
    ----------
    error : what the reader raised
    text : the file's whole text as read (:func:`read_text`), before :func:`select_record`
    record : the record type read, or None
    kind : "log" or "truth" (:data:`RECORD_FLAGS`)
    """
    if error.line is None or error.source is None:
        return error
    if record is None:
        return mixed_records_at(text, error.source, error.line, kind) or error
    message = str(error).removeprefix(f"{error.source}, line {error.line}: ")
    if "drops the tag" in message:
        return error
    return InputError(f"{message} ({RECORD_FLAGS[kind]} {record.strip()} drops the tag: column 1 is the "
                      "field after it)", source=error.source, line=error.line)


def seconds_per_unit(unit: str | float, flag: str = "--time-unit") -> float:
    """Seconds per unit of a time column: a unit of :data:`TIME_UNITS` or a positive number
    of seconds (``"1e-4"`` for 100 µs ticks).

    Examples
    --------
    >>> seconds_per_unit("ms"), seconds_per_unit("1e-4"), seconds_per_unit(2.5)
    (0.001, 0.0001, 2.5)
    """
    if isinstance(unit, str) and unit.strip() in TIME_UNITS:
        return TIME_UNITS[unit.strip()]
    try:
        value = float(unit)
    except (TypeError, ValueError):
        value = math.nan
    if isinstance(unit, bool) or not math.isfinite(value) or value <= 0:
        raise InputError(f"{flag} must be one of {', '.join(TIME_UNITS)} or a positive number of "
                         f"seconds per unit (1e-4 for 100 µs ticks), got {unit!r}")
    return value
