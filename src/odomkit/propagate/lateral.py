"""Lateral slip in the covariance engines: a running sum on the position block.

A position-only white noise (:class:`odomkit.noise.LateralSlipNoise`: a sideways
displacement ε_k ~ N(0, c_k), c_k = α_lat·|Δd_k|, along the step's unit normal u_k)
needs no engine of its own. Why, for the linearised dead-reckoning recursion
(Chong–Kleeman eq. 2) with the slip as a third input of G::

    P_{k+1} = F_k P_k F_kᵀ + G_k Q_k G_kᵀ + c_k ū_k ū_kᵀ,      ū_k = (u_k, 0) ∈ R³

Integrated heading: F_k = I + w_k e_θᵀ, w_k = (−Δy_k, Δx_k, 0) (Kelly eq. 9–11 in step
form, :mod:`odomkit.propagate.transition`). Since e_θᵀ ū = 0, F_k ū = ū, so
F_k (ū ūᵀ) F_kᵀ = ū ūᵀ: a pure-position perturbation [δp; 0] passes every step
unchanged. Write P_k = P'_k + L_k with P'_k the recursion without the slip and
L_k = Σ_{j<k} c_j ū_j ū_jᵀ (zero outside the x–y block). Then F_k L_k F_kᵀ = L_k and

    P_{k+1} = (F_k P'_k F_kᵀ + G_k Q_k G_kᵀ) + L_k + c_k ū_k ū_kᵀ = P'_{k+1} + L_{k+1},

so by induction the slip adds exactly the running sum L_k to the x–y block of P_k at
every row: no cross term with θ and no interaction with any other noise (nor with the
start covariance). The same holds for Kelly's transition-matrix solution
(Φ(k, j+1) ū = ū), for a bias (its sensitivity S_k does not see the slip), and for
direct-heading odometry, whose positions are sums of step displacements and whose
heading is measured (Kelly section 3.1): ε_k is independent of every other error and
moves the position alone. Every engine therefore runs as before and adds L_k to its
rows (:func:`accumulate_lateral`, carried from chunk to chunk: one compiled pass, or the
numpy reference :func:`lateral_sums` and :func:`add_lateral` without numba).

The direction: θ̄_k is the chord direction of the step map (:func:`lateral_headings`):
θ_k + Δθ_k/2 for the exact arc and the midpoint map, θ_k for Euler, θ_k + Δθ_k for the
classical map (rotate, then translate; Chong–Kleeman eq. 1). u uᵀ = [[s², −sc], [−sc, c²]]
with (c, s) = (cos θ̄, sin θ̄), i.e. ½[[1 − cos 2θ̄, −sin 2θ̄], [−sin 2θ̄, 1 + cos 2θ̄]].

Over a constant-curvature segment (length D, heading θ_0 → θ_0 + Δθ, uniform in the arc
length) the sum has closed forms (:func:`lateral_segment_cov`): cut into N equal steps,
the chord headings are θ_0 + (j + ½)Δθ/N and Σ_j cos(2θ̄_j) = N·cos 2θ_m·D_N with
θ_m = θ_0 + Δθ/2 and D_N = sin Δθ/(N·sin(Δθ/N)) (a Dirichlet kernel); as N → ∞,
D_∞ = sin Δθ/Δθ, the integral ∫ u uᵀ α|ds|.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import jit
from odomkit.angles import sinc
from odomkit.errors import ModelError
from odomkit.propagate.inputs import ENGINE_METHODS

__all__ = ["accumulate_lateral", "add_lateral", "lateral_headings", "lateral_segment_cov", "lateral_sums"]

# θ̄ = θ + w·Δθ of each step map (lateral_headings)
_CHORD_WEIGHT = {"exact": 0.5, "midpoint": 0.5, "euler": 0.0, "classical": 1.0}


def lateral_headings(theta: ArrayLike, dtheta: ArrayLike, method: str) -> NDArray[np.float64]:
    """Chord direction θ̄ of each step [rad] under a step map (the heading of its
    displacement, :func:`odomkit.propagate.inputs.step_terms`).

    Examples
    --------
    >>> lateral_headings([0.0], [0.2], "exact").tolist(), lateral_headings([0.0], [0.2], "classical").tolist()
    ([0.1], [0.2])
    """
    theta = np.asarray(theta, dtype=float)
    dtheta = np.asarray(dtheta, dtype=float)
    if method == "euler":
        return np.broadcast_arrays(theta, dtheta)[0].copy()
    if method == "classical":
        return theta + dtheta
    if method in ("exact", "midpoint"):
        return theta + 0.5 * dtheta
    raise ModelError(f"unknown method {method!r}; expected one of {', '.join(ENGINE_METHODS)}")


def lateral_sums(theta: ArrayLike, dtheta: ArrayLike, var_lateral: ArrayLike, method: str,
                 start: ArrayLike | None = None) -> NDArray[np.float64]:
    """Running sums L_k of the slip's position covariance after each of n steps, (n, 3):
    (xx, xy, yy) [m²] of Σ_{j≤k} c_j u_j u_jᵀ (module docstring), plus ``start`` (3,),
    the sums before the first step (carried from the previous chunk).

    The sums are accumulated one step after the other (``np.cumsum`` is sequential), so
    a carried ``start`` gives the same bits as one pass over the whole log.

    Parameters
    ----------
    theta, dtheta : array_like, shape (n,)
        Heading at the start of each step and its change [rad].
    var_lateral : array_like, shape (n,)
        Variance c_k of each step's sideways displacement [m²].
    method : {"exact", "midpoint", "euler", "classical"}
    start : array_like, shape (3,), optional

    Examples
    --------
    >>> lateral_sums([0.0, 0.0], [0.0, 0.0], [1.0, 2.0], "exact").tolist()   # along x: var y
    [[0.0, 0.0, 1.0], [0.0, 0.0, 3.0]]
    """
    heading = lateral_headings(theta, dtheta, method)
    c, s = np.cos(heading), np.sin(heading)
    var = np.asarray(var_lateral, dtype=float)
    terms = np.empty((heading.size + 1, 3))
    terms[0] = 0.0 if start is None else np.asarray(start, dtype=float)
    terms[1:, 0] = var * s * s
    terms[1:, 1] = -(var * s * c)
    terms[1:, 2] = var * c * c
    return np.cumsum(terms, axis=0)[1:]


def add_lateral(cov: NDArray[np.float64], sums: NDArray[np.float64]) -> None:
    """Add :func:`lateral_sums` (n, 3) to the x–y blocks of ``cov`` (n, 3, 3), in place."""
    cov[:, 0, 0] += sums[:, 0]
    cov[:, 0, 1] += sums[:, 1]
    cov[:, 1, 0] += sums[:, 1]
    cov[:, 1, 1] += sums[:, 2]


def accumulate_lateral(theta: NDArray[np.float64], dtheta: NDArray[np.float64],
                       var_lateral: NDArray[np.float64], method: str, sums: NDArray[np.float64],
                       out: NDArray[np.float64]) -> None:
    """Add the slip's running sums over n steps to the x–y blocks of ``out`` (n, 3, 3),
    in place, continuing from ``sums`` (3,) = (xx, xy, yy), which is updated: what every
    engine does per chunk. One compiled pass (:mod:`odomkit.propagate._numba`), or
    :func:`lateral_sums` and :func:`add_lateral` without numba (the same sums to
    rounding; either way the chunking changes no bit)."""
    module = jit.load("propagate._numba", stacklevel=4)
    if method not in _CHORD_WEIGHT:
        lateral_headings(theta, dtheta, method)  # the error names the methods
    if module is None:
        part = lateral_sums(theta, dtheta, var_lateral, method, sums)
        add_lateral(out, part)
        if part.shape[0]:
            sums[:] = part[-1]
        return
    module.lateral_kernel(np.asarray(theta, dtype=float), np.asarray(dtheta, dtype=float),
                          np.asarray(var_lateral, dtype=float), _CHORD_WEIGHT[method], sums, out)


def lateral_segment_cov(alpha_lateral: float, length: float, theta0: float, dtheta: float,
                        steps: int | None = None) -> NDArray[np.float64]:
    """Position covariance a lateral slip adds over one constant-curvature segment, (2, 2)
    [m²] (module docstring).

    Parameters
    ----------
    alpha_lateral : float
        α_lat [m²/m].
    length : float
        Arc length D [m] (signed: a reversing segment slips as much).
    theta0, dtheta : float
        Start heading and heading change of the segment [rad].
    steps : int, optional
        The exact sum over N equal exact-arc steps (a compass's samples); None for the
        integral (N → ∞), the limit of the engines' sum as the steps shrink.

    Examples
    --------
    A straight metre along x slips only in y; a half turn spreads it over both axes:

    >>> lateral_segment_cov(0.01, 1.0, 0.0, 0.0).tolist()
    [[0.0, -0.0], [-0.0, 0.01]]
    >>> lateral_segment_cov(0.01, 1.0, 0.0, math.pi).round(12).tolist()
    [[0.005, -0.0], [-0.0, 0.005]]
    """
    total = alpha_lateral * abs(length)
    if steps is None:
        kernel = float(sinc(dtheta))
    else:
        h = dtheta / steps
        kernel = 1.0 if h == 0.0 else math.sin(dtheta) / (steps * math.sin(h))
    two = 2.0 * theta0 + dtheta  # 2·θ_m
    cos2, sin2 = kernel * math.cos(two), kernel * math.sin(two)
    half = 0.5 * total
    return np.array([[half * (1.0 - cos2), -half * sin2], [-half * sin2, half * (1.0 + cos2)]])
