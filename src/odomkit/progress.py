"""Progress of long computations: the small protocol the core reports to, and no display.

A long function (a Monte Carlo simulation, a log of millions of rows, a fit over many logs)
takes ``progress: Progress = NO_PROGRESS`` and reports its work in *stages*, one after the
other:

- ``start(total, description)`` opens a stage of ``total`` units (blocks of runs, rows,
  logs; None when the amount is unknown, e.g. a text file read at once);
- ``advance(n)`` says that n more units are done;
- ``close()`` ends the stage (also when the work fails: use :func:`stage`).

The units are whole blocks, chunks or logs, never single samples, so that reporting costs
nothing beside the work; and progress only observes, so every number is the same with or
without it. A function that has a stage open passes :data:`NO_PROGRESS` to the functions it
calls, so stages never nest. The calls come from the thread that called the function.

The command line shows a bar on a terminal (:mod:`odomkit.cli.progress`, with rich); a
library user passes any object with these three methods, e.g. :class:`RecordingProgress`:

>>> from odomkit.noise import WheelNoise
>>> from odomkit.path import Arc
>>> from odomkit.simulate import simulate_runs
>>> seen = RecordingProgress()
>>> _ = simulate_runs([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=1000, partitions=10,
...                   seed=1, workers=1, progress=seen)
>>> seen.stages
[Stage(description='Monte Carlo runs', total=1000, done=1000, advances=4, closed=True)]
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

__all__ = ["NO_PROGRESS", "NoProgress", "Progress", "RecordingProgress", "Stage", "stage"]


@runtime_checkable
class Progress(Protocol):
    """What a long computation reports to (module docstring: stages, units, threads)."""

    def start(self, total: float | None, description: str) -> None:
        """Open a stage of ``total`` units (None: unknown), shown as ``description``."""

    def advance(self, n: float = 1) -> None:
        """``n`` more units of the open stage are done."""

    def close(self) -> None:
        """End the open stage."""


class NoProgress:
    """The :class:`Progress` that shows nothing: every call returns at once (the default)."""

    def start(self, total: float | None, description: str) -> None:
        """Nothing to show."""

    def advance(self, n: float = 1) -> None:
        """Nothing to show."""

    def close(self) -> None:
        """Nothing to show."""

    def __repr__(self) -> str:
        return "NO_PROGRESS"


#: The default of every ``progress`` parameter.
NO_PROGRESS: Progress = NoProgress()


@contextmanager
def stage(progress: Progress, total: float | None, description: str) -> Iterator[Progress]:
    """``progress.start(total, description)``, the block, then ``progress.close()`` (also
    when the block raises).

    >>> seen = RecordingProgress()
    >>> with stage(seen, 3, "logs") as p:
    ...     for _ in range(3):
    ...         p.advance()
    >>> seen.stages[0].done, seen.stages[0].closed
    (3, True)
    """
    progress.start(total, description)
    try:
        yield progress
    finally:
        progress.close()


@dataclass
class Stage:
    """One stage as :class:`RecordingProgress` saw it.

    Attributes
    ----------
    description : str
    total : float or None
        Units announced by ``start`` (None: unknown).
    done : float
        Sum of the ``advance`` calls.
    advances : int
        Number of ``advance`` calls.
    closed : bool
        ``close`` was called.
    """

    description: str
    total: float | None
    done: float = 0
    advances: int = 0
    closed: bool = False


@dataclass
class RecordingProgress:
    """A :class:`Progress` that keeps what it is told, stage by stage (for tests, logs and
    anyone who wants the numbers rather than a bar)."""

    stages: list[Stage] = field(default_factory=list)

    def start(self, total: float | None, description: str) -> None:
        """Open a new stage (the previous one stays as it was left)."""
        self.stages.append(Stage(description, total))

    def advance(self, n: float = 1) -> None:
        """Add ``n`` to the open stage."""
        if not self.stages or self.stages[-1].closed:
            raise RuntimeError("advance() without an open stage: call start() first")
        self.stages[-1].done += n
        self.stages[-1].advances += 1

    def close(self) -> None:
        """Mark the open stage closed."""
        if not self.stages or self.stages[-1].closed:
            raise RuntimeError("close() without an open stage: call start() first")
        self.stages[-1].closed = True
