"""Reading a log in any supported format: the log options every log-reading command shares
(``track``, ``calibrate``, ``calibrate-noise``, ``umbmark --runs``)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from odomkit.errors import InputError
from odomkit.io.csvlog import parse_column_map, read_csv_log
from odomkit.io.halmstad import read_khepera, read_snowhite
from odomkit.io.optiodom import read_run
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive, Robot

__all__ = ["LOG_FORMATS", "LogOptions", "detect_format", "load_log"]

LOG_FORMATS = ("auto", "csv", "khepera", "snowhite", "optiodom")


def detect_format(path: Path) -> str:
    """Guess a log format from its file name.

    >>> detect_format(Path("230620202042_run-01.csv")), detect_format(Path("log.csv"))
    ('optiodom', 'csv')
    """
    name = path.name.lower()
    if name.startswith("snowhite"):
        return "snowhite"
    if name.startswith("khepera"):
        return "khepera"
    if re.search(r"_run-\d+\.csv$", name):
        return "optiodom"
    return "csv"


@dataclass(frozen=True)
class LogOptions:
    """How to read a log (see ``odomkit track --help``)."""

    format: str = "auto"
    columns: str | None = None
    cumulative: bool = False
    wrap_bits: int | None = None
    period: float | None = None
    time_scale: float = 1.0


def load_log(path: str | Path, robot: Robot, options: LogOptions = LogOptions()) -> OdometryLog:
    """Read a log in any supported format."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    fmt = detect_format(path) if options.format == "auto" else options.format
    if fmt not in LOG_FORMATS:
        raise InputError(f"unknown log format {fmt!r}; expected one of {', '.join(LOG_FORMATS)}")
    if fmt == "khepera":
        return read_khepera(path, period=options.period or 1.0, wrap_bits=options.wrap_bits)
    if fmt == "snowhite":
        return read_snowhite(path, **({"period": options.period} if options.period else {}))
    if fmt == "optiodom":
        return read_run(path, "diff" if isinstance(robot, DiffDrive) else "tricyc")
    if not options.columns:
        raise InputError("a CSV log needs --columns, e.g. t=time,ticks_left=L,ticks_right=R",
                         source=str(path))
    return read_csv_log(path, parse_column_map(options.columns), cumulative=options.cumulative,
                        wrap_bits=options.wrap_bits, time_scale=options.time_scale)
