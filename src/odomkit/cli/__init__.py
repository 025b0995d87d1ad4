"""The ``odomkit`` command line: each command parses, calls one library function, prints.

Commands live one per module in this package and register themselves on :data:`app`
(:mod:`odomkit.cli.application`). Only the command that runs imports its stack, so that
``--help`` starts fast (``benchmarks/startup.py``).
User errors (:class:`~odomkit.errors.OdomkitError`) are printed on one line and exit
with status 2, never with a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from odomkit.cli.application import app
from odomkit.errors import OdomkitError

__all__ = ["app", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return (and, as a console script, exit with) the status code."""
    from odomkit.cli import commands  # noqa: F401  (registers the commands on app)

    args = list(sys.argv[1:] if argv is None else argv)
    try:
        # Standalone mode lets click report usage errors itself (status 2).
        app(args=args, prog_name="odomkit")
    except OdomkitError as exc:
        print(f"odomkit: error: {exc}", file=sys.stderr)
        return _exit(2, argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        return _exit(code, argv)
    return _exit(0, argv)


def _exit(code: int, argv: Sequence[str] | None) -> int:
    if argv is None:  # running as the console script
        sys.exit(code)
    return code
