"""The ``odomkit`` command line: each command parses, calls one library function, prints.

Commands live one per module in this package and register themselves on :data:`app`
(:mod:`odomkit.cli.application`). Only the command that runs imports its stack, so that
``--help`` starts fast (``benchmarks/startup.py``).
User errors (:class:`~odomkit.errors.OdomkitError`), usage mistakes (an unknown command or
option, a missing argument) and file-system errors are printed on one line and exit with
status 2, never with a traceback.
"""

from __future__ import annotations

import errno
import os
import sys
from collections.abc import Sequence
from typing import Any

import typer

from odomkit.cli.application import app
from odomkit.errors import OdomkitError

__all__ = ["app", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return (and, as a console script, exit with) the status code."""
    from odomkit.cli import commands  # noqa: F401  (registers the commands on app)

    usage_error, click_exception = _click_errors()

    args = list(sys.argv[1:] if argv is None else argv)
    try:
        # Not standalone: usage errors come here, to be printed as one line like all others.
        code = app(args=args, prog_name="odomkit", standalone_mode=False)
    except OdomkitError as exc:
        return _error(str(exc), argv)
    except usage_error as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            # A bare ``odomkit`` asks for the help: give it as ``--help`` does (stdout, exit 0),
            # not as an error (click shows it on stderr with exit 2).
            if exc.ctx is not None:
                print(exc.ctx.get_help())
            return _exit(0, argv)
        return _error(_usage_message(exc, args), argv)
    except click_exception as exc:
        return _error(" ".join(exc.format_message().split()), argv, exc.exit_code)
    except typer.Abort:
        return _error("aborted", argv, 1)
    except OSError as exc:
        if exc.errno == errno.EPIPE:  # the reader of stdout went away (``| head``)
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115  (so the exit flush is quiet)
            return _exit(1, argv)
        where = f"{exc.filename}: " if exc.filename else ""
        return _error(f"{where}{exc.strerror or exc}", argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        return _exit(code, argv)
    return _exit(code if isinstance(code, int) else 0, argv)


def _click_errors() -> tuple[type[Any], type[Any]]:
    """Click's ``UsageError`` and ``ClickException`` as typer raises them (typer 0.27 has its
    own copy of click, so ``import click`` would name other classes)."""
    mro = {cls.__name__: cls for cls in typer.BadParameter.__mro__}
    return mro["UsageError"], mro["ClickException"]


def _usage_message(exc: Any, args: Sequence[str]) -> str:
    """Click's usage error as one line: its message, then the commands (for an unknown
    command) or where the help is."""
    text = " ".join(exc.format_message().split()).rstrip(".")
    text = text[:1].lower() + text[1:]
    ctx = exc.ctx
    if ctx is None:  # click names no command for some parse errors: the first argument does
        prog = f"odomkit {args[0]}" if args and args[0] in _app_commands() else "odomkit"
        return f"{text} (see '{prog} --help')"
    if text.startswith("no such command") and hasattr(ctx.command, "list_commands"):
        return f"{text}; commands: {', '.join(ctx.command.list_commands(ctx))}"
    return f"{text} (see '{ctx.command_path} --help')"


def _app_commands() -> list[str]:
    """The names of the registered commands."""
    return sorted(c.name or c.callback.__name__ for c in app.registered_commands if c.callback)


def _error(message: str, argv: Sequence[str] | None, code: int = 2) -> int:
    print(f"odomkit: error: {message}", file=sys.stderr)
    return _exit(code, argv)


def _exit(code: int, argv: Sequence[str] | None) -> int:
    if argv is None:  # running as the console script
        sys.exit(code)
    return code
