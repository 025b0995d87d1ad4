"""Calibration from files: read runs and robot files, calibrate, write what robots use.

The maths lives in :mod:`odomkit.calibrate`; this module is the file side behind
``odomkit calibrate`` and ``odomkit calibrate-noise`` (``odomkit umbmark --runs`` is
:mod:`odomkit.workflows.umbmark`).
Nothing existing is overwritten unless ``overwrite=True`` (CLI ``--force``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.noise_fit import fit_wheel_noise_from_runs
from odomkit.calibrate.realdata import (
    SquareRow,
    e_max_syst_of_runs,
    square_table,
    umbmark_from_runs,
)
from odomkit.errors import InputError, ModelError
from odomkit.io.files import refuse_overwrite
from odomkit.io.optiodom import read_experiment
from odomkit.io.robotfile import read_robot, robot_to_dict, write_robot
from odomkit.io.ros import write_ros2_yaml
from odomkit.robot import DiffDrive
from odomkit.workflows.logs import LogOptions, load_log

__all__ = ["calibrate_files", "noise_files", "optiodom_square_table"]


def calibrate_files(
    run_paths: Sequence[str | Path],
    robot_path: str | Path,
    *,
    method: str = "exact",
    source: str = "endpoints",
    side: float | None = None,
    out_robot: str | Path | None = None,
    ros_yaml: str | Path | None = None,
    wheel_radius: float | None = None,
    overwrite: bool = False,
    log_options: LogOptions | None = None,
    **exact_kwargs: Any,
) -> dict[str, Any]:
    """Read runs and a robot file, calibrate, write the requested outputs (CLI backend).

    Parameters
    ----------
    run_paths : log files with ground truth (any format
        :func:`odomkit.workflows.logs.load_log` reads).
    robot_path : robot file (TOML) with the parameters the odometry used.
    method : {"exact", "umbmark"}
    source : {"endpoints", "trajectory"} (exact only)
    side : square side [m] (UMBmark only; required there).
    out_robot, ros_yaml : optional output paths (never overwritten unless ``overwrite``).
    wheel_radius : nominal wheel radius for the ROS snippet [m].
    log_options : :class:`odomkit.workflows.logs.LogOptions`.
    **exact_kwargs : passed to :func:`odomkit.calibrate.exact.calibrate_exact`.

    Returns
    -------
    dict with the calibration summary (JSON-ready), ``robot`` (the corrected parameters
    as in the robot file) and ``outputs`` (paths written).
    """
    robot, noise = read_robot(robot_path)
    refuse_overwrite(out_robot, ros_yaml, overwrite=overwrite)
    if ros_yaml is not None and wheel_radius is None:
        raise InputError("--ros-yaml needs --wheel-radius (the controller's nominal radius, m)")
    runs = [load_log(p, robot, log_options or LogOptions()) for p in run_paths]
    if method == "umbmark":
        if side is None:
            raise InputError("--method umbmark needs --side (the square side in metres)")
        if not isinstance(robot, DiffDrive):
            raise InputError("UMBmark needs a differential-drive robot (type = \"diff\")",
                             source=str(robot_path))
        um = umbmark_from_runs(runs, robot, side)
        summary = um.to_dict()
        new_robot: Any = um.robot
    elif method == "exact":
        cal = calibrate_exact(runs, robot, source, **exact_kwargs)  # type: ignore[arg-type]
        summary = cal.to_dict()
        new_robot = cal.robot
        if side is not None and isinstance(robot, DiffDrive):
            summary["e_max_syst_before"] = e_max_syst_of_runs(runs, robot)
            summary["e_max_syst_after"] = e_max_syst_of_runs(runs, new_robot)
    else:
        raise ModelError(f"--method must be 'exact' or 'umbmark', got {method!r}")
    outputs: dict[str, str] = {}
    if out_robot is not None:
        outputs["robot"] = str(write_robot(out_robot, new_robot, noise, overwrite=overwrite))
    if ros_yaml is not None:
        assert wheel_radius is not None
        outputs["ros_yaml"] = str(write_ros2_yaml(ros_yaml, new_robot, wheel_radius,
                                                  overwrite=overwrite))
    summary["method"] = method
    summary["robot"] = robot_to_dict(new_robot)["robot"]
    summary["outputs"] = outputs
    return summary


def noise_files(
    run_paths: Sequence[str | Path], robot_path: str | Path, *,
    log_options: LogOptions | None = None, plot: str | Path | None = None,
    overwrite: bool = False, **kwargs: Any,
) -> dict[str, Any]:
    """Read repeated runs and a robot file and fit k_L, k_R
    (:func:`odomkit.calibrate.noise_fit.fit_wheel_noise_from_runs`); JSON-ready dict.
    With ``plot``, also draw the runs' errors with the fitted and empirical 95 % ellipses
    (needs matplotlib)."""
    robot, _ = read_robot(robot_path)
    if not isinstance(robot, DiffDrive):
        raise InputError(f"calibrate-noise fits the wheel noise k_L, k_R of a differential drive; "
                         f"the robot file describes a {robot.type_name!r} robot", source=str(robot_path))
    refuse_overwrite(plot, overwrite=overwrite)
    runs = [load_log(p, robot, log_options or LogOptions()) for p in run_paths]
    fit = fit_wheel_noise_from_runs(runs, robot, **kwargs)
    out = fit.to_dict()
    if plot is not None:
        from odomkit.plot import have_matplotlib, plot_noise_fit

        if not have_matplotlib():
            raise InputError("--plot needs matplotlib: pip install 'odomkit[plot]'")
        out["plot"] = str(plot_noise_fit(fit, plot))
    return out


def optiodom_square_table(data_dir: str | Path, **exact_kwargs: Any) -> list[SquareRow]:
    """:func:`odomkit.calibrate.realdata.square_table` of every OptiOdom ``diff/square``
    experiment under ``data_dir`` (the folder holding ``optiodom/``, or ``optiodom/``)."""
    root = Path(data_dir)
    folder = root / "optiodom" / "diff" / "square"
    if not folder.is_dir():
        folder = root / "diff" / "square"
    if not folder.is_dir():
        raise InputError("no optiodom/diff/square folder here", source=str(root))
    experiments = [read_experiment(p) for p in sorted(folder.iterdir()) if p.is_dir()]
    return square_table(experiments, **exact_kwargs)
