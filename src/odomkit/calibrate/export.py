"""What robots consume: a ROS 2 ``diff_drive_controller`` parameter snippet (YAML text)
with ``wheel_separation``/``wheel_radius`` and their multipliers.

The corrected robot itself is written as an odomkit robot file by
:func:`odomkit.io.robotfile.write_robot`; writing files is the job of
:mod:`odomkit.workflows.calibration`.
"""

from __future__ import annotations

from odomkit.errors import ModelError
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
