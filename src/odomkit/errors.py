"""The one exception family of odomkit.

Every error a user can cause by what they give us (a file, a flag, an argument) is an
:class:`OdomkitError`. The CLI prints its message on one line and exits with status 2.
"""

from __future__ import annotations

__all__ = ["InputError", "ModelError", "OdomkitError"]


class OdomkitError(Exception):
    """Base class: something the user gave is not what odomkit expects."""


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
