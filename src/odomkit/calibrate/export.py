"""What robots consume: the ROS 2 ``diff_drive_controller`` settings of a calibrated robot,
``wheel_separation``/``wheel_radius`` and their multipliers, as numbers.

The YAML file the controller reads is written by :mod:`odomkit.io.ros`; the corrected
robot itself by :func:`odomkit.io.robotfile.write_robot`.
"""

from __future__ import annotations

from odomkit.errors import ModelError
from odomkit.robot import DiffDrive

__all__ = ["diff_drive_controller_parameters"]


def diff_drive_controller_parameters(
    robot: DiffDrive,
    wheel_radius: float,
    *,
    nominal_m_per_tick: float | None = None,
) -> dict[str, float]:
    """ROS 2 ``diff_drive_controller`` parameters that reproduce a calibrated robot.

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
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to.

    Returns
    -------
    dict
        ``wheel_separation`` [m], ``wheel_radius`` [m], ``wheel_separation_multiplier``,
        ``left_wheel_radius_multiplier``, ``right_wheel_radius_multiplier`` (in the
        controller's YAML order).

    Examples
    --------
    >>> p = diff_drive_controller_parameters(DiffDrive(0.2, 1e-4, 1e-4, 0.999, 1.001, 1.006), 0.042)
    >>> p["wheel_separation_multiplier"], p["left_wheel_radius_multiplier"]
    (1.006, 0.999)
    """
    if not isinstance(robot, DiffDrive):
        raise ModelError("diff_drive_controller parameters need a DiffDrive robot")
    if not (isinstance(wheel_radius, int | float) and wheel_radius > 0):
        raise ModelError(f"wheel_radius must be a positive number of metres, got {wheel_radius!r}")
    ref = nominal_m_per_tick or 0.5 * (robot.m_per_tick_left + robot.m_per_tick_right)
    return {
        "wheel_separation": float(robot.wheel_base),
        "wheel_radius": float(wheel_radius),
        "wheel_separation_multiplier": float(robot.c_wheel_base),
        "left_wheel_radius_multiplier": float(robot.scale_left / ref),
        "right_wheel_radius_multiplier": float(robot.scale_right / ref),
    }
