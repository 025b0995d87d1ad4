"""Monte Carlo blocks and tasks: the unit of randomness and the unit of work.

Runs are grouped into fixed blocks of :data:`BLOCK_RUNS`; block ``b`` draws from its own
stream ``SeedSequence(seed, spawn_key=(b,))`` (the b-th child of ``SeedSequence(seed).spawn``)
in a fixed order: 3 normals per run for the initial pose, then (with bias noise) p normals
per run for its bias parameters (one draw per run, :mod:`odomkit.simulate.plan`), then,
partition after partition along the whole path (K per segment, or a segment's samples
at a sample period), 2 normals per run (3 with a lateral slip:
the third moves the partition across its chord). A task is a list of
blocks; how blocks are grouped into tasks, and tasks onto threads
(:mod:`odomkit.simulate.engine`) or Dask workers (:mod:`odomkit.simulate.distributed`),
therefore never changes a number. Memory stays
bounded: a block holds at most :data:`PARTITION_CHUNK` partitions of noise.

Both executors import this module; neither imports the other's internals.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import ModelError
from odomkit.simulate import _kernels
from odomkit.simulate.plan import Plan

__all__ = ["BLOCK_RUNS", "PARTITION_CHUNK", "make_tasks", "run_block", "run_task"]

BLOCK_RUNS = 256
PARTITION_CHUNK = 512


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
    shifts = None
    if plan.bias is not None:
        # One bias draw per run: every partition of segment j moves by bias[j] @ zβ.
        z_bias = rng.standard_normal((n_runs, plan.bias.shape[-1]))
        shifts = np.einsum("sip,np->sin", plan.bias, z_bias)  # (S, 2, n_runs)
        if plan.bias_heading is not None:
            # A heading offset moves every compass reading, the first (the start) too.
            offset = z_bias @ plan.bias_heading
            poses[:, 2] += offset
            shifts[:, 1, :] = offset
    state = _kernels.new_state(poses)
    n_seg = plan.coefs.shape[0]
    ends = np.empty((n_runs, n_seg, 3)) if want_ends else None
    advance: Callable[..., None]
    if plan.kind == "compass":
        advance = _kernels.advance_compass_numpy
    elif plan.kind == "classical":
        advance = _kernels.advance_classical_numpy
    elif engine == "numba":
        advance = _kernels.advance_numba()
    else:
        advance = _kernels.advance_numpy
    # One row of normals per partition and run for each of (Δd, Δθ), and a third for the
    # lateral slip: drawn partition after partition, so the chunking changes no number,
    # and without a slip the stream is the one it always was.
    rows = 2 if plan.lateral is None else 3
    buf = np.empty((min(partition_chunk, plan.partitions), rows, n_runs))
    # Kernel steps of each segment: K, or its samples at a sample period (Plan.counts).
    counts = [plan.partitions] * n_seg if plan.counts is None else [int(c) for c in plan.counts]
    done = 0  # kernel steps of the segments before
    for j in range(n_seg):
        coef = plan.coefs[j]
        k = counts[j]
        slip = None if plan.lateral is None else float(plan.lateral[j])
        for start in range(0, k, partition_chunk):
            z = buf[: min(partition_chunk, k - start)]
            rng.standard_normal(out=z)
            # the numba kernel resyncs its heading vector at global partition indices
            first = start if plan.kind == "compass" else done + start
            if shifts is None and slip is None:
                advance(state, z, coef, first)
            else:
                advance(state, z, coef, first, None if shifts is None else shifts[j], slip)
        done += k
        if ends is not None:
            ends[:, j, :] = state[:3].T
    return state[:3].T.copy(), ends


def run_task(plan: Plan, seed: int, blocks: list[tuple[int, int]], engine: str,
             want_ends: bool) -> list[tuple[NDArray[np.float64], NDArray[np.float64] | None]]:
    """Run the blocks ``[(index, size), ...]`` of one task in order: what one thread or one
    Dask worker executes (see :func:`make_tasks`)."""
    return [run_block(plan, seed, b, n, engine, want_ends) for b, n in blocks]


def make_tasks(runs: int, chunk_runs: int | None) -> list[list[tuple[int, int]]]:
    """Group the blocks (index, size) into tasks of about ``chunk_runs`` runs."""
    if not isinstance(runs, int | np.integer) or runs < 1:
        raise ModelError(f"runs must be a positive integer, got {runs!r}")
    if chunk_runs is not None and (not isinstance(chunk_runs, int | np.integer) or chunk_runs < 1):
        raise ModelError(f"chunk_runs must be a positive integer, got {chunk_runs!r}")
    per_task = max(1, math.ceil((chunk_runs or BLOCK_RUNS) / BLOCK_RUNS))
    blocks = list(enumerate(_block_sizes(int(runs))))
    return [blocks[i: i + per_task] for i in range(0, len(blocks), per_task)]
