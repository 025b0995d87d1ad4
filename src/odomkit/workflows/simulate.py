"""``odomkit simulate``: Monte Carlo runs of a segment path against the prediction.

The core (:func:`odomkit.simulate.monte_carlo`) returns the simulation, the theory and
the checks; the command's ``theory`` also carries the predicted covariance in ROS's 6×6
layout, added here as in ``odomkit predict``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from odomkit.path import Segment
from odomkit.robot import SystematicErrors
from odomkit.workflows.predict import add_ros_pose_covariance
from odomkit.workflows.results import check_result, numeric_guard

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg

__all__ = ["run_simulate"]


def run_simulate(
    segments: Sequence[Segment],
    noise: NoiseArg,
    wheel_base: float | None = None,
    *,
    runs: int = 10_000,
    partitions: int = 1000,
    seed: int | None = 0,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    systematic: SystematicErrors | None = None,
    alpha: float = 0.01,
    workers: int | None = None,
    chunk_runs: int | None = None,
    scheduler: str | object | None = None,
    progress: Callable[[int], None] | None = None,
    compass_period: float | None = None,
    max_work: float | None = None,
) -> dict[str, Any]:
    """Simulate ``runs`` noisy runs of ``segments`` and check them against the closed-form
    prediction: the ``--json`` object.

    Parameters are those of :func:`odomkit.simulate.monte_carlo` (``scheduler``: a Dask
    scheduler address or ``dask.distributed.Client``; ``max_work``: the largest runs ×
    partitions × segments, default :data:`odomkit.simulate.engine.MAX_WORK`). Returns its result with
    ``ros_pose_covariance`` added to ``theory``.
    """
    # The Monte Carlo stack (scipy.stats, numba, dask) loads only when a simulation runs.
    from odomkit.simulate import monte_carlo
    from odomkit.simulate.engine import MAX_WORK

    with numeric_guard("the simulation"):
        result = monte_carlo(
            segments, noise, wheel_base,
            runs=runs, partitions=partitions, seed=seed, pose0=pose0, cov0=cov0,
            systematic=systematic, alpha=alpha, workers=workers, chunk_runs=chunk_runs,
            scheduler=scheduler, progress=progress, compass_period=compass_period,
            max_work=MAX_WORK if max_work is None else max_work,
        )
    theory, simulation = result["theory"], result["simulation"]
    check_result("the simulation", {"the predicted pose": theory["pose"],
                                    "the simulated mean": simulation["mean"],
                                    # se.cov squares the variances: overflows before the cov does.
                                    **{f"se.{k}": simulation["se"][k] for k in ("mean", "std", "cov")}},
                 {"the predicted covariance": theory["cov"],
                  "the simulated covariance": simulation["cov"]})
    result["theory"] = add_ros_pose_covariance(result["theory"])
    return result
