"""Monte Carlo engine: many noisy runs of a planned segment path.

Each segment is cut into K partitions; every partition gets fresh, independent noise from
the noise model, and the pose is integrated with the exact arc (see
:mod:`odomkit.simulate._kernels`). This is the experiment of Chong–Kleeman section 6.1
(Tables 1–2: 10 000 runs, 10 000 partitions, wheel base 0.4 m).

Reproducibility: runs are grouped into fixed blocks, each with its own random stream
(:mod:`odomkit.simulate.blocks`), so how blocks are grouped into chunks, threads or Dask
workers never changes a number.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.path import Segment
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import Robot
from odomkit.simulate import _kernels
from odomkit.simulate.blocks import make_tasks, run_task
from odomkit.simulate.distributed import Scheduler
from odomkit.simulate.plan import Plan, SystematicErrors, make_plan

__all__ = ["check_scheduler", "check_size", "Engine", "MAX_MEMORY", "MAX_WORK", "MonteCarloRuns",
           "simulate_runs"]

#: Default limit on runs × partitions × segments, the partition steps one simulation
#: integrates. Chong–Kleeman's experiment, 10⁴ runs × 10⁴ partitions of one arc, is 10⁸
#: steps and takes about 1.5 s; the limit is about 100 times the largest of their tables.
MAX_WORK = 1e10
#: Default limit on the memory the runs' poses take [bytes] (final poses, segment ends, and
#: the copies the statistics make).
MAX_MEMORY = 4 * 2**30
# Seconds per partition step, to turn the work into a rough time in the message.
_SECONDS_PER_STEP = 1.5e-8
# Bytes per run and per stored pose: 3 float64, held about 4 times (blocks, their
# concatenation, the statistics' centred copy and its products).
_BYTES_PER_POSE = 4 * 3 * 8
_ADDRESS = re.compile(r"^(?:[a-z][a-z0-9+.-]*://)?(?:\[[0-9a-fA-F:.]+\]|[^\s:/\[\]]+):\d+$")

Engine = Literal["auto", "numba", "numpy"]


@dataclass(frozen=True)
class MonteCarloRuns:
    """Result of :func:`simulate_runs`.

    Attributes
    ----------
    final : ndarray, shape (N, 3)
        Final pose of every run [m, m, rad], θ continuous (not wrapped).
    segment_ends : ndarray, shape (N, S, 3) or None
        Pose of every run at the end of each segment (when asked for).
    seed : int
        The seed used (drawn from the OS when none was given), to repeat the experiment.
    seconds : float
        Wall-clock time of the simulation.
    engine : str
        ``"numba"`` or ``"numpy"``; the two agree to rounding, not bit for bit.
    """

    final: NDArray[np.float64]
    segment_ends: NDArray[np.float64] | None
    runs: int
    partitions: int
    seed: int
    seconds: float
    engine: str


def check_size(runs: int, partitions: int, segments: int, *, segment_ends: bool = False,
               max_work: float = MAX_WORK, max_memory: float = MAX_MEMORY) -> None:
    """Refuse a simulation that would run for hours or exhaust the memory, before it starts.

    Parameters
    ----------
    runs, partitions, segments : int
        N runs of a path of S segments, each cut into K partitions.
    segment_ends : bool
        The pose at every segment end is kept too (N·S poses).
    max_work : float
        Largest N·K·S allowed (``--max-work``); :data:`MAX_WORK` by default.
    max_memory : float
        Largest memory for the poses [bytes]; :data:`MAX_MEMORY` by default.

    Raises
    ------
    ModelError
        With the estimate, the limit, and how to go on.

    Examples
    --------
    >>> check_size(10_000, 10_000, 1)          # Chong–Kleeman Table 1: allowed
    >>> check_size(10**9, 1000, 1)
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: 1e+09 runs × 1000 partitions × 1 segment = 1e+12 partition \
steps, above the limit 1e+10 (this would take about 4.2 h); lower --runs or --partitions, or \
raise the limit with --max-work 1e+12
    """
    runs = validate.positive_int(runs, "runs")
    partitions = validate.positive_int(partitions, "partitions")
    limit = validate.positive(max_work, "max_work")
    work = float(runs) * float(partitions) * float(segments)
    if work > limit:
        plural = "s" if segments != 1 else ""
        raise ModelError(
            f"{runs:.4g} runs × {partitions:.4g} partitions × {segments} segment{plural} = "
            f"{work:.3g} partition steps, above the limit {limit:.3g} (this would take about "
            f"{_duration(work * _SECONDS_PER_STEP)}); lower --runs or --partitions, or raise the "
            f"limit with --max-work {work:.3g}")
    memory = float(runs) * (1 + (segments if segment_ends else 0)) * _BYTES_PER_POSE
    if memory > max_memory:
        raise ModelError(
            f"{runs:.4g} runs need about {memory / 2**30:.3g} GiB of memory for their poses, above "
            f"the limit {max_memory / 2**30:.3g} GiB; simulate fewer runs at a time (the same "
            "--seed and more runs extend the same experiment)")


def _duration(seconds: float) -> str:
    for unit, size in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.2g} {unit}"
    return f"{seconds:.2g} s"


def check_scheduler(scheduler: Scheduler) -> None:
    """A scheduler given as text must be a Dask address ``[protocol://]host:port``.

    Examples
    --------
    >>> check_scheduler("tcp://10.0.0.5:8786")
    >>> check_scheduler("")
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: --scheduler must be a Dask scheduler address host:port \
(e.g. tcp://10.0.0.5:8786), got ''
    """
    if isinstance(scheduler, str) and not _ADDRESS.match(scheduler):
        raise ModelError("--scheduler must be a Dask scheduler address host:port "
                         f"(e.g. tcp://10.0.0.5:8786), got {scheduler!r}")


def _pick_engine(engine: Engine) -> str:
    if engine == "auto":
        return "numba" if _kernels.have_numba() else "numpy"
    if engine == "numba" and not _kernels.have_numba():
        raise ModelError("engine='numba' needs numba: pip install 'odomkit[fast]'")
    if engine not in ("numba", "numpy"):
        raise ModelError(f"engine must be auto, numba or numpy, got {engine!r}")
    return engine


def _resolve_seed(seed: int | None) -> int:
    if seed is None:
        return int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
    return validate.non_negative_int(seed, "seed")


def simulate_runs(
    path: Sequence[Segment],
    noise: NoiseArg,
    wheel_base: float | None = None,
    *,
    runs: int = 10_000,
    partitions: int = 1000,
    seed: int | None = None,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    systematic: SystematicErrors | None = None,
    segment_ends: bool = False,
    workers: int | None = None,
    chunk_runs: int | None = None,
    scheduler: Scheduler = None,
    engine: Engine = "auto",
    progress: Progress = NO_PROGRESS,
    compass_period: float | None = None,
    max_work: float = MAX_WORK,
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> MonteCarloRuns:
    """Simulate ``runs`` noisy runs of ``path`` and return their poses.

    Parameters
    ----------
    path : sequence of Segment
        Arc/Straight/Spin (differential drive), KellyArc (gyro, unicycle, compass) or
        SteerArc (tricycle, car).
    noise : noise model or tuple of them
        Selects the model, as in :func:`odomkit.propagate.predict.predict`:
        :class:`~odomkit.noise.WheelNoise` (variance k²·|d| per partition and wheel);
        :class:`~odomkit.noise.ClassicalNoise` (fixed σ of D and α per partition, each
        partition a rotation α then a translation D, Chong–Kleeman eq. 1, so K = 1 is one
        step per segment); (SpeedNoise, GyroNoise); (SpeedNoise, CompassNoise): a compass
        read every ``compass_period`` T, each reading with its own error of variance
        ``psd_compass/T`` (not integrated), exact arcs between readings; the final θ is
        the last reading, and the first reading replaces the initial θ variance. A
        :class:`~odomkit.noise.ParameterUncertainty` joins any of them but the classical:
        each run draws its bias parameters once (:mod:`odomkit.simulate.plan`). With
        ``robot``, any set of models ``odomkit track`` takes for that vehicle.
    wheel_base : float, optional
        Nominal wheel base B [m] of a differential drive (required for those models).
    runs, partitions : int
        Number N of runs; number K of partitions of *each* segment: the numerical
        resolution. A compass segment is cut into a whole number of steps per compass
        reading, at least K (``MonteCarloRuns.partitions`` gives the largest count).
    seed : int, optional
        Same seed, same numbers, whatever ``workers``, ``chunk_runs`` or ``scheduler``.
    pose0 : array_like, shape (3,)
        Mean initial pose [m, m, rad].
    cov0 : array_like, shape (3,) or (3, 3), optional
        Initial covariance (3 numbers = diagonal of variances); may be singular.
    systematic : SystematicErrors, optional
        Actual-vs-nominal wheel diameters and wheel base (diff model only).
    segment_ends : bool
        Also return the pose of every run at the end of every segment.
    workers : int, optional
        Threads for the local run (default: CPU count).
    chunk_runs : int, optional
        Runs per task (rounded up to whole blocks of 256); only scheduling, never numbers.
    scheduler : str or dask.distributed.Client, optional
        Run the tasks on a Dask cluster instead (see :mod:`odomkit.simulate.distributed`).
    engine : {"auto", "numba", "numpy"}
    progress : Progress
        One stage, ``"Monte Carlo runs"`` of ``runs`` units, advanced by the runs of each
        task as it finishes (:mod:`odomkit.progress`); never changes a number.
    max_work : float
        Largest runs × partitions × segments allowed (:func:`check_size`).
    compass_period : float, optional
        Compass model only: sample period T [s] of the compass (default
        :data:`~odomkit.noise.kelly.DEFAULT_COMPASS_PERIOD`); every segment must last a
        whole number of periods.
    robot : Robot, optional
        The vehicle (required for a tricycle or car; see
        :func:`odomkit.propagate.paths.path_model`).
    sample_period : float, optional
        The odometry's sample period T [s]: each segment (KellyArc, SteerArc) is cut into
        its D/T samples, each with its own noise, instead of K partitions (required with
        per-sample noise, a TricycleNoise; ``MonteCarloRuns.partitions`` gives the most
        samples of a segment).

    Returns
    -------
    MonteCarloRuns

    Examples
    --------
    Without noise every run ends on the nominal pose (Chong–Kleeman Table 1 path):

    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Arc
    >>> mc = simulate_runs([Arc(3, 1)], WheelNoise(0.0, 0.0), 0.4, runs=3, partitions=100,
    ...                    seed=1)
    >>> np.round(mc.final[0], 6).tolist()
    [-0.38357, -0.286535, -5.0]
    """
    start = time.perf_counter()
    path = list(path)
    check_scheduler(scheduler)
    check_size(runs, partitions, len(path), segment_ends=segment_ends, max_work=max_work)
    plan = make_plan(path, noise, wheel_base, partitions, pose0, cov0, systematic, compass_period,
                     robot, sample_period)
    # A compass path may be cut finer than asked (whole steps per compass reading), a
    # sampled path into as many steps as it has samples.
    check_size(runs, plan.partitions, len(path), segment_ends=segment_ends, max_work=max_work)
    seed_used = _resolve_seed(seed)
    engine_used = _pick_engine(engine)
    if plan.kind != "increment":
        engine_used = "numpy"  # the classical and compass kernels exist in numpy only
    tasks = make_tasks(runs, chunk_runs)
    with stage(progress, runs, "Monte Carlo runs"):
        if scheduler is not None:
            from odomkit.simulate.distributed import run_tasks_dask

            results = run_tasks_dask(scheduler, plan, seed_used, tasks, engine_used, segment_ends,
                                     progress.advance)
        else:
            results = _run_tasks_local(plan, seed_used, tasks, engine_used, segment_ends,
                                       workers, progress.advance)
    blocks = [r for task in results for r in task]
    final = np.concatenate([f for f, _ in blocks])
    # The statistics need the spread of the runs too: its 3×3 scatter must be finite.
    dev = final - final.mean(axis=0) if np.all(np.isfinite(final)) else final
    if not np.all(np.isfinite(dev.T @ dev)):
        raise ModelError("the simulated poses (or their spread) are not finite: a number overflowed; "
                         "check the units and the size of the path, noise and initial covariance")
    ends = np.concatenate([e for _, e in blocks]) if segment_ends else None  # type: ignore[misc]
    return MonteCarloRuns(final, ends, int(runs), plan.partitions, seed_used,
                          time.perf_counter() - start, engine_used)


def _run_tasks_local(plan: Plan, seed: int, tasks: list[list[tuple[int, int]]], engine: str,
                     want_ends: bool, workers: int | None, advance: Callable[[int], None],
                     ) -> list[Any]:
    n_workers = (os.cpu_count() or 1) if workers is None else validate.positive_int(workers, "workers")
    if engine == "numba" and plan.kind == "increment":
        _kernels.advance_numba()  # compile once, before the threads race to do it
    results: list[Any] = [None] * len(tasks)
    if n_workers == 1 or len(tasks) == 1:
        for i, task in enumerate(tasks):
            results[i] = run_task(plan, seed, task, engine, want_ends)
            advance(sum(n for _, n in task))
        return results
    with ThreadPoolExecutor(max_workers=n_workers) as pool:
        futures = {pool.submit(run_task, plan, seed, task, engine, want_ends): i
                   for i, task in enumerate(tasks)}
        for fut in as_completed(futures):
            i = futures[fut]
            results[i] = fut.result()
            advance(sum(n for _, n in tasks[i]))
    return results
