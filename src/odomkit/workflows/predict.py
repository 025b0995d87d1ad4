"""``odomkit predict``: the closed-form prediction of a segment path, as its JSON object.

The core (:func:`odomkit.propagate.predict.predict`) returns the pose and covariance; the
command's output also carries the covariance in ROS's 6×6 layout
(:func:`odomkit.io.ros.ros_pose_covariance`), added here.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.io.ros import ros_pose_covariance, yaw_variance_note
from odomkit.path import Segment
from odomkit.robot import Robot
from odomkit.workflows.results import check_result, numeric_guard

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg

__all__ = ["add_ros_pose_covariance", "MAX_STEPS", "run_predict"]

#: Largest partitions × segments a prediction takes: the recursion and transition engines
#: hold every step (a 3×3 covariance and its step data, ~150 bytes), so 10⁷ steps use about
#: 1.5 GB; 10⁹ would need 150 GB.
MAX_STEPS = 10**7


def add_ros_pose_covariance(summary: dict[str, Any]) -> dict[str, Any]:
    """``summary`` with ``ros_pose_covariance`` (36 numbers, from its ``cov``) right after
    ``cov``, the order in which the command prints them.

    Examples
    --------
    >>> d = add_ros_pose_covariance({"pose": [0, 0, 0], "cov": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
    ...                              "std": [1, 1, 1]})
    >>> list(d), d["ros_pose_covariance"][35], d["ros_pose_covariance"][14]
    (['pose', 'cov', 'ros_pose_covariance', 'std'], 1.0, 1000000.0)
    """
    out: dict[str, Any] = {}
    for key, value in summary.items():
        out[key] = value
        if key == "cov":
            out["ros_pose_covariance"] = ros_pose_covariance(value)
            # A consumer takes the yaw variance literally (io.ros.yaw_variance_note says why).
            if note := yaw_variance_note(float(out["ros_pose_covariance"][35]), "ros_pose_covariance"):
                warnings.warn(note, UserWarning, stacklevel=2)
    return out


def run_predict(
    segments: Sequence[Segment],
    noise: NoiseArg,
    *,
    wheel_base: float | None = None,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    engine: str = "closed",
    partitions: int | None = None,
    compass_period: float | None = None,
    plot: str | Path | None = None,
    overwrite: bool = False,
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> dict[str, Any]:
    """Predict the end pose of ``segments`` and its covariance: the ``--json`` object.

    Parameters are those of :func:`odomkit.propagate.predict.predict` (``robot`` and
    ``noise`` as a robot file gives them, ``read_robot``). Returns
    :meth:`~odomkit.propagate.predict.Prediction.to_dict` plus ``ros_pose_covariance``.
    With ``plot`` (.png, .svg or .pdf; replaced only when ``overwrite``) it also draws
    :func:`odomkit.workflows.figures.predict_figure` and adds ``outputs``.
    """
    from odomkit.propagate.predict import predict

    if plot is not None:
        from odomkit.io.files import check_outputs
        from odomkit.plot import check_plot_file

        check_outputs({"--plot": plot}, overwrite=overwrite)
        check_plot_file(plot)

    if partitions is not None:  # checked here too, so that the message names the flag
        validate.positive_int(partitions, "--partitions")
    if partitions is not None and partitions * max(len(segments), 1) > MAX_STEPS:
        raise ModelError(f"--partitions {partitions} × {len(segments)} segment(s) = "
                         f"{partitions * len(segments):.3g} steps, above the limit {MAX_STEPS:.0e} "
                         "(memory); lower --partitions (the closed engine needs none)")
    if sample_period is not None:
        validate.positive(sample_period, "--sample-period", unit="s")
        samples = sum(float(getattr(s, "duration", 0.0)) for s in segments) / sample_period
        if samples > MAX_STEPS:
            raise ModelError(f"the path lasts {samples:.3g} sample periods, above the limit "
                             f"{MAX_STEPS:.0e} steps (memory); is --sample-period in seconds?")
    with numeric_guard("the prediction"):
        result = predict(segments, noise, wheel_base=wheel_base, pose0=pose0, cov0=cov0,
                         engine=engine,  # type: ignore[arg-type]
                         partitions=partitions, compass_period=compass_period, robot=robot,
                         sample_period=sample_period)
    check_result("the prediction", {"the pose": result.pose}, {"the covariance": result.cov})
    out = add_ros_pose_covariance(result.to_dict())
    if plot is not None:
        from odomkit.workflows.figures import predict_figure

        out["outputs"] = {"plot": str(predict_figure(
            plot, segments, noise, wheel_base, pose0=pose0, cov0=cov0, end_pose=result.pose,
            end_cov=result.cov, compass_period=compass_period, partitions=partitions, robot=robot,
            sample_period=sample_period))}
    return out
