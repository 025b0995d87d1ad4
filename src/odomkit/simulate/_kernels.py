"""Inner loops of the Monte Carlo engine: one block of runs, one stretch of partitions.

Every partition's body motion is an affine map of two standard normals ``z0, z1``::

    Δd = dd0 + a_d·z0 + b_d·z1          Δθ = dθ0 + a_t·z0 + b_t·z1

which covers all incremental models (wheel noise, speed + gyro, classical); see
:mod:`odomkit.simulate.engine`. A run's bias draw adds a per-run constant ``shift``
(2, B) to (Δd, Δθ) of every partition of a segment (:mod:`odomkit.simulate.plan`). The
pose is integrated with the exact arc (:func:`odomkit.kinematics.step_displacement`, ``method="exact"``)::

    x' = x + Δd·sinc(Δθ/2)·cos(θ + Δθ/2),  y' = y + Δd·sinc(Δθ/2)·sin(θ + Δθ/2),  θ' = θ + Δθ

A lateral slip (``lateral`` = its σ for the segment's partitions, z of three rows) moves
each partition by ε = σ·z2 across the run's own chord: x −= ε·sin θ̄, y += ε·cos θ̄ with
θ̄ the chord direction of the step map (θ + Δθ/2 here, θ + α for the classical map).

The numba kernel (:mod:`odomkit.simulate._numba`) avoids two of three transcendental
calls per step by turning a unit heading vector with series sin/cos of the half angle;
rounding would slowly denormalise the vector, so it is recomputed from the separately
summed θ every 64 partitions, counted from the start of the path, so the numbers never
depend on how partitions are chunked. :func:`advance_numpy` is the plain vectorised
reference with the same arithmetic meaning (equal to rounding, not bit for bit).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from odomkit import jit
from odomkit.errors import ModelError
from odomkit.kinematics import step_displacement

__all__ = [
    "advance_classical_numpy", "advance_compass_numpy", "advance_numba", "advance_numpy", "have_numba",
    "new_state", "State"
]

State = NDArray[np.float64]  # shape (5, B): x, y, θ, cos θ, sin θ


def new_state(pose0: NDArray[np.float64]) -> State:
    """Kernel state for initial poses ``pose0`` of shape (B, 3)."""
    state = np.empty((5, pose0.shape[0]))
    state[0:3] = pose0.T
    state[3] = np.cos(pose0[:, 2])
    state[4] = np.sin(pose0[:, 2])
    return state


def _increments(z: NDArray[np.float64], coef: NDArray[np.float64],
                shift: NDArray[np.float64] | None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(Δd, Δθ) of each partition and run, (P, B): coef's affine map of z, plus ``shift``."""
    if shift is None:
        return (coef[0] + coef[1] * z[:, 0, :] + coef[2] * z[:, 1, :],
                coef[3] + coef[4] * z[:, 0, :] + coef[5] * z[:, 1, :])
    return (coef[0] + shift[0] + coef[1] * z[:, 0, :] + coef[2] * z[:, 1, :],
            coef[3] + shift[1] + coef[4] * z[:, 0, :] + coef[5] * z[:, 1, :])


def _slip(z: NDArray[np.float64], lateral: float | None, chord: NDArray[np.float64],
          dx: NDArray[np.float64], dy: NDArray[np.float64]) -> None:
    """Add each partition's sideways slip ε = σ·z2 along the normal of its chord
    direction ``chord`` (P, B) to the displacements dx, dy (P, B), in place."""
    if lateral is None:
        return
    eps = lateral * z[: chord.shape[0], 2, :]
    dx -= eps * np.sin(chord)
    dy += eps * np.cos(chord)


def advance_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                  first_partition: int, shift: NDArray[np.float64] | None = None,
                  lateral: float | None = None) -> None:
    """Plain numpy reference: advance ``state`` in place over ``z.shape[0]`` partitions.

    ``z`` has shape (P, 2, B), or (P, 3, B) with a lateral slip; ``coef`` is
    ``[dd0, a_d, b_d, dθ0, a_t, b_t]``; ``shift`` (2, B), optional, is added to every
    partition's (Δd, Δθ) of each run (its bias); ``lateral`` is the σ [m] of each
    partition's sideways slip (times z[:, 2]). ``first_partition`` is unused (kept so
    both kernels share a signature).
    """
    dd, dth = _increments(z, coef, shift)
    theta = np.empty_like(dth)
    theta[0] = state[2]
    np.cumsum(dth[:-1], axis=0, out=theta[1:])
    theta[1:] += state[2]
    dx, dy = step_displacement(theta, dd, dth, "exact")
    _slip(z, lateral, theta + 0.5 * dth, dx, dy)
    state[0] += dx.sum(axis=0)
    state[1] += dy.sum(axis=0)
    state[2] = theta[-1] + dth[-1]
    state[3] = np.cos(state[2])
    state[4] = np.sin(state[2])


def advance_classical_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                            first_partition: int, shift: NDArray[np.float64] | None = None,
                            lateral: float | None = None) -> None:
    """The classical step map: rotate by α = Δθ, then translate D = Δd along the new
    heading (Chong–Kleeman eq. 1), as :mod:`odomkit.propagate` linearises it; a lateral
    slip moves across that new heading."""
    dd, dth = _increments(z, coef, shift)
    theta_after = state[2] + np.cumsum(dth, axis=0)
    dx, dy = dd * np.cos(theta_after), dd * np.sin(theta_after)
    _slip(z, lateral, theta_after, dx, dy)
    state[0] += dx.sum(axis=0)
    state[1] += dy.sum(axis=0)
    state[2] = theta_after[-1]
    state[3] = np.cos(state[2])
    state[4] = np.sin(state[2])


def advance_compass_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                          first_partition: int, shift: NDArray[np.float64] | None = None,
                          lateral: float | None = None) -> None:
    """Direct heading (compass) sampled every T: one heading error per compass reading,
    not per partition (Kelly section 3.1; ``track``'s model of a compass log).

    ``coef`` is ``[dd, σ_d, θ_start, dθ, σ_h, q, m]`` (:mod:`odomkit.simulate.plan`):
    the segment's kernel steps g = 0 … m−1 are q per compass interval; step g runs from
    the nominal heading θ_start + g·dθ plus the measured heading's error, linear between
    the errors e_j, e_{j+1} of the interval's two readings (so the q steps make up the
    exact arc from one reading to the next), over a distance dd + σ_d·z0. The error of the
    reading that ends an interval, σ_h·z1, is drawn at the interval's first step (z1 of
    the other steps is unused); the segment's first reading is the one the previous
    segment (or the start pose) ended on: e_0 = θ − θ_start. Steps g >= m do nothing
    (another segment needs more). ``state[2]`` is the measured heading (the compass error
    is not integrated); between calls ``state[3:5]`` carry the errors of the current
    interval's readings (the kernel state's cos/sin slots, unused by this kernel).
    ``first_partition`` counts from the start of the segment. ``shift`` (2, B), a run's
    bias: row 0 is added to every step's distance, row 1 to every reading's error (a
    heading offset; the start reading's is in the start pose already). ``lateral``, the σ
    of each step's sideways slip (times z2), moves it across its chord.
    """
    dd0, sigma_d, theta_start, dth0, sigma_h = coef[:5]
    q, m = int(coef[5]), int(coef[6])
    act = max(0, min(z.shape[0], m - first_partition))
    if act == 0:
        return
    g = first_partition + np.arange(act)
    sub = g % q
    new = sub == 0  # steps that open an interval and draw its end reading's error
    aligned = first_partition % q == 0
    if first_partition == 0:
        base = [state[2] - theta_start]  # the reading the segment starts on
    elif aligned:
        base = [state[3]]
    else:
        base = [state[3], state[4]]
    fresh = sigma_h * z[:act, 1, :][new]
    if shift is not None:
        fresh = fresh + shift[1]
    errs = np.concatenate([np.asarray(base), fresh])
    idx = np.cumsum(new) - (1 if aligned else 0)
    e_lo, e_hi = errs[idx], errs[idx + 1]  # (act, B): the interval's two readings
    w0 = (sub / q)[:, None]
    w1 = ((sub + 1) / q)[:, None]
    err0 = e_lo + (e_hi - e_lo) * w0
    err1 = e_lo + (e_hi - e_lo) * w1
    heading = theta_start + dth0 * g[:, None] + err0
    dist = dd0 + sigma_d * z[:act, 0, :] if shift is None else dd0 + shift[0] + sigma_d * z[:act, 0, :]
    turn = dth0 + (err1 - err0)
    dx, dy = step_displacement(heading, dist, turn, "exact")
    _slip(z, lateral, heading + 0.5 * turn, dx, dy)
    state[0] += dx.sum(axis=0)
    state[1] += dy.sum(axis=0)
    end = first_partition + act
    state[2] = theta_start + dth0 * end + err1[-1]
    if end % q == 0:
        state[3] = e_hi[-1]  # on a reading: the next call opens a new interval
    else:
        state[3], state[4] = e_lo[-1], e_hi[-1]


def advance_numba() -> Callable[..., None]:
    """The compiled kernel of :mod:`odomkit.simulate._numba`, loaded by
    :func:`odomkit.jit.load` (compiled, or read from numba's cache, on first call);
    ModelError without numba."""
    module = jit.load("simulate._numba")
    if module is None:
        raise ModelError("engine='numba' needs numba: pip install 'odomkit[fast]'")
    return module.advance_state


def have_numba() -> bool:
    """Whether the numba kernel can be loaded (warns once, via :func:`odomkit.jit.load`,
    when it cannot)."""
    return jit.load("simulate._numba") is not None

