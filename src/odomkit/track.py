"""A log and a robot -> a pose track (and, with a noise model, its covariance)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import InputError
from odomkit.integrate import dead_reckon, path_length
from odomkit.kinematics import BodySteps, Method, body_steps
from odomkit.log import OdometryLog
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.robot import Robot

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg

__all__ = ["dead_reckon_log", "initial_pose", "Track"]


@dataclass(frozen=True)
class Track:
    """A dead-reckoned pose track.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time of each pose [s].
    poses : ndarray, shape (N, 3)
        ``[x, y, θ]`` [m, m, rad], θ continuous.
    cov : ndarray, shape (N, 3, 3), optional
        Pose covariance, order x, y, θ; None when no noise model was given.
    steps : BodySteps
        The body motion the track was integrated from.
    """

    t: NDArray[np.float64]
    poses: NDArray[np.float64]
    cov: NDArray[np.float64] | None
    steps: BodySteps

    @property
    def path_length(self) -> float:
        """Distance travelled by the reference point [m], reversing included."""
        return path_length(self.steps.dd)

    @property
    def duration(self) -> float:
        """Time from the first to the last row [s]."""
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0


def initial_pose(log: OdometryLog, pose0: ArrayLike | None) -> NDArray[np.float64]:
    """``pose0`` if given, else the first ground-truth pose, else the origin."""
    if pose0 is not None:
        return validate.pose(pose0, "initial pose")
    if log.ground_truth is not None:
        return log.ground_truth[0].copy()
    return np.zeros(3)


def dead_reckon_log(
    log: OdometryLog,
    robot: Robot,
    method: Method = "exact",
    pose0: ArrayLike | None = None,
    noise: NoiseArg | None = None,
    cov0: ArrayLike | None = None,
    engine: str = "recursion",
    *,
    progress: Progress = NO_PROGRESS,
) -> Track:
    """Dead-reckon a whole log.

    Parameters
    ----------
    log : OdometryLog, N rows
    robot : Robot
    method : {"exact", "midpoint", "euler"}
    pose0 : array_like, shape (3,), optional
        Initial pose; defaults to the first ground-truth pose, else the origin.
    noise : noise model or tuple of noise models, optional
        When given, the covariance of every pose is propagated
        (:func:`odomkit.propagate.recursion.track_covariance`).
    cov0 : array_like, shape (3, 3), optional
        Initial covariance (default zero).
    engine : {"recursion", "transition"}
        Covariance engine: the step recursion (Chong–Kleeman eq. 2) or Kelly's
        transition-matrix solution; they agree to round-off.
    progress : Progress
        Two stages: ``"dead reckoning"`` (of unknown length) and, with ``noise``, the
        covariance chunk by chunk (:func:`odomkit.propagate.recursion.track_covariance`);
        never changes a number (:mod:`odomkit.progress`).

    Returns
    -------
    Track with N poses.
    """
    if len(log) == 0:
        raise InputError("the log is empty: no rows to dead-reckon", source=log.source)
    with stage(progress, None, "dead reckoning"):
        steps = body_steps(robot, log)
        p0 = initial_pose(log, pose0)
        if robot.measures_heading:
            # Direct heading: the measured heading replaces the integrated one.
            heading = steps.inputs["heading"]
            p0 = np.array([p0[0], p0[1], heading[0]])
        poses = dead_reckon(steps.dd, steps.dtheta, p0, method)
    cov = None
    if noise is not None:
        from odomkit.propagate.recursion import track_covariance

        c0 = np.zeros((3, 3)) if cov0 is None else validate.covariance(cov0, "initial covariance")
        cov = track_covariance(steps, poses, noise, c0, method=method, engine=engine, progress=progress)
    return Track(log.t, poses, cov, steps)
