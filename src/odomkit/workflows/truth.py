"""The truth options every truth-taking command shares (``track``, ``evaluate``, ``fit-noise``):
a truth file, or the log's own ``gt_*`` columns."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.truth import Truth

__all__ = ["load_truth", "TruthOptions", "truth_options_per_log"]


@dataclass(frozen=True)
class TruthOptions:
    """How to read the truth (see ``odomkit evaluate --help``).

    ``path`` None means the log's own ground truth. ``sigma`` [m] is the truth's own
    position noise per axis, ``max_gap`` [s] the longest gap between fixes to interpolate
    across (None: no limit).
    """

    path: Path | None = None
    format: str = "auto"
    columns: str | None = None
    time_unit: str = "s"
    sigma: float = 0.0
    max_gap: float | None = 0.5


def load_truth(options: TruthOptions, log: OdometryLog | None = None) -> Truth | None:
    """The truth file of ``options``, else the log's own ground truth, else None."""
    from odomkit.io.truth import read_truth
    from odomkit.truth import Truth, truth_from_log

    if options.path is not None:
        return read_truth(options.path, options.format, options.columns, options.time_unit,
                          options.sigma)
    if log is None:
        return None
    truth = truth_from_log(log)
    if truth is None:
        return None
    return Truth(truth.t, truth.xy, truth.theta, options.sigma, truth.source) if options.sigma else truth


def truth_options_per_log(options: TruthOptions, paths: list[Path], logs: int) -> list[TruthOptions]:
    """One :class:`TruthOptions` per log: the i-th ``--truth`` for the i-th log.

    No ``--truth`` gives every log its own ``gt_*`` columns; otherwise the counts must match.
    """
    if not paths:
        return [options] * logs
    if len(paths) != logs:
        raise InputError(f"give one --truth per log: {logs} log(s) but {len(paths)} --truth file(s)")
    return [replace(options, path=Path(p)) for p in paths]
