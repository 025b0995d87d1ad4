"""The ``odomkit`` command line: each command parses, calls one library function, prints.

Commands live one per module in this package and register themselves on :data:`app`.
User errors (:class:`~odomkit.errors.OdomkitError`) are printed on one line and exit
with status 2, never with a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import click
import typer

from odomkit.errors import OdomkitError

app = typer.Typer(
    name="odomkit",
    help="Wheeled-robot odometry: dead reckoning, error covariance, Monte Carlo, calibration.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return (and, as a console script, exit with) the status code."""
    from odomkit.cli import commands  # noqa: F401  (registers the commands on app)

    args = list(sys.argv[1:] if argv is None else argv)
    try:
        app(args=args, prog_name="odomkit", standalone_mode=False)
    except OdomkitError as exc:
        print(f"odomkit: error: {exc}", file=sys.stderr)
        return _exit(2, argv)
    except click.exceptions.Exit as exc:
        return _exit(exc.exit_code, argv)
    except click.ClickException as exc:
        exc.show()
        return _exit(2, argv)
    except click.Abort:
        print("odomkit: aborted", file=sys.stderr)
        return _exit(1, argv)
    return _exit(0, argv)


def _exit(code: int, argv: Sequence[str] | None) -> int:
    if argv is None:  # running as the console script
        sys.exit(code)
    return code
