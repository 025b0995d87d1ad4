"""Monte Carlo experiments: simulate, predict, compare, give a verdict; and sweeps."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from odomkit.errors import ModelError
from odomkit.path import Segment
from odomkit.robot import Robot
from odomkit.simulate.engine import Engine, Progress, SystematicErrors, simulate_runs
from odomkit.simulate.stats import _corr, compare, wrap_angle


def _predicted(robot: Robot, noise: Any, path: Sequence[Segment], pose0: ArrayLike,
               cov0: ArrayLike | None) -> tuple[np.ndarray, np.ndarray]:
    """(pose, cov) from :func:`odomkit.propagate.predict.predict`."""
    try:
        from odomkit.propagate.predict import predict
    except ImportError as exc:
        raise ModelError("no covariance prediction available (odomkit.propagate.predict); "
                         "pass theory=(pose, cov)") from exc
    out = predict(robot, noise, path, pose0=pose0, cov0=cov0)
    return np.asarray(out.pose, dtype=float), np.asarray(out.cov, dtype=float)


def theory_summary(pose: ArrayLike, cov: ArrayLike) -> dict[str, Any]:
    """The ``predict`` output shape: pose (θ wrapped), cov, std, corr."""
    pose = np.asarray(pose, dtype=float).copy()
    cov = np.asarray(cov, dtype=float)
    pose[2] = wrap_angle(pose[2])
    return {"pose": pose, "cov": cov, "std": np.sqrt(np.clip(np.diag(cov), 0, None)),
            "corr": _corr(cov)}


def monte_carlo(
    robot: Robot,
    noise: Any,
    path: Sequence[Segment],
    runs: int = 10_000,
    partitions: int = 1000,
    *,
    seed: int | None = 0,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    cov0: ArrayLike | None = None,
    systematic: SystematicErrors | None = None,
    theory: tuple[ArrayLike, ArrayLike] | None = None,
    alpha: float = 0.01,
    workers: int | None = None,
    chunk_runs: int | None = None,
    scheduler: Any = None,
    engine: Engine = "auto",
    progress: Progress | None = None,
) -> dict[str, Any]:
    """Simulate ``runs`` runs of ``path`` and check them against the linear prediction.

    Parameters are those of :func:`odomkit.simulate.simulate_runs`, plus:

    theory : (pose, cov), optional
        Predicted final pose (3,) and covariance (3, 3); by default
        :func:`odomkit.propagate.predict.predict` of the same robot, noise and path.
        The predicted mean is the nominal (noise-free) end pose.
    alpha : float
        Level of each consistency check (see :mod:`odomkit.simulate.stats`).

    Returns
    -------
    dict
        ``theory`` {pose, cov, std, corr}, ``simulation`` {mean, cov, std, corr, se},
        ``z``, ``checks``, ``verdict``, ``consistent``, ``runs``, ``partitions``,
        ``seed``, ``seconds``, ``engine``.

    Examples
    --------
    >>> from odomkit.robot import DiffDrive
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Straight

    A 1 m straight line; its covariance is Chong–Kleeman eq. (27) with k_L = k_R = 1 mm/√m:
    σx² = 2k²D/4, σy² = 2k²D³/(3b²), σyθ = 2k²D²/(2b²), σθ² = 2k²D/b².

    >>> k2, b = 1e-6, 0.4
    >>> cov = [[k2 / 2, 0, 0], [0, 2 * k2 / (3 * b**2), k2 / b**2], [0, k2 / b**2, 2 * k2 / b**2]]
    >>> r = monte_carlo(DiffDrive(b), WheelNoise(1e-3, 1e-3), [Straight(1.0)], runs=2000,
    ...                 partitions=50, seed=3, theory=([1.0, 0.0, 0.0], cov))
    >>> r["verdict"]
    'consistent'
    """
    if theory is None:
        pose_p, cov_p = _predicted(robot, noise, path, pose0, cov0)
    else:
        pose_p, cov_p = _theory_arrays(theory)
    mc = simulate_runs(robot, noise, path, runs, partitions, seed=seed, pose0=pose0, cov0=cov0,
                       systematic=systematic, workers=workers, chunk_runs=chunk_runs,
                       scheduler=scheduler, engine=engine, progress=progress)
    result = compare(mc.final, pose_p, cov_p, alpha)
    result["theory"] = theory_summary(pose_p, cov_p)
    result.update(runs=mc.runs, partitions=mc.partitions, seed=mc.seed, seconds=mc.seconds,
                  engine=mc.engine)
    return result


def _theory_arrays(theory: Any) -> tuple[np.ndarray, np.ndarray]:
    try:
        pose, cov = theory
        pose = np.asarray(pose, dtype=float).reshape(3)
        cov = np.asarray(cov, dtype=float).reshape(3, 3)
    except (TypeError, ValueError) as exc:
        raise ModelError("theory must be (pose (3,), cov (3, 3))") from exc
    return pose, cov


def simulate_sweep(settings: Sequence[Mapping[str, Any]], *, scheduler: Any = None,
                   **common: Any) -> list[dict[str, Any]]:
    """Run :func:`monte_carlo` for every setting of a grid.

    Parameters
    ----------
    settings : sequence of mappings
        Each overrides keyword arguments of :func:`monte_carlo` (``robot``, ``noise``,
        ``path``, ``runs``, ...); ``common`` supplies the rest.
    scheduler : str or Client, optional
        One Dask client is opened for the whole sweep and every setting's blocks run on it.

    Returns
    -------
    list of dict
        One :func:`monte_carlo` result per setting, in order, each with the ``setting``
        that produced it.

    Examples
    --------
    >>> from odomkit.robot import DiffDrive
    >>> from odomkit.noise import WheelNoise
    >>> from odomkit.path import Arc
    >>> zero = ([-0.38357, -0.286535, -5.0], np.zeros((3, 3)))
    >>> out = simulate_sweep([{"noise": WheelNoise(0, 0)}], robot=DiffDrive(0.4),
    ...                      path=[Arc(3, 1)], runs=8, partitions=10, theory=zero)
    >>> [round(float(v), 4) for v in out[0]["simulation"]["mean"]]
    [-0.3836, -0.2865, -5.0]
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
        if owned:
            client.close()
