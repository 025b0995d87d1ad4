"""The progress bar of the long commands on a terminal (the display of :mod:`odomkit.progress`).

A command asks :func:`progress_bar` for a :class:`~odomkit.progress.Progress` and hands it to
its workflow. It is a rich bar on **stderr** only when all of these hold:

- stderr is a terminal (``odomkit ... 2> file`` or a pipe shows nothing);
- the command prints no ``--json`` (a machine reads it: nothing extra anywhere);
- ``TERM`` is not ``dumb`` (Emacs shells, some CI consoles), and ``ODOMKIT_NO_PROGRESS`` is
  unset or empty (set it to turn the bar off for good).

Otherwise the command gets :data:`~odomkit.progress.NO_PROGRESS`, and its output is the same
byte for byte. The bar appears only once the command has run for :data:`DELAY` seconds (a
quick command never flickers) and is erased when the command ends; stdout is never touched,
so ``odomkit simulate ... > table.txt`` on a terminal writes the same table. ``NO_COLOR`` is
honoured by rich. rich is imported only when a bar is made: importing a command module
stays light (``tests/cli/test_startup_imports.py``).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import IO, Any

from odomkit.progress import NO_PROGRESS, Progress

__all__ = ["DELAY", "progress_bar", "wants_bar"]

#: Seconds a command runs before its bar appears.
DELAY = 0.5


def wants_bar(json_out: bool, stream: IO[str] | None = None,
              environ: Mapping[str, str] | None = None) -> bool:
    """Whether a command shows a bar (module docstring): ``stream`` (default stderr) is a
    terminal, no ``--json``, ``TERM`` not dumb, ``ODOMKIT_NO_PROGRESS`` unset or empty.

    >>> import io
    >>> wants_bar(False, io.StringIO())
    False
    """
    env = os.environ if environ is None else environ
    if json_out or env.get("ODOMKIT_NO_PROGRESS") or env.get("TERM", "").lower() == "dumb":
        return False
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # a closed or replaced stream
        return False


@contextmanager
def progress_bar(json_out: bool = False, *, delay: float = DELAY) -> Iterator[Progress]:
    """The command's :class:`~odomkit.progress.Progress`: a bar on stderr when
    :func:`wants_bar`, else :data:`~odomkit.progress.NO_PROGRESS`; the bar is stopped and
    erased when the block ends, also by an error (whose one line then stands alone)."""
    if not wants_bar(json_out):
        yield NO_PROGRESS
        return
    bar = _TerminalProgress(delay)
    try:
        yield bar
    finally:
        bar.stop()


class _TerminalProgress:
    """:class:`~odomkit.progress.Progress` as one rich task, replaced at each stage."""

    def __init__(self, delay: float) -> None:
        self._show_at = time.monotonic() + delay
        self._bar: Any = None
        self._task: Any = None

    def _display(self) -> Any:
        if self._bar is None:
            self._bar = _make_bar(self._show_at)
            self._bar.start()
        return self._bar

    def start(self, total: float | None, description: str) -> None:
        bar = self._display()
        if self._task is not None:
            bar.remove_task(self._task)
        self._task = bar.add_task(description, total=total)

    def advance(self, n: float = 1) -> None:
        if self._task is not None:
            self._bar.advance(self._task, n)

    def close(self) -> None:
        if self._task is not None:
            self._bar.remove_task(self._task)
            self._task = None

    def stop(self) -> None:
        if self._bar is not None:
            self._bar.stop()


def _make_bar(show_at: float) -> Any:
    """A transient rich ``Progress`` on stderr that draws nothing before ``show_at``
    (``time.monotonic()``)."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    class Delayed(Progress):
        def get_renderables(self) -> Iterator[Any]:
            if time.monotonic() >= show_at:
                yield from super().get_renderables()

    return Delayed(TextColumn("{task.description}"), BarColumn(), TaskProgressColumn(),
                   MofNCompleteColumn(), TimeElapsedColumn(), TimeRemainingColumn(),
                   console=Console(stderr=True), transient=True,
                   # The commands print their results on stdout: never capture it.
                   redirect_stdout=False, redirect_stderr=False)
