"""Run Monte Carlo blocks on a Dask cluster (optional; ``pip install 'odomkit[dask]'``).

Blocks are the unit of randomness (see :mod:`odomkit.simulate.blocks`), so sending tasks
of blocks to Dask workers gives the same numbers as the local thread pool. Dask is only
imported here, never by a local run.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from odomkit.errors import ModelError
from odomkit.simulate.blocks import run_task

__all__ = ["CONNECT_TIMEOUT", "Scheduler", "get_client", "run_tasks_dask"]

if TYPE_CHECKING:
    from odomkit.simulate.plan import Plan

Scheduler = str | object | None
"""A Dask scheduler address (``tcp://host:8786``), a ``dask.distributed.Client``, or None
(run locally). Typed loosely so that dask stays an optional import."""

CONNECT_TIMEOUT = "10s"


def get_client(scheduler: Scheduler) -> tuple[Any, bool]:
    """A ``dask.distributed.Client`` for an address or an existing client, and whether we
    opened it (and so must close it)."""
    try:
        from dask.distributed import Client
    except ImportError as exc:  # pragma: no cover - dask is installed in the test env
        raise ModelError("--scheduler needs dask: pip install 'odomkit[dask]'") from exc
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str):
        raise ModelError(f"scheduler must be an address such as tcp://host:8786 or a Client, "
                         f"got {scheduler!r}")
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT), True
    except ValueError as exc:  # dask's own parse of the address: '', 'a b', 'host:' ...
        raise ModelError(f"--scheduler must be a Dask scheduler address host:port (e.g. "
                         f"tcp://10.0.0.5:8786), got {scheduler!r} ({exc})") from None
    except (OSError, TimeoutError) as exc:
        raise ModelError(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}") from exc


def run_tasks_dask(scheduler: Scheduler, plan: Plan, seed: int, tasks: list[list[tuple[int, int]]],
                   engine: str, want_ends: bool,
                   progress: Callable[[int], None] | None = None) -> list[Any]:
    """Run every task on the cluster; results in task order."""
    from dask.distributed import as_completed

    client, owned = get_client(scheduler)
    try:
        futures = client.map(run_task, [plan] * len(tasks), [seed] * len(tasks), tasks,
                             [engine] * len(tasks), [want_ends] * len(tasks), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list[Any] = [None] * len(tasks)
        for fut in as_completed(futures):
            i = index[fut.key]
            results[i] = fut.result()
            if progress:
                progress(sum(n for _, n in tasks[i]))
        return results
    finally:
        if owned:
            client.close()
