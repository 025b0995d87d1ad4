"""Dead reckoning: body steps -> pose track, vectorised over samples.

The heading is a prefix sum of Δθ, so it is known for every step at once; each step's
displacement then depends only on that heading, and positions are prefix sums too. No
Python loop runs per sample.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import jit, validate
from odomkit.angles import unwrap_angle
from odomkit.errors import ModelError
from odomkit.kinematics import METHODS, Method, step_displacement

__all__ = ["dead_reckon", "dead_reckon_direct_heading", "path_length"]

_METHOD_CODE = {"euler": 0, "midpoint": 1, "exact": 2}
# Below this many steps the numpy path is as fast and needs no compilation.
_NUMBA_FROM = 20_000


def _numba_kernel() -> Callable[..., None] | None:
    """The compiled dead-reckoning kernel, or None without numba (see :mod:`odomkit.jit`)."""
    module = jit.load("_integrate_numba", stacklevel=4)
    return None if module is None else module.dead_reckon_kernel


def dead_reckon(
    dd: ArrayLike,
    dtheta: ArrayLike,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    method: Method = "exact",
    engine: str = "auto",
) -> NDArray[np.float64]:
    """Integrate body steps into a pose track.

    Parameters
    ----------
    dd : array_like, shape (M,)
        Arc length travelled by the reference point in each step [m] (negative = reverse).
    dtheta : array_like, shape (M,)
        Heading change of each step [rad].
    pose0 : array_like, shape (3,)
        Initial pose [x (m), y (m), θ (rad)].
    method : {"exact", "midpoint", "euler"}
        See :func:`odomkit.kinematics.step_displacement`.
    engine : {"auto", "numpy", "numba"}
        ``auto`` uses the numba kernel (``odomkit[fast]``) for long logs when installed.
        Both give the same poses to about 1e-15 relative.

    Returns
    -------
    poses : ndarray, shape (M + 1, 3)
        ``[x, y, θ]`` before the first step and after each step; θ is continuous (not
        wrapped).

    Examples
    --------
    A quarter circle of radius 1 m driven in 1000 steps ends at (1, 1, π/2):

    >>> n = 1000
    >>> p = dead_reckon(np.full(n, np.pi / 2 / n), np.full(n, np.pi / 2 / n))
    >>> np.allclose(p[-1], [1.0, 1.0, np.pi / 2])
    True
    """
    if method not in METHODS:
        raise ModelError(f"unknown integration method {method!r}; expected one of {', '.join(METHODS)}")
    dd = np.asarray(dd, dtype=float)
    dtheta = np.asarray(dtheta, dtype=float)
    if dd.shape != dtheta.shape or dd.ndim != 1:
        raise ModelError(f"dd and dtheta must be 1-D of equal length, got {dd.shape} and {dtheta.shape}")
    validate.finite_array(dd, "dd")
    validate.finite_array(dtheta, "dtheta")
    p0 = validate.pose(pose0, "initial pose")
    poses = np.empty((dd.size + 1, 3))
    if engine == "numba" or (engine == "auto" and dd.size >= _NUMBA_FROM):
        kernel = _numba_kernel()
        if kernel is not None:
            kernel(dd, dtheta, p0[0], p0[1], p0[2], _METHOD_CODE[method], poses)
            return poses
        if engine == "numba":
            raise ModelError("engine='numba' needs numba: pip install 'odomkit[fast]'")
    elif engine not in ("auto", "numpy"):
        raise ModelError(f"unknown engine {engine!r}; expected auto, numpy or numba")
    # Prefix sums that start from the initial value add in the same order as the numba
    # kernel, so both give the very same headings.
    poses[0] = p0
    poses[1:, 2] = dtheta
    np.cumsum(poses[:, 2], out=poses[:, 2])
    dx, dy = step_displacement(poses[:-1, 2], dd, dtheta, method)
    poses[1:, 0], poses[1:, 1] = dx, dy
    np.cumsum(poses[:, 0], out=poses[:, 0])
    np.cumsum(poses[:, 1], out=poses[:, 1])
    return poses


def dead_reckon_direct_heading(
    dd: ArrayLike,
    heading: ArrayLike,
    xy0: ArrayLike = (0.0, 0.0),
    method: Method = "exact",
) -> NDArray[np.float64]:
    """Direct-heading odometry (Kelly section 4.1): heading is measured, not integrated.

    Parameters
    ----------
    dd : array_like, shape (M,)
        Distance travelled in each step [m].
    heading : array_like, shape (M + 1,)
        Measured heading at every row [rad]; it is unwrapped so that a compass jump from
        +π to −π is not read as a full turn.
    xy0 : array_like, shape (2,)
        Initial position [m].
    """
    heading = unwrap_angle(np.asarray(heading, dtype=float))
    dd = np.asarray(dd, dtype=float)
    if heading.shape != (dd.size + 1,):
        raise ModelError(f"heading must have one more sample than dd: {heading.shape} vs {dd.shape}")
    xy0 = np.asarray(xy0, dtype=float).reshape(2)
    return dead_reckon(dd, np.diff(heading), (xy0[0], xy0[1], heading[0]), method)


def path_length(dd: ArrayLike) -> float:
    """Distance travelled by the reference point, Σ|Δd| [m] (reversing counts)."""
    return float(np.sum(np.abs(np.asarray(dd, dtype=float))))
