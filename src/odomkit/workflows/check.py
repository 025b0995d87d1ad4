"""``odomkit check``: read a log (and its truth) and run the data checks of
:mod:`odomkit.calibrate.check` before calibrating.

A text log the readers refuse (NaN values, text in a number column, a wrong ``--columns``)
is itself a finding, not a crash: the reader's one-line message (file, line, column) becomes a
``fail`` and the other checks are skipped. A ROS bag the bag reader refuses (no ``--topic``
among several, a topic that is not there, a joint not named) is the command line's error, as
in every other command: one line, exit status 2 (its rows are no one's to fix). The readers'
warnings (rows out of time order, a cumulative counter read as increments) become ``warn``
findings.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["check_file"]


def check_file(
    log_path: str | Path,
    robot_path: str | Path,
    truth: TruthOptions,
    *,
    log_options: LogOptions | None = None,
    spin: str | None = None,
) -> dict[str, Any]:
    """Check one log before calibrating.

    Parameters
    ----------
    log_path : the log (any format :func:`odomkit.workflows.logs.load_log` reads)
    robot_path : its robot file (TOML)
    truth : truth options (``path`` None: the log's own ``gt_*`` columns, if any)
    log_options : how to read the log
    spin : "ccw" or "cw" when the log is a spin in place that way (checks the wheels
        without truth)

    Returns
    -------
    dict
        ``log``, ``ok`` (no finding failed), ``findings`` [{check, status, message,
        advice}], ``next`` [what to record or fix next], ``truth`` (where it came from or None).
    """
    from odomkit.calibrate.check import check_log, next_steps
    from odomkit.calibrate.check_finding import Finding
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.logs import LogOptions, detect_format, load_log, require_log_file
    from odomkit.workflows.results import numeric_guard
    from odomkit.workflows.truth import clock_from_robot, load_truth

    if spin is not None and spin not in ("ccw", "cw"):
        raise InputError(f"--spin must be ccw or cw, got {spin!r}")
    path = Path(log_path)
    require_log_file(path)
    robot, _ = read_robot(robot_path)
    options = log_options or LogOptions()
    is_bag = (options.format if options.format != "auto" else detect_format(path)) == "bag"
    findings: list[Finding] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        try:
            log = load_log(path, robot, options)
        except InputError as exc:
            if is_bag:  # which topics to read, not rows to fix: the one line track gives
                raise
            log = None
            findings.append(Finding("reading", "fail", str(exc),
                                    "fix the rows or the --columns mapping the message names"))
    from odomkit.units import FAST_TRAVEL, SLOW_ROWS

    for item in caught:
        if issubclass(item.category, UserWarning) and any(
                words in str(item.message) for words in (SLOW_ROWS, FAST_TRAVEL)):
            continue  # the time or the distance finding says it, with what to do
        if issubclass(item.category, UserWarning):
            findings.append(Finding("reading", "warn", " ".join(str(item.message).split()),
                                    "read the log as the message says, then check again"))
        else:  # not ours: show it as Python would
            warnings.showwarning(item.message, item.category, item.filename, item.lineno)
    found_truth = None
    if log is not None:
        found_truth = load_truth(clock_from_robot(robot_path, [truth])[0], log, heading_warning=False)
        if spin is not None and found_truth is not None:
            spin = None  # the truth says more than the spin's stated direction
        # Times of 1e200 s make the checks' least squares fail (SVD on inf): one line.
        with numeric_guard("the checks"):
            findings += check_log(log, robot, found_truth, spin=spin, max_gap=truth.max_gap)
    return {
        "log": str(path),
        "ok": not any(f.status == "fail" for f in findings),
        "findings": [f.to_dict() for f in findings],
        "next": next_steps(findings) or ["nothing: the log is fit to calibrate from" + (
            "" if found_truth is not None else
            ", once it has a ground truth (--truth FILE, --truth-topic for a bag's own, or gt_* columns)")],
        "truth": None if found_truth is None else found_truth.source,
    }
