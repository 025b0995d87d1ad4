"""Inner loops of the Monte Carlo engine: one block of runs, one stretch of partitions.

Every partition's body motion is an affine map of two standard normals ``z0, z1``::

    Δd = dd0 + a_d·z0 + b_d·z1          Δθ = dθ0 + a_t·z0 + b_t·z1

which covers all incremental models (wheel noise, speed + gyro, classical); see
:mod:`odomkit.simulate.engine`. The pose is integrated with the exact arc
(:func:`odomkit.kinematics.step_displacement`, ``method="exact"``)::

    x' = x + Δd·sinc(Δθ/2)·cos(θ + Δθ/2),  y' = y + Δd·sinc(Δθ/2)·sin(θ + Δθ/2),  θ' = θ + Δθ

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
from odomkit.angles import sinc_half
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


def advance_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                  first_partition: int) -> None:
    """Plain numpy reference: advance ``state`` in place over ``z.shape[0]`` partitions.

    ``z`` has shape (P, 2, B); ``coef`` is ``[dd0, a_d, b_d, dθ0, a_t, b_t]``.
    ``first_partition`` is unused (kept so both kernels share a signature).
    """
    dd = coef[0] + coef[1] * z[:, 0, :] + coef[2] * z[:, 1, :]
    dth = coef[3] + coef[4] * z[:, 0, :] + coef[5] * z[:, 1, :]
    theta = np.empty_like(dth)
    theta[0] = state[2]
    np.cumsum(dth[:-1], axis=0, out=theta[1:])
    theta[1:] += state[2]
    dx, dy = step_displacement(theta, dd, dth, "exact")
    state[0] += dx.sum(axis=0)
    state[1] += dy.sum(axis=0)
    state[2] = theta[-1] + dth[-1]
    state[3] = np.cos(state[2])
    state[4] = np.sin(state[2])


def advance_classical_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                            first_partition: int) -> None:
    """The classical step map: rotate by α = Δθ, then translate D = Δd along the new
    heading (Chong–Kleeman eq. 1), as :mod:`odomkit.propagate` linearises it."""
    dd = coef[0] + coef[1] * z[:, 0, :] + coef[2] * z[:, 1, :]
    dth = coef[3] + coef[4] * z[:, 0, :] + coef[5] * z[:, 1, :]
    theta_after = state[2] + np.cumsum(dth, axis=0)
    state[0] += (dd * np.cos(theta_after)).sum(axis=0)
    state[1] += (dd * np.sin(theta_after)).sum(axis=0)
    state[2] = theta_after[-1]
    state[3] = np.cos(state[2])
    state[4] = np.sin(state[2])


def advance_compass_numpy(state: State, z: NDArray[np.float64], coef: NDArray[np.float64],
                          first_partition: int) -> None:
    """Direct heading (compass): the heading of partition i is the nominal heading at its
    middle plus white error ``sigma·z1`` (not integrated, Kelly section 3.1).

    ``coef`` is ``[dd0, sigma_d, theta_mid_0, dθ0, sigma_heading, 0]`` with theta_mid_0
    the nominal heading at the middle of the segment's first partition;
    ``first_partition`` counts from the start of the segment. ``state[2]`` becomes the
    last *measured* heading (the compass error is not integrated).
    """
    p = z.shape[0]
    dd = coef[0] + coef[1] * z[:, 0, :]
    theta_mid = coef[2] + coef[3] * (first_partition + np.arange(p))[:, None]
    heading = theta_mid + coef[4] * z[:, 1, :]
    length = dd * sinc_half(coef[3])
    state[0] += (length * np.cos(heading)).sum(axis=0)
    state[1] += (length * np.sin(heading)).sum(axis=0)
    # The measured heading at the end of the stretch: nominal end heading plus the last
    # partition's compass error.
    state[2] = coef[2] + coef[3] * (first_partition + p - 0.5) + coef[4] * z[-1, 1, :]


def advance_numba() -> Callable[[State, NDArray[np.float64], NDArray[np.float64], int], None]:
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

