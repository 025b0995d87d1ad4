"""``odomkit umbmark``: Borenstein–Feng calibration from a return-error file or from logs
with ground truth."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from odomkit.calibrate.umbmark import umbmark_summary
from odomkit.errors import InputError
from odomkit.io.robotfile import read_robot
from odomkit.io.umbmark_errors import read_errors_csv
from odomkit.robot import DiffDrive
from odomkit.workflows.logs import LogOptions, load_log
from odomkit.workflows.results import check_result, numeric_guard

if TYPE_CHECKING:
    from odomkit.calibrate.realdata import UmbmarkFromRuns

__all__ = ["few_runs_note", "umbmark_from_errors_file", "umbmark_from_files"]


def _diff_robot(robot_path: str | Path) -> DiffDrive:
    robot, _ = read_robot(robot_path)
    if not isinstance(robot, DiffDrive):
        raise InputError("UMBmark needs a differential-drive robot (type = \"diff\")",
                         source=str(robot_path))
    return robot


def umbmark_from_errors_file(errors_csv: str | Path, side: float, *,
                             wheel_base: float | None = None,
                             robot_path: str | Path | None = None,
                             plot: str | Path | None = None, overwrite: bool = False) -> dict[str, Any]:
    """UMBmark (:func:`odomkit.calibrate.umbmark.umbmark_summary`) of the return errors in
    ``errors_csv`` (:func:`odomkit.io.umbmark_errors.read_errors_csv`): what
    ``odomkit umbmark ERRORS.csv`` prints.

    Parameters
    ----------
    errors_csv : path of the return-error file.
    side : square side L [m].
    wheel_base : the wheel base the odometry used [m]; by default the effective wheel base
        of the differential-drive robot in ``robot_path``.
    robot_path : robot file (TOML), read only when ``wheel_base`` is not given.
    plot : draw the errors (:func:`odomkit.workflows.figures.umbmark_figure`) into this
        .png, .svg or .pdf file (replaced only when ``overwrite``).
    """
    _check_plot(plot, overwrite, [errors_csv, *([robot_path] if robot_path else [])])
    if wheel_base is None:
        if robot_path is None:
            raise InputError("--wheel-base (or --robot ROBOT.toml) is required")
        wheel_base = _diff_robot(robot_path).effective_wheel_base
    if not (math.isfinite(wheel_base) and wheel_base > 0):
        raise InputError(f"--wheel-base must be a positive length in metres, got {wheel_base!r}")
    errors_cw, errors_ccw = read_errors_csv(errors_csv)
    with numeric_guard("UMBmark"):
        summary = umbmark_summary(errors_cw, errors_ccw, side, wheel_base)
    _check_umbmark(summary)
    if plot is not None:
        from odomkit.workflows.figures import umbmark_figure

        umbmark_figure(plot, errors_cw, errors_ccw, title=f"UMBmark return errors of {Path(errors_csv).name}")
    return summary


def umbmark_from_files(run_paths: str | Path | Sequence[str | Path], robot_path: str | Path, side: float, *,
                       log_options: LogOptions | None = None, plot: str | Path | None = None,
                       overwrite: bool = False, **kwargs: Any) -> UmbmarkFromRuns:
    """UMBmark (:func:`odomkit.calibrate.realdata.umbmark_from_runs`) from log files, read
    as ``log_options`` say (:class:`~odomkit.workflows.logs.LogOptions`), and a robot file:
    what ``odomkit umbmark --runs`` calls. ``plot`` draws the return errors before and after
    the correction (:func:`odomkit.workflows.figures.umbmark_figure`)."""
    # The exact-calibration stack (scipy) loads only for this form.
    from odomkit.calibrate.realdata import return_errors_from_runs, umbmark_from_runs
    from odomkit.workflows.results import paths_given

    run_paths = paths_given(run_paths, "run")
    _check_plot(plot, overwrite, [*run_paths, robot_path])

    robot = _diff_robot(robot_path)
    runs = [load_log(p, robot, log_options or LogOptions()) for p in run_paths]
    with numeric_guard("UMBmark"):
        result = umbmark_from_runs(runs, robot, side, **kwargs)
    summary = result.to_dict()
    _check_umbmark(summary)
    note = few_runs_note(summary["runs"])
    if note:
        warnings.warn(note, stacklevel=2)
    if plot is not None:
        from odomkit.workflows.figures import umbmark_figure

        cw, ccw = return_errors_from_runs(runs, robot)
        cw_after, ccw_after = return_errors_from_runs(runs, list(result.robots), allow_mixed=True)
        umbmark_figure(plot, cw, ccw, cw_after=cw_after, ccw_after=ccw_after,
                       title=f"UMBmark from {len(runs)} runs, before and after the correction (same runs)")
    return result


def _check_plot(plot: str | Path | None, overwrite: bool, inputs: Sequence[str | Path]) -> None:
    if plot is not None:
        from odomkit.io.files import check_outputs
        from odomkit.plot import check_plot_file

        check_outputs({"--plot": plot}, overwrite=overwrite, inputs=inputs)
        check_plot_file(plot)


def few_runs_note(runs: dict[str, int]) -> str | None:
    """Why ``sigma`` and ``sem`` are undefined (null) for a direction with fewer than two
    runs, or None when every direction has two or more.

    >>> few_runs_note({"cw": 1, "ccw": 3})
    '1 CW run: a standard deviation of the return errors needs 2 or more runs per direction, \
so sigma and sem of CW are undefined (null) and the 3·SEM advice is unknown'
    >>> few_runs_note({"cw": 2, "ccw": 2}) is None
    True
    """
    few = {d.upper(): n for d, n in runs.items() if n < 2}
    if not few:
        return None
    counts = " and ".join(f"{n} {d} run{'s' if n != 1 else ''}" for d, n in few.items())
    return (f"{counts}: a standard deviation of the return errors needs 2 or more runs per direction, "
            f"so sigma and sem of {' and '.join(few)} are undefined (null) and the 3·SEM advice is unknown")


def _check_umbmark(summary: dict[str, Any]) -> None:
    """The numbers UMBmark returns are finite (``radius`` is infinite on straight legs)."""
    check_result("UMBmark", {key: summary.get(key) for key in (
        "cg", "e_max_syst", "alpha", "beta", "E_d", "E_b", "c_left", "c_right", "wheel_base",
        "e_max_syst_before", "e_max_syst_after")})
