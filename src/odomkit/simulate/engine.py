"""Monte Carlo engine: many noisy runs of a planned segment path.

Each segment is cut into K partitions; every partition gets fresh, independent noise from
the robot's noise model, and the pose is integrated with the exact arc (see
:mod:`odomkit.simulate._kernels`). This is the experiment of Chong–Kleeman section 6.1
(Tables 1–2: 10 000 runs, 10 000 partitions, wheel base 0.4 m).

Reproducibility: runs are grouped into fixed blocks of :data:`BLOCK_RUNS`; block ``b``
draws from its own stream ``SeedSequence(seed, spawn_key=(b,))`` (the b-th child of
``SeedSequence(seed).spawn``) in a fixed order: 3 normals per run for the initial pose,
then, partition after partition along the whole path, 2 normals per run. How blocks are
grouped into chunks, threads or Dask workers therefore never changes a number.
Memory stays bounded: a block holds at most :data:`PARTITION_CHUNK` partitions of noise.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc, Segment, Spin, Straight
from odomkit.robot import CompassOdometry, DiffDrive, GyroOdometry, Robot
from odomkit.simulate import _kernels

BLOCK_RUNS = 256
PARTITION_CHUNK = 512
Engine = Literal["auto", "numba", "numpy"]
Progress = Callable[[int], None]


@dataclass(frozen=True)
class SystematicErrors:
    """Systematic odometry errors of a differential drive, Borenstein–Feng section II-A.

    The robot is *commanded* (its odometry believes it drives) the nominal wheel travels
    of the path; the simulation returns where it *actually* goes:

    - ``E_d = D_R / D_L`` (eq. 2.3), the ratio of the actual wheel diameters;
    - ``E_b = b_actual / b_nominal`` (eq. 2.4), the wheel-base error;
    - ``E_s = D_a / D_n``, the scaling error: actual average diameter
      ``D_a = (D_L + D_R)/2`` over the nominal diameter (section II-A and VI).

    With ``D_L = 2·D_a/(E_d + 1)`` (eq. 4.29) and ``D_R = 2·D_a/(1/E_d + 1)`` (eq. 4.30),
    a wheel that the odometry says moved ``d`` really moved ``d·D/D_n``, i.e.
    ``d_L,true = E_s·2/(E_d + 1)·d_L`` and ``d_R,true = E_s·2·E_d/(E_d + 1)·d_R``, and the
    robot turns by ``(d_R,true − d_L,true)/(E_b·b)``. All three equal 1 for a perfect robot.

    >>> SystematicErrors(E_d=1.0, E_b=1.0, E_s=1.0).wheel_scales()
    (1.0, 1.0)
    """

    E_d: float = 1.0
    E_b: float = 1.0
    E_s: float = 1.0

    def __post_init__(self) -> None:
        for name in ("E_d", "E_b", "E_s"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ModelError(f"SystematicErrors.{name} must be a positive finite number, "
                                 f"got {value!r}")

    def wheel_scales(self) -> tuple[float, float]:
        """(true/nominal travel of the left wheel, of the right wheel), eq. (4.29)–(4.30)."""
        return (self.E_s * 2.0 / (self.E_d + 1.0), self.E_s * 2.0 * self.E_d / (self.E_d + 1.0))


@dataclass(frozen=True)
class Plan:
    """What one run does, in kernel terms (picklable, sent to Dask workers).

    ``coefs[j]`` maps two standard normals to the body motion of one partition of segment
    j (see :mod:`odomkit.simulate._kernels`); ``kind`` is ``"increment"`` (exact arc),
    ``"classical"`` (rotate, then translate) or ``"compass"``.
    """

    kind: str
    coefs: NDArray[np.float64]  # (S, 6)
    partitions: int
    pose0: NDArray[np.float64]  # (3,)
    factor0: NDArray[np.float64]  # (3, 3): initial pose = pose0 + factor0 @ z


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


def _cov_factor(cov0: ArrayLike | None) -> NDArray[np.float64]:
    """A with A·Aᵀ = cov0, from the eigen-decomposition so a singular PSD cov0 works."""
    if cov0 is None:
        return np.zeros((3, 3))
    cov = np.asarray(cov0, dtype=float)
    if cov.shape == (3,):
        cov = np.diag(cov)
    if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
        raise ModelError(f"initial covariance must be 3 variances or a 3x3 matrix, got {cov0!r}")
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-15):
        raise ModelError("initial covariance must be symmetric")
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    # eigenvalues a few ulps below zero are rounding of a PSD matrix, not negative variance
    tol = 1e-12 * max(1.0, float(np.max(np.abs(w))))
    if np.min(w) < -tol:
        raise ModelError(f"initial covariance must be positive semi-definite; eigenvalues {w}")
    return np.asarray(v * np.sqrt(np.clip(w, 0.0, None)))


def _noise_parts(noise: Any) -> list[Any]:
    parts = list(noise) if isinstance(noise, list | tuple) else [noise]
    return [n for n in parts if n is not None]


def _diff_coefs(robot: DiffDrive, noise: Any, path: Sequence[Segment], k: int,
                systematic: SystematicErrors | None) -> NDArray[np.float64]:
    parts = _noise_parts(noise)
    if len(parts) != 1 or not isinstance(parts[0], WheelNoise | ClassicalNoise):
        raise ModelError("the diff model needs one noise model: WheelNoise or ClassicalNoise")
    model = parts[0]
    sys_err = systematic or SystematicErrors()
    scale_left, scale_right = sys_err.wheel_scales()
    b = robot.effective_wheel_base * sys_err.E_b
    coefs = np.empty((len(path), 6))
    for j, seg in enumerate(path):
        if not isinstance(seg, Arc | Straight | Spin):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a diff-drive segment; "
                             "expected arc:L,R, straight:D or spin:DTHETA")
        # commanded travels use the nominal wheel base (a spin is commanded with it)
        left, right = seg.wheel_travel(robot.effective_wheel_base)
        left, right = scale_left * left / k, scale_right * right / k
        if isinstance(model, WheelNoise):
            # Chong–Kleeman eq. (4): each partition's wheel travel has variance k²·|d|
            sigma_l = model.k_left * math.sqrt(abs(left))
            sigma_r = model.k_right * math.sqrt(abs(right))
            # Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b, Borenstein–Feng (2.2)–(2.4)
            coefs[j] = (0.5 * (left + right), 0.5 * sigma_l, 0.5 * sigma_r,
                        (right - left) / b, -sigma_l / b, sigma_r / b)
        else:
            # Chong–Kleeman eq. (1)–(3): fixed σ per step, whatever the step's length
            coefs[j] = (0.5 * (left + right), model.sigma_distance, 0.0,
                        (right - left) / b, 0.0, model.sigma_angle)
    return coefs


def _kelly_coefs(robot: GyroOdometry | CompassOdometry, noise: Any,
                 path: Sequence[Segment], k: int, theta0: float) -> NDArray[np.float64]:
    parts = _noise_parts(noise)
    heading_type = GyroNoise if isinstance(robot, GyroOdometry) else CompassNoise
    speed = [n for n in parts if isinstance(n, SpeedNoise)]
    heading = [n for n in parts if isinstance(n, heading_type)]
    if len(speed) + len(heading) != len(parts) or len(speed) > 1 or len(heading) > 1:
        raise ModelError(f"the {type(robot).__name__} model takes SpeedNoise and "
                         f"{heading_type.__name__}; got {parts!r}")
    alpha_ss = speed[0].alpha_ss if speed else 0.0
    coefs = np.empty((len(path), 6))
    theta_start = theta0
    for j, seg in enumerate(path):
        if not isinstance(seg, KellyArc):
            raise ModelError(f"segment {j + 1} ({seg!r}) is not a speed/yaw-rate segment; "
                             "expected arc:V,OMEGA,T or straight:V,T")
        dt = seg.duration / k
        dd0, dth0 = seg.speed * dt, seg.yaw_rate * dt
        # Kelly Table 1: σ_vv = α_ss·|V|, so a partition's distance has variance α_ss·|Δs|
        sigma_d = math.sqrt(alpha_ss * abs(dd0))
        if isinstance(robot, GyroOdometry):
            # Kelly Table 1: σ_ωω = σ_gg, the integrated heading gains variance σ_gg·Δt
            psd = heading[0].psd_gyro if heading else 0.0
            coefs[j] = (dd0, sigma_d, 0.0, dth0, 0.0, math.sqrt(psd * dt))
        else:
            # white compass error of density σ_θθ sampled every Δt: variance σ_θθ/Δt
            psd = heading[0].psd_compass if heading else 0.0
            sigma_h = math.sqrt(psd / dt) if dt > 0 else 0.0
            coefs[j] = (dd0, sigma_d, theta_start + 0.5 * dth0, dth0, sigma_h, 0.0)
        theta_start += seg.yaw_rate * seg.duration
    return coefs


def make_plan(robot: Robot, noise: Any, path: Sequence[Segment], partitions: int,
              pose0: ArrayLike = (0.0, 0.0, 0.0), cov0: ArrayLike | None = None,
              systematic: SystematicErrors | None = None) -> Plan:
    """Translate robot, noise and path into per-segment kernel coefficients."""
    if not isinstance(partitions, int | np.integer) or partitions < 1:
        raise ModelError(f"partitions must be a positive integer, got {partitions!r}")
    if len(path) == 0:
        raise ModelError("the path needs at least one segment")
    p0 = np.asarray(pose0, dtype=float).reshape(-1)
    if p0.shape != (3,) or not np.all(np.isfinite(p0)):
        raise ModelError(f"initial pose must be three finite numbers x, y, theta; got {pose0!r}")
    k = int(partitions)
    if isinstance(robot, DiffDrive):
        coefs = _diff_coefs(robot, noise, path, k, systematic)
        kind = "classical" if isinstance(_noise_parts(noise)[0], ClassicalNoise) else "increment"
    elif isinstance(robot, GyroOdometry | CompassOdometry):
        if systematic is not None:
            raise ModelError("systematic errors (E_d, E_b, E_s) apply to the diff model only")
        coefs = _kelly_coefs(robot, noise, path, k, float(p0[2]))
        kind = "increment" if isinstance(robot, GyroOdometry) else "compass"
    else:
        raise ModelError(f"simulate supports the diff, gyro and compass models, "
                         f"not {type(robot).__name__}")
    return Plan(kind, coefs, k, p0, _cov_factor(cov0))


def _pick_engine(engine: Engine) -> str:
    if engine == "auto":
        return "numba" if _kernels.have_numba() else "numpy"
    if engine == "numba" and not _kernels.have_numba():
        raise ModelError("engine='numba' needs numba: pip install 'odomkit[fast]'")
    if engine not in ("numba", "numpy"):
        raise ModelError(f"engine must be auto, numba or numpy, got {engine!r}")
    return engine


def _block_sizes(runs: int) -> list[int]:
    return [min(BLOCK_RUNS, runs - start) for start in range(0, runs, BLOCK_RUNS)]


def run_block(plan: Plan, seed: int, block: int, n_runs: int, engine: str,
              want_ends: bool, partition_chunk: int = PARTITION_CHUNK,
              ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Simulate block ``block`` (``n_runs`` runs): final poses (n, 3), segment ends (n, S, 3).

    ``partition_chunk`` only bounds memory; it never changes the numbers.
    """
    rng = np.random.Generator(np.random.SFC64(np.random.SeedSequence(seed, spawn_key=(block,))))
    z_pose = rng.standard_normal((n_runs, 3))
    poses = plan.pose0 + z_pose @ plan.factor0.T
    state = _kernels.new_state(poses)
    n_seg = plan.coefs.shape[0]
    ends = np.empty((n_runs, n_seg, 3)) if want_ends else None
    if plan.kind == "compass":
        advance = _kernels.advance_compass_numpy
    elif plan.kind == "classical":
        advance = _kernels.advance_classical_numpy
    elif engine == "numba":
        advance = _kernels.advance_numba()
    else:
        advance = _kernels.advance_numpy
    buf = np.empty((min(partition_chunk, plan.partitions), 2, n_runs))
    k = plan.partitions
    for j in range(n_seg):
        coef = plan.coefs[j]
        for start in range(0, k, partition_chunk):
            z = buf[: min(partition_chunk, k - start)]
            rng.standard_normal(out=z)
            # the numba kernel resyncs its heading vector at global partition indices
            first = start if plan.kind == "compass" else j * k + start
            advance(state, z, coef, first)
        if ends is not None:
            ends[:, j, :] = state[:3].T
    return state[:3].T.copy(), ends


def _run_task(plan: Plan, seed: int, blocks: list[tuple[int, int]], engine: str,
              want_ends: bool) -> list[tuple[NDArray[np.float64], NDArray[np.float64] | None]]:
    return [run_block(plan, seed, b, n, engine, want_ends) for b, n in blocks]


def make_tasks(runs: int, chunk_runs: int | None) -> list[list[tuple[int, int]]]:
    """Group the blocks (index, size) into tasks of about ``chunk_runs`` runs."""
    if not isinstance(runs, int | np.integer) or runs < 1:
        raise ModelError(f"runs must be a positive integer, got {runs!r}")
    per_task = max(1, math.ceil((chunk_runs or BLOCK_RUNS) / BLOCK_RUNS))
    blocks = list(enumerate(_block_sizes(int(runs))))
    return [blocks[i: i + per_task] for i in range(0, len(blocks), per_task)]


def _resolve_seed(seed: int | None) -> int:
    if seed is None:
        return int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
    if not isinstance(seed, int | np.integer) or seed < 0:
        raise ModelError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def simulate_runs(
    robot: Robot,
    noise: Any,
    path: Sequence[Segment],
    runs: int,
    partitions: int = 1000,
    *,
    seed: int | None = None,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    systematic: SystematicErrors | None = None,
    segment_ends: bool = False,
    workers: int | None = None,
    chunk_runs: int | None = None,
    scheduler: Any = None,
    engine: Engine = "auto",
    progress: Progress | None = None,
) -> MonteCarloRuns:
    """Simulate ``runs`` noisy runs of ``path`` and return their poses.

    Parameters
    ----------
    robot : DiffDrive, GyroOdometry or CompassOdometry
        For DiffDrive the effective wheel base is used.
    noise : noise model or tuple of them
        DiffDrive: :class:`~odomkit.noise.WheelNoise` (variance k²·|d| per partition and
        wheel) or :class:`~odomkit.noise.ClassicalNoise` (fixed σ of D and α per
        partition, each partition a rotation α then a translation D, Chong–Kleeman eq. 1,
        so K = 1 is one step per segment). Gyro:
        SpeedNoise and/or GyroNoise. Compass: SpeedNoise and/or CompassNoise (the heading
        of each partition is the nominal one plus white error of variance
        ``psd_compass/Δt``, not integrated; the final θ is the last such measurement, so
        its variance grows with K and the initial θ variance has no effect).
    path : sequence of Segment
        Arc/Straight/Spin (diff) or KellyArc (gyro, compass).
    runs, partitions : int
        Number N of runs; number K of partitions of *each* segment.
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
    progress : callable, optional
        Called with the number of runs just finished, after each task.

    Returns
    -------
    MonteCarloRuns

    Examples
    --------
    Without noise every run ends on the nominal pose (Chong–Kleeman Table 1 path):

    >>> from odomkit.robot import DiffDrive
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Arc
    >>> mc = simulate_runs(DiffDrive(0.4), WheelNoise(0.0, 0.0), [Arc(3, 1)], runs=3,
    ...                    partitions=100, seed=1)
    >>> np.round(mc.final[0], 6).tolist()
    [-0.38357, -0.286535, -5.0]
    """
    start = time.perf_counter()
    plan = make_plan(robot, noise, path, partitions, pose0, cov0, systematic)
    seed_used = _resolve_seed(seed)
    engine_used = _pick_engine(engine)
    tasks = make_tasks(runs, chunk_runs)
    if scheduler is not None:
        from odomkit.simulate.distributed import run_tasks_dask

        results = run_tasks_dask(scheduler, plan, seed_used, tasks, engine_used, segment_ends,
                                 progress)
    else:
        results = _run_tasks_local(plan, seed_used, tasks, engine_used, segment_ends,
                                   workers, progress)
    blocks = [r for task in results for r in task]
    final = np.concatenate([f for f, _ in blocks])
    ends = np.concatenate([e for _, e in blocks]) if segment_ends else None  # type: ignore[misc]
    return MonteCarloRuns(final, ends, int(runs), plan.partitions, seed_used,
                          time.perf_counter() - start, engine_used)


def _run_tasks_local(plan: Plan, seed: int, tasks: list[list[tuple[int, int]]], engine: str,
                     want_ends: bool, workers: int | None, progress: Progress | None,
                     ) -> list[Any]:
    n_workers = workers if workers is not None else (os.cpu_count() or 1)
    if not isinstance(n_workers, int) or n_workers < 1:
        raise ModelError(f"workers must be a positive integer, got {workers!r}")
    if engine == "numba" and plan.kind == "increment":
        _kernels.advance_numba()  # compile once, before the threads race to do it
    results: list[Any] = [None] * len(tasks)
    if n_workers == 1 or len(tasks) == 1:
        for i, task in enumerate(tasks):
            results[i] = _run_task(plan, seed, task, engine, want_ends)
            if progress:
                progress(sum(n for _, n in task))
        return results
    with ThreadPoolExecutor(max_workers=n_workers) as pool:
        futures = {pool.submit(_run_task, plan, seed, task, engine, want_ends): i
                   for i, task in enumerate(tasks)}
        for fut in as_completed(futures):
            i = futures[fut]
            results[i] = fut.result()
            if progress:
                progress(sum(n for _, n in tasks[i]))
    return results
