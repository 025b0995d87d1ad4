"""The one exception family of odomkit.

Every error a user can cause by what they give us (a file, a flag, an argument) is an
:class:`OdomkitError`. The CLI prints its message on one line and exits with status 2.
"""

from __future__ import annotations

import re

__all__ = ["InputError", "ModelError", "OdomkitError"]

_LINE_BREAK = re.compile(r"\s*[\r\n]+\s*")


class OdomkitError(Exception):
    """Base class: something the user gave is not what odomkit expects.

    The message is one line by construction: a message that quotes another library's
    multi-line text (a YAML parser's pointer into a corrupt ROS bag's ``metadata.yaml``)
    has its line breaks folded into single spaces, so the CLI's answer stays one line.

    Examples
    --------
    >>> str(OdomkitError("not a readable bag (while scanning\\n  in line 3)"))
    'not a readable bag (while scanning in line 3)'
    """

    def __init__(self, *args: object) -> None:
        if len(args) == 1 and isinstance(args[0], str):
            args = (_LINE_BREAK.sub(" ", args[0].strip()),)
        super().__init__(*args)


class InputError(OdomkitError):
    """A file or log is unreadable or malformed.

    The message names the file, line or field and says what was expected.
    """

    def __init__(self, message: str, *, source: str | None = None, line: int | None = None):
        where = ""
        if source is not None:
            where = f"{source}"
            if line is not None:
                where += f", line {line}"
            where += ": "
        super().__init__(where + message)
        self.source = source
        self.line = line


class ModelError(OdomkitError):
    """A parameter set, noise model or path is invalid (e.g. a negative wheel base)."""
