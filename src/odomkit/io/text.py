"""Reading a text file as users have it: plain or gzip-compressed, UTF-8 or an older encoding.

Every text reader of :mod:`odomkit.io` starts here, so that a compressed log, a byte-order
mark, a comment written in Latin-1 or a binary file handed over by mistake behave the same
in every format, and a problem is one line naming the file and line (DESIGN.md, "Text logs").

Decoding rule (decided for issue 10): text is UTF-8 (a leading byte-order mark is dropped).
A log line that is not valid UTF-8 is read as Latin-1, which maps every byte to one
character: such a line can only be a comment or a header written by an older logger (the
column names then read as that logger meant them, e.g. ``vitesse_é``); in a data row the
odd character cannot pass for a number, so the row is refused with its line and column.
Robot files are TOML, which is UTF-8 by definition: there any other byte is an error.
"""

from __future__ import annotations

import codecs
import gzip
import zlib
from pathlib import Path

from odomkit.errors import InputError

__all__ = ["GZIP_MAGIC", "read_text"]

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
