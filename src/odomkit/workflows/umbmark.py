"""``odomkit umbmark``: Borenstein–Feng calibration from a return-error file or from logs
with ground truth."""

from __future__ import annotations

import math
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

__all__ = ["umbmark_from_errors_file", "umbmark_from_files"]


def _diff_robot(robot_path: str | Path) -> DiffDrive:
    robot, _ = read_robot(robot_path)
    if not isinstance(robot, DiffDrive):
        raise InputError("UMBmark needs a differential-drive robot (type = \"diff\")",
                         source=str(robot_path))
    return robot


def umbmark_from_errors_file(errors_csv: str | Path, side: float, *,
                             wheel_base: float | None = None,
                             robot_path: str | Path | None = None) -> dict[str, Any]:
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
    """
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
    return summary


def umbmark_from_files(run_paths: Sequence[str | Path], robot_path: str | Path, side: float, *,
                       log_options: LogOptions | None = None, **kwargs: Any) -> UmbmarkFromRuns:
    """UMBmark (:func:`odomkit.calibrate.realdata.umbmark_from_runs`) from log files, read
    as ``log_options`` say (:class:`~odomkit.workflows.logs.LogOptions`), and a robot file:
    what ``odomkit umbmark --runs`` calls."""
    # The exact-calibration stack (scipy) loads only for this form.
    from odomkit.calibrate.realdata import umbmark_from_runs

    robot = _diff_robot(robot_path)
    runs = [load_log(p, robot, log_options or LogOptions()) for p in run_paths]
    with numeric_guard("UMBmark"):
        result = umbmark_from_runs(runs, robot, side, **kwargs)
    _check_umbmark(result.to_dict())
    return result


def _check_umbmark(summary: dict[str, Any]) -> None:
    """The numbers UMBmark returns are finite (``radius`` is infinite on straight legs)."""
    check_result("UMBmark", {key: summary.get(key) for key in (
        "cg", "e_max_syst", "alpha", "beta", "E_d", "E_b", "c_left", "c_right", "wheel_base",
        "e_max_syst_before", "e_max_syst_after")})
