"""Monte Carlo experiments: simulate, predict, compare, give a verdict; and sweeps."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from odomkit.angles import TWO_PI, wrap_angle
from odomkit.errors import ModelError
from odomkit.noise import NoiseSet
from odomkit.path import Segment
from odomkit.progress import NO_PROGRESS, Progress
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import Robot
from odomkit.simulate.distributed import Scheduler
from odomkit.simulate.engine import MAX_WORK, Engine, check_scheduler, check_size, simulate_runs
from odomkit.simulate.plan import SystematicErrors, resolve_model
from odomkit.simulate.stats import compare, correlations

__all__ = ["monte_carlo", "simulate_sweep", "theory_summary"]


def _predicted(path: Sequence[Segment], noise: NoiseArg, wheel_base: float | None,
               pose0: ArrayLike, cov0: ArrayLike | None, partitions: int,
               compass_period: float | None, robot: Robot | None = None,
               sample_period: float | None = None,
               ) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """(pose, cov, JSON summary) from :func:`odomkit.propagate.predict.predict`: the
    closed form, or (no closed form: bias noise, a steered vehicle, a model beside the
    family's) the step recursion on the same K steps per segment that are simulated (the
    same samples, at a sample period)."""
    from odomkit.propagate.predict import predict

    # The classical model's answer depends on the number of steps: predict the same
    # K steps per segment that are simulated. The consistent models ignore it.
    pieces = partitions if NoiseSet.of(noise).family == "classical" else None
    model = resolve_model(noise, wheel_base, compass_period, robot, sample_period)
    engine: Literal["closed", "recursion"] = "closed" if model.closed_form else "recursion"
    out = predict(path, noise, wheel_base=wheel_base if robot is None else None, pose0=pose0,
                  cov0=cov0, engine=engine, partitions=partitions if engine == "recursion" else pieces,
                  compass_period=compass_period, robot=robot, sample_period=sample_period)
    return np.asarray(out.pose, dtype=float), np.asarray(out.cov, dtype=float), out.to_dict()


def theory_summary(pose: ArrayLike, cov: ArrayLike) -> dict[str, Any]:
    """The ``predict --json`` shape: pose (θ wrapped), cov, std, corr."""
    pose = np.asarray(pose, dtype=float).copy()
    cov = np.asarray(cov, dtype=float)
    pose[2] = wrap_angle(pose[2])
    return {"pose": pose, "cov": cov, "std": np.sqrt(np.clip(np.diag(cov), 0, None)),
            "corr": correlations(cov)}


def _cov_matrix(cov0: ArrayLike | None) -> np.ndarray | None:
    if cov0 is None:
        return None
    cov = np.asarray(cov0, dtype=float)
    return np.diag(cov) if cov.shape == (3,) else cov


def monte_carlo(
    path: Sequence[Segment],
    noise: NoiseArg,
    wheel_base: float | None = None,
    *,
    runs: int = 10_000,
    partitions: int = 1000,
    seed: int | None = 0,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    systematic: SystematicErrors | None = None,
    theory: tuple[ArrayLike, ArrayLike] | None = None,
    alpha: float = 0.01,
    workers: int | None = None,
    chunk_runs: int | None = None,
    scheduler: Scheduler = None,
    engine: Engine = "auto",
    progress: Progress = NO_PROGRESS,
    compass_period: float | None = None,
    max_work: float = MAX_WORK,
    robot: Robot | None = None,
    sample_period: float | None = None,
) -> dict[str, Any]:
    """Simulate ``runs`` runs of ``path`` and check them against the linear prediction.

    Parameters are those of :func:`odomkit.simulate.simulate_runs`, plus:

    theory : (pose, cov), optional
        Predicted final pose (3,) and covariance (3, 3); by default the closed form of
        :func:`odomkit.propagate.predict.predict` for the same path, noise and start
        (where there is none, as with bias noise or a steered vehicle, its step recursion
        on the simulated steps).
        The predicted mean is the nominal (noise-free) end pose. A given heading may be
        wrapped: it is moved by whole turns onto the branch of the nominal continuous end
        heading (θ0 plus the segments' turns).
    alpha : float
        Level of each consistency check (see :mod:`odomkit.simulate.stats`).

    Returns
    -------
    dict
        ``theory`` {pose (θ wrapped to [−π, π) for display), cov, std, corr},
        ``simulation`` {mean (θ continuous), mean_error, cov, std, corr, se}, ``z``,
        ``checks``, ``verdict``, ``consistent``, ``linear_model_ok`` (see
        :func:`odomkit.simulate.compare`), ``runs``, ``partitions``, ``seed``, ``seconds``,
        ``engine``.

    Examples
    --------
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Straight

    A 1 m straight line; its covariance is Chong–Kleeman eq. (27) with k_L = k_R = 1 mm/√m:
    σx² = 2k²D/4, σy² = 2k²D³/(3b²), σyθ = 2k²D²/(2b²), σθ² = 2k²D/b².

    >>> k2, b = 1e-6, 0.4
    >>> cov = [[k2 / 2, 0, 0], [0, 2 * k2 / (3 * b**2), k2 / b**2], [0, k2 / b**2, 2 * k2 / b**2]]
    >>> r = monte_carlo([Straight(1.0)], WheelNoise(1e-3, 1e-3), b, runs=2000, partitions=50,
    ...                 seed=3, theory=([1.0, 0.0, 0.0], cov))
    >>> r["verdict"]
    'consistent'
    """
    # Too large a request is refused before the prediction, which may also take K steps.
    check_scheduler(scheduler)
    check_size(runs, partitions, len(path), max_work=max_work)
    cov0 = _cov_matrix(cov0)
    if theory is None:
        pose_p, cov_p, summary = _predicted(path, noise, wheel_base, pose0, cov0, partitions,
                                            compass_period, robot, sample_period)
    else:
        pose_p, cov_p = _theory_arrays(theory)
        pose_p[2] = _nominal_branch(path, noise, wheel_base, pose0, pose_p[2], compass_period, robot,
                                    sample_period)
        summary = theory_summary(pose_p, cov_p)
    # NaN marks a component the theory leaves undefined; inf, or nothing defined, is overflow.
    if np.isinf(cov_p).any() or not np.isfinite(np.diag(cov_p)).any():
        raise ModelError("the predicted covariance is not finite: a number overflowed; check the "
                         "units and the size of the path, noise and initial covariance")
    mc = simulate_runs(path, noise, wheel_base, runs=runs, partitions=partitions, seed=seed,
                       pose0=pose0, cov0=cov0, systematic=systematic, workers=workers,
                       chunk_runs=chunk_runs, scheduler=scheduler, engine=engine,
                       progress=progress, compass_period=compass_period, max_work=max_work,
                       robot=robot, sample_period=sample_period)
    # θ continuous in every statistic (docs/reference/commands/simulate.md): the simulated
    # mean θ stays continuous; only the theory's pose is shown wrapped
    result = compare(mc.final, pose_p, cov_p, alpha)
    head = {"theory": summary, "simulation": result.pop("simulation"), "z": result.pop("z"),
            "verdict": result.pop("verdict")}
    tail = {"runs": mc.runs, "partitions": mc.partitions, "seed": mc.seed,
            "seconds": mc.seconds, "engine": mc.engine}
    return {**head, **result, **tail}


def _nominal_branch(path: Sequence[Segment], noise: NoiseArg, wheel_base: float | None,
                    pose0: ArrayLike, theta: float, compass_period: float | None,
                    robot: Robot | None = None, sample_period: float | None = None) -> float:
    """``theta`` moved by whole turns onto the branch of the path's nominal, continuous
    end heading θ0 + ΣΔθ: a theory may give its heading wrapped, the runs are continuous."""
    from odomkit.propagate.paths import segment_motion

    model = resolve_model(noise, wheel_base, compass_period, robot, sample_period)
    base = model.robot.wheel_base if model.diff else 1.0  # type: ignore[union-attr]
    end = float(np.asarray(pose0, dtype=float)[2]) + sum(segment_motion(s, base, model.robot)[1]
                                                         for s in path)
    return float(theta + TWO_PI * round((end - theta) / TWO_PI))


def _theory_arrays(theory: Any) -> tuple[np.ndarray, np.ndarray]:
    try:
        pose, cov = theory
        # copies: the heading is moved onto the runs' branch (a Prediction's arrays are read-only)
        pose = np.array(pose, dtype=float).reshape(3)
        cov = np.array(cov, dtype=float).reshape(3, 3)
    except (TypeError, ValueError) as exc:
        raise ModelError("theory must be (pose (3,), cov (3, 3))") from exc
    return pose, cov


def simulate_sweep(settings: Sequence[Mapping[str, Any]], *, scheduler: Scheduler = None,
                   **common: Any) -> list[dict[str, Any]]:
    """Run :func:`monte_carlo` for every setting of a grid.

    Parameters
    ----------
    settings : sequence of mappings
        Each overrides arguments of :func:`monte_carlo` (``path``, ``noise``,
        ``wheel_base``, ``runs``, ...); ``common`` supplies the rest.
    scheduler : str or Client, optional
        One Dask client is opened for the whole sweep and every setting's blocks run on it.

    Returns
    -------
    list of dict
        One :func:`monte_carlo` result per setting, in order, each with the ``setting``
        that produced it.

    Examples
    --------
    Two noise levels on Chong–Kleeman's Table 1 path:

    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Arc
    >>> grid = [{"noise": WheelNoise(k, k)} for k in (0.001, 0.003)]
    >>> out = simulate_sweep(grid, path=[Arc(3, 1)], wheel_base=0.4, runs=2000, partitions=100)
    >>> [r["verdict"] for r in out]
    ['consistent', 'consistent']
    """
    client, owned = None, False
    if scheduler is not None:
        from odomkit.simulate.distributed import get_client

        client, owned = get_client(scheduler)
    try:
        results = []
        for setting in settings:
            kwargs = {**common, **setting}
            result = monte_carlo(scheduler=client, **kwargs)
            result["setting"] = dict(setting)
            results.append(result)
        return results
    finally:
        if owned and client is not None:
            client.close()
