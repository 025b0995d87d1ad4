"""``odomkit simulate``: Monte Carlo runs of a segment path against the prediction.

The core (:func:`odomkit.simulate.monte_carlo`) returns the simulation, the theory and
the checks; the command's ``theory`` also carries the predicted covariance in ROS's 6×6
layout, added here as in ``odomkit predict``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from odomkit import validate
from odomkit.path import Segment
from odomkit.progress import NO_PROGRESS, Progress
from odomkit.robot import Robot, SystematicErrors
from odomkit.workflows.predict import add_ros_pose_covariance
from odomkit.workflows.results import check_result, numeric_guard

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg

__all__ = ["infinite_z_warning", "run_simulate"]


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
    progress: Progress = NO_PROGRESS,
    compass_period: float | None = None,
    max_work: float | None = None,
    plot: str | Path | None = None,
    overwrite: bool = False,
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> dict[str, Any]:
    """Simulate ``runs`` noisy runs of ``segments`` and check them against the closed-form
    prediction (or the track's engines where there is none): the ``--json`` object.

    Parameters are those of :func:`odomkit.simulate.monte_carlo` (``scheduler``: a Dask
    scheduler address or ``dask.distributed.Client``; ``max_work``: the largest runs ×
    partitions × segments, default :data:`odomkit.simulate.engine.MAX_WORK`; ``progress``:
    one stage of ``runs`` units, :mod:`odomkit.progress`). Returns its result with
    ``ros_pose_covariance`` added to ``theory``; a warning names the z-scores that are
    infinite (:func:`infinite_z_warning`). With ``plot`` (.png, .svg or .pdf; replaced only
    when ``overwrite``) it also draws :func:`odomkit.workflows.figures.simulate_figure` and
    adds ``outputs``.
    """
    # The Monte Carlo stack (scipy.stats, numba, dask) loads only when a simulation runs.
    from odomkit.simulate import monte_carlo
    from odomkit.simulate.engine import MAX_WORK

    _check_counts(runs, partitions, seed, workers, chunk_runs, max_work)
    if plot is not None:
        from odomkit.io.files import check_outputs
        from odomkit.plot import check_plot_file

        check_outputs({"--plot": plot}, overwrite=overwrite)
        check_plot_file(plot)
    with numeric_guard("the simulation"):
        result = monte_carlo(
            segments, noise, wheel_base,
            runs=runs, partitions=partitions, seed=seed, pose0=pose0, cov0=cov0,
            systematic=systematic, alpha=alpha, workers=workers, chunk_runs=chunk_runs,
            scheduler=scheduler, progress=progress, compass_period=compass_period,
            max_work=MAX_WORK if max_work is None else max_work, robot=robot,
            sample_period=sample_period,
        )
    theory, simulation = result["theory"], result["simulation"]
    check_result("the simulation", {"the predicted pose": theory["pose"],
                                    "the simulated mean": simulation["mean"],
                                    # se.cov squares the variances: overflows before the cov does.
                                    **{f"se.{k}": simulation["se"][k] for k in ("mean", "std", "cov")}},
                 {"the predicted covariance": theory["cov"],
                  "the simulated covariance": simulation["cov"]})
    result["theory"] = add_ros_pose_covariance(result["theory"])
    message = infinite_z_warning(result)
    if message is not None:
        warnings.warn(message, stacklevel=2)
    if plot is not None:
        result["outputs"] = {"plot": str(_figure(plot, result, segments, noise, wheel_base, partitions,
                                                 pose0, cov0, systematic, workers, compass_period,
                                                 robot, sample_period))}
    return result


#: Most runs the figure shows: the scatter reads the same, and the runs are drawn again.
PLOT_RUNS = 4096


def _figure(plot: str | Path, result: dict[str, Any], segments: Sequence[Segment], noise: NoiseArg,
            wheel_base: float | None, partitions: int, pose0: ArrayLike, cov0: ArrayLike | None,
            systematic: SystematicErrors | None, workers: int | None, compass_period: float | None,
            robot: Robot | None = None, sample_period: float | None = None) -> Path:
    """The end poses are not kept by the experiment: the first :data:`PLOT_RUNS` runs are
    simulated again with its seed and engine, which draws the same numbers (each block of
    runs has its own seeded stream, :mod:`odomkit.simulate.blocks`)."""
    from odomkit.simulate import simulate_runs
    from odomkit.workflows.figures import simulate_figure

    shown = simulate_runs(segments, noise, wheel_base, runs=min(int(result["runs"]), PLOT_RUNS),
                          partitions=partitions, seed=int(result["seed"]), pose0=pose0, cov0=cov0,
                          systematic=systematic, workers=workers, engine=result["engine"],
                          compass_period=compass_period, robot=robot, sample_period=sample_period)
    theory = result["theory"]
    return simulate_figure(plot, shown.final, theory["pose"], theory["cov"], runs=int(result["runs"]),
                           seed=int(result["seed"]))


def _check_counts(runs: int, partitions: int, seed: int | None, workers: int | None,
                  chunk_runs: int | None, max_work: float | None) -> None:
    """The core checks these too, naming its parameters (``max_work``); the command's
    messages name its flags (``--max-work``)."""
    validate.positive_int(runs, "--runs")
    validate.positive_int(partitions, "--partitions")
    for value, flag in ((workers, "--workers"), (chunk_runs, "--chunk-runs")):
        if value is not None:
            validate.positive_int(value, flag)
    if seed is not None:
        validate.non_negative_int(seed, "--seed")
    if max_work is not None:
        validate.positive(max_work, "--max-work")


_NAMES = ("x", "y", "theta")
_UNITS = ("m", "m", "rad")


def infinite_z_warning(result: dict[str, Any]) -> str | None:
    """Why some z-scores of a :func:`run_simulate` result are infinite, or None.

    A z-score divides by the standard error the theory predicts; where the predicted variance
    of a component is exactly zero and the runs still differ from the prediction in it (a
    systematic error with no noise, or rounding in a spread that should be nil), the z-score
    is ±inf, which JSON spells null. The message names the component, the figures and
    their simulated values, so that the reader can tell a real departure from rounding.

    Examples
    --------
    >>> r = {"theory": {"std": [0.0, 1.0, 1.0]},
    ...      "simulation": {"mean_error": [0.002, 0.0, 0.0], "std": [0.0, 1.0, 1.0],
    ...                     "cov": [[0.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]},
    ...      "z": {"mean": [math.inf, 0.1, 0.2], "std": [0.0, 0.3, 0.4],
    ...            "cov": [[0.0, 0, 0], [0, 0.5, 0], [0, 0, 0.6]]}}
    >>> infinite_z_warning(r)
    'the predicted variance of x is zero but the simulated runs differ from the prediction in it \
(mean x 0.002 m): their z-scores are infinite (null in the JSON); see checks.outside_span'
    """
    z, sim, std_p = result["z"], result["simulation"], result["theory"]["std"]
    items: list[tuple[str, float, str, tuple[int, ...]]] = []
    for i, (name, unit) in enumerate(zip(_NAMES, _UNITS, strict=True)):
        if math.isinf(z["mean"][i]):
            items.append((f"mean {name}", float(sim["mean_error"][i]), unit, (i,)))
        if math.isinf(z["std"][i]):
            items.append((f"std {name}", float(sim["std"][i]), unit, (i,)))
    for i in range(3):
        for j in range(i + 1, 3):
            if math.isinf(z["cov"][i][j]):
                unit = "m²" if j < 2 else ("m·rad" if i < 2 else "rad²")
                items.append((f"cov {_NAMES[i]},{_NAMES[j]}", float(sim["cov"][i][j]), unit, (i, j)))
    if not items:
        return None
    zero = sorted({k for *_, idx in items for k in idx if float(std_p[k]) == 0.0})
    values = ", ".join(f"{label} {value:.3g} {unit}" for label, value, unit, _ in items)
    them = "it" if len(zero) == 1 else "them"
    return (f"the predicted variance of {', '.join(_NAMES[k] for k in zero)} is zero but the simulated "
            f"runs differ from the prediction in {them} ({values}): their z-scores are infinite (null "
            "in the JSON); see checks.outside_span")
