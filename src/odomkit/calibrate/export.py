"""Outputs robots consume, and the file-level calibration workflow behind the CLI.

* an odomkit robot file (TOML) with the corrected parameters
  (:func:`odomkit.io.robotfile.write_robot`);
* a ROS 2 ``diff_drive_controller`` parameter snippet (YAML) with
  ``wheel_separation``/``wheel_radius`` and their multipliers.

Nothing existing is overwritten unless ``overwrite=True``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from odomkit.errors import InputError, ModelError
from odomkit.robot import DiffDrive


def ros2_diff_drive_yaml(
    robot: DiffDrive,
    wheel_radius: float,
    *,
    controller_name: str = "diff_drive_controller",
    nominal_m_per_tick: float | None = None,
) -> str:
    """ROS 2 ``diff_drive_controller`` parameters for a calibrated robot (YAML text).

    The controller computes wheel travel as ``radius · multiplier · joint angle`` and uses
    ``wheel_separation · wheel_separation_multiplier`` as the wheel base, so:

    * ``wheel_separation`` = the nominal wheel base, multiplier = ``c_wheel_base``;
    * ``wheel_radius`` = the nominal radius you give, and each wheel's radius multiplier
      = its corrected metres per tick over the nominal metres per tick that radius stands
      for (``nominal_m_per_tick``, default the mean of the robot's two nominal values):
      ``c_left`` and ``c_right`` when both wheels have the same nominal size.

    Parameters
    ----------
    robot : DiffDrive
        Calibrated robot.
    wheel_radius : float
        Nominal wheel radius configured in the controller [m].
    controller_name : str
        Top-level key (the controller's node name).
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to.

    Examples
    --------
    >>> print(ros2_diff_drive_yaml(DiffDrive(0.2, 1e-4, 1e-4, 0.999, 1.001, 1.006), 0.042))
    diff_drive_controller:
      ros__parameters:
        wheel_separation: 0.2
        wheel_radius: 0.042
        wheel_separation_multiplier: 1.006
        left_wheel_radius_multiplier: 0.999
        right_wheel_radius_multiplier: 1.001
    <BLANKLINE>
    """
    if not isinstance(robot, DiffDrive):
        raise ModelError("diff_drive_controller parameters need a DiffDrive robot")
    if not (isinstance(wheel_radius, int | float) and wheel_radius > 0):
        raise ModelError(f"wheel_radius must be a positive number of metres, got {wheel_radius!r}")
    if not controller_name or any(c in controller_name for c in ":#\n "):
        raise ModelError(f"controller_name must be a plain ROS node name, got {controller_name!r}")
    ref = nominal_m_per_tick or 0.5 * (robot.m_per_tick_left + robot.m_per_tick_right)
    values = {
        "wheel_separation": robot.wheel_base,
        "wheel_radius": float(wheel_radius),
        "wheel_separation_multiplier": robot.c_wheel_base,
        "left_wheel_radius_multiplier": robot.scale_left / ref,
        "right_wheel_radius_multiplier": robot.scale_right / ref,
    }
    body = "".join(f"    {k}: {float(v)!r}\n" for k, v in values.items())
    return f"{controller_name}:\n  ros__parameters:\n{body}"


def _write_new(path: str | Path, text: str, overwrite: bool) -> Path:
    p = Path(path)
    if p.exists() and not overwrite:
        raise InputError("exists already; pass overwrite=True (CLI: --force) to replace it",
                         source=str(p))
    p.write_text(text, encoding="utf-8")
    return p


def write_ros2_yaml(path: str | Path, robot: DiffDrive, wheel_radius: float, *,
                    overwrite: bool = False, **kwargs: Any) -> Path:
    """Write :func:`ros2_diff_drive_yaml` to ``path``; refuse to replace a file."""
    return _write_new(path, ros2_diff_drive_yaml(robot, wheel_radius, **kwargs), overwrite)


def write_calibrated_robot(path: str | Path, robot: Any, noise: tuple[Any, ...] = (), *,
                           overwrite: bool = False) -> Path:
    """Write an odomkit robot file (TOML) via :func:`odomkit.io.robotfile.write_robot`."""
    from odomkit.io.robotfile import write_robot

    return write_robot(path, robot, noise, overwrite=overwrite)


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
    log_options: Any = None,
    **exact_kwargs: Any,
) -> dict[str, Any]:
    """Read runs and a robot file, calibrate, write the requested outputs (CLI backend).

    Parameters
    ----------
    run_paths : log files with ground truth (any format :func:`odomkit.workflows.load_log`
        reads).
    robot_path : robot file (TOML) with the parameters the odometry used.
    method : {"exact", "umbmark"}
    source : {"endpoints", "trajectory"} (exact only)
    side : square side [m] (UMBmark only; required there).
    out_robot, ros_yaml : optional output paths (never overwritten unless ``overwrite``).
    wheel_radius : nominal wheel radius for the ROS snippet [m].
    log_options : :class:`odomkit.workflows.LogOptions`.
    **exact_kwargs : passed to :func:`odomkit.calibrate.exact.calibrate_exact`.

    Returns
    -------
    dict with the calibration summary (JSON-ready), ``robot`` (the corrected parameters
    as in the robot file) and ``outputs`` (paths written).
    """
    from odomkit.calibrate.exact import calibrate_exact
    from odomkit.calibrate.realdata import e_max_syst_of_runs, umbmark_from_runs
    from odomkit.io.robotfile import read_robot, robot_to_dict
    from odomkit.workflows import LogOptions, load_log

    robot, noise = read_robot(robot_path)
    opts = log_options or LogOptions()
    runs = [load_log(p, robot, opts) for p in run_paths]
    if ros_yaml is not None and wheel_radius is None:
        raise InputError("--ros-yaml needs --wheel-radius (the controller's nominal radius, m)")
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
    # Check both targets before writing either, so a refusal leaves nothing half-done.
    for target in (out_robot, ros_yaml):
        if target is not None and Path(target).exists() and not overwrite:
            raise InputError("exists already; pass --force to replace it", source=str(target))
    if out_robot is not None:
        outputs["robot"] = str(write_calibrated_robot(out_robot, new_robot, noise, overwrite=overwrite))
    if ros_yaml is not None:
        assert wheel_radius is not None
        outputs["ros_yaml"] = str(write_ros2_yaml(ros_yaml, new_robot, wheel_radius,
                                                  overwrite=overwrite))
    summary["method"] = method
    summary["robot"] = robot_to_dict(new_robot)["robot"]
    summary["outputs"] = outputs
    return summary


def noise_files(
    run_paths: Sequence[str | Path], robot_path: str | Path, *, log_options: Any = None,
    plot: str | Path | None = None, overwrite: bool = False, **kwargs: Any,
) -> dict[str, Any]:
    """Read repeated runs and a robot file and fit k_L, k_R
    (:func:`odomkit.calibrate.noise_fit.fit_wheel_noise_from_runs`); JSON-ready dict.
    With ``plot``, also draw the runs' errors with the fitted and empirical 95 % ellipses
    (needs matplotlib)."""
    from odomkit.calibrate.noise_fit import fit_wheel_noise_from_runs
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows import LogOptions, load_log

    robot, _ = read_robot(robot_path)
    opts = log_options or LogOptions()
    if plot is not None and Path(plot).exists() and not overwrite:
        raise InputError("exists already; pass --force to replace it", source=str(plot))
    runs = [load_log(p, robot, opts) for p in run_paths]
    fit = fit_wheel_noise_from_runs(runs, robot, **kwargs)
    out = fit.to_dict()
    if plot is not None:
        from odomkit.plot import have_matplotlib, plot_noise_fit

        if not have_matplotlib():
            raise InputError("--plot needs matplotlib: pip install 'odomkit[plot]'")
        out["plot"] = str(plot_noise_fit(fit, plot))
    return out
