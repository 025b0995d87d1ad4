"""The typer application every command module registers itself on.

It lives apart from :mod:`odomkit.cli` so that a command module imports only this
(typer and nothing else), never the package whose :func:`~odomkit.cli.main` imports the
command modules: that would be an import cycle.
"""

from __future__ import annotations

import typer

__all__ = ["app"]

app = typer.Typer(
    name="odomkit",
    help="Wheeled-robot odometry: dead reckoning, error covariance, Monte Carlo, calibration.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # Plain click help: rich's help renderer costs ~70 ms of imports at every --help
    # (benchmarks/startup.py) and reads "[m]" in a help string as markup and drops it.
    rich_markup_mode=None,
)
