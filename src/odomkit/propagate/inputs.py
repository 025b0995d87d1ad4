"""Step maps the propagation engines linearise: F_k, G_k and their compact terms.

The exact arc, midpoint and Euler maps are :mod:`odomkit.kinematics`; this module adds the
classical rotate-then-translate map of Chong–Kleeman eq. (1) (``method="classical"``) and
:func:`step_terms`, the six numbers per step the prefix-sum engines need. What each noise
model contributes per step (Q_k, bias sensitivities) is the model's own answer
(:mod:`odomkit.noise`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.angles import sinc_half_pair
from odomkit.errors import ModelError
from odomkit.kinematics import step_displacement, step_jacobians

__all__ = [
    "ENGINE_METHODS",
    "classical_step_displacement",
    "classical_step_jacobians",
    "any_step_displacement",
    "any_step_jacobians",
    "step_terms",
]

ENGINE_METHODS = ("exact", "midpoint", "euler", "classical")


def _f(a: ArrayLike) -> NDArray[np.float64]:
    return np.asarray(a, dtype=float)


def classical_step_displacement(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(Δx, Δy) of the classical step: rotate by α = Δθ, then translate D = Δd along
    the new heading (Chong–Kleeman eq. 1)."""
    heading = _f(theta) + _f(dtheta)
    return _f(dd) * np.cos(heading), _f(dd) * np.sin(heading)


def classical_step_jacobians(
    theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """F = ∂f/∂(x, y, θ) (M, 3, 3) and G = ∂f/∂(D, α) (M, 3, 2) of Chong–Kleeman eq. (1).

    ``G = [[cos(θ+α), −D sin(θ+α)], [sin(θ+α), D cos(θ+α)], [0, 1]]`` (eq. 3). Unlike
    the arc, the whole rotation acts before the translation, so ∂x/∂α equals ∂x/∂θ.

    Examples
    --------
    >>> F, G = classical_step_jacobians([0.0], [1.0], [0.0])
    >>> G[0].tolist()
    [[1.0, -0.0], [0.0, 1.0], [0.0, 1.0]]
    """
    theta, dd, dtheta = np.broadcast_arrays(_f(theta), _f(dd), _f(dtheta))
    dx, dy = classical_step_displacement(theta, dd, dtheta)
    F = np.zeros(theta.shape + (3, 3))
    F[..., 0, 0] = F[..., 1, 1] = F[..., 2, 2] = 1.0
    F[..., 0, 2], F[..., 1, 2] = -dy, dx
    G = np.zeros(theta.shape + (3, 2))
    heading = theta + dtheta
    G[..., 0, 0], G[..., 1, 0] = np.cos(heading), np.sin(heading)
    G[..., 0, 1], G[..., 1, 1] = -dy, dx
    G[..., 2, 1] = 1.0
    return F, G


def any_step_displacement(theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: str):
    """:func:`odomkit.kinematics.step_displacement`, plus ``method="classical"``."""
    if method == "classical":
        return classical_step_displacement(theta, dd, dtheta)
    return step_displacement(theta, dd, dtheta, method)  # type: ignore[arg-type]


def any_step_jacobians(theta: ArrayLike, dd: ArrayLike, dtheta: ArrayLike, method: str):
    """:func:`odomkit.kinematics.step_jacobians`, plus ``method="classical"``."""
    if method == "classical":
        return classical_step_jacobians(theta, dd, dtheta)
    return step_jacobians(theta, dd, dtheta, method)  # type: ignore[arg-type]


def step_terms(
    theta: NDArray[np.float64], dd: NDArray[np.float64], dtheta: NDArray[np.float64],
    method: str,
) -> tuple[NDArray[np.float64], ...]:
    """(Δx, Δy, g00, g01, g10, g11) of each step as 1-D arrays (n,).

    The same numbers as :func:`any_step_jacobians` (F = I + (−Δy, Δx, 0) e_θ^T and
    G = [[g00, g01], [g10, g11], [0, 1]]) without building (n, 3, 3) arrays: the
    prefix-sum engines need only these six per step.
    """
    if method == "euler":
        c, s = np.cos(theta), np.sin(theta)
        return dd * c, dd * s, c, np.zeros_like(c), s, np.zeros_like(c)
    if method == "classical":
        heading = theta + dtheta
        c, s = np.cos(heading), np.sin(heading)
        dx, dy = dd * c, dd * s
        return dx, dy, c, -dy, s, dx
    heading = theta + 0.5 * dtheta
    c, s = np.cos(heading), np.sin(heading)
    if method == "midpoint":
        dx, dy = dd * c, dd * s
        return dx, dy, c, -0.5 * dy, s, 0.5 * dx
    if method != "exact":
        raise ModelError(f"unknown method {method!r}; expected one of {', '.join(ENGINE_METHODS)}")
    f, df = sinc_half_pair(dtheta)
    fc, fs = f * c, f * s
    dx, dy = dd * fc, dd * fs
    ddf = dd * df
    # kinematics.step_jacobians: ∂/∂Δθ [Δd·f·cos(θ+Δθ/2)] = Δd·(f'·cos − f·sin/2)
    return dx, dy, fc, ddf * c - 0.5 * dy, fs, ddf * s + 0.5 * dx
