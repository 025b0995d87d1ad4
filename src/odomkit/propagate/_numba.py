"""The numba kernel of the step recursion (Chong–Kleeman eq. 2).

The recurrence P_{k+1} = F_k P_k F_k^T + G_k Q_k G_k^T cannot be vectorised as written.
It runs here in two compiled passes per chunk: the per-step terms (F_k and G_k Q_k G_k^T
formed inline from (θ, Δd, Δθ), mostly sines and cosines; optionally in parallel over
the steps), then the cheap sequential recurrence (about 4 ns a step). No (M, 3, 3)
Jacobian arrays are ever materialised. Each step's terms do not depend on how steps are
split across threads, so serial and parallel results are identical. The Jacobians are
the same as :func:`odomkit.kinematics.step_jacobians` (and, for ``METHOD_CLASSICAL``,
:func:`odomkit.propagate.inputs.classical_step_jacobians`); the tests compare them.

Importing this module imports numba; :mod:`odomkit.propagate.recursion` does so lazily
and falls back to a numpy loop when numba is missing.
"""

from __future__ import annotations

import math

import numba
import numpy as np

# Method codes shared with recursion.py.
METHOD_EXACT = 0
METHOD_MIDPOINT = 1
METHOD_EULER = 2
METHOD_CLASSICAL = 3

# Below this |u| = |Δθ/2| the Taylor series of sinc(u) = sin(u)/u and of its derivative
# is used. Besides avoiding the cancellation in (u·cos u − sin u)/u², it spares two
# transcendental calls per step (the kernel's main cost): at |u| = 0.1 the first omitted
# terms, u^10/11! and 10·u^9/11!, are below 3e-17 relative.
_SERIES_BELOW = 0.1


@numba.njit(cache=True, nogil=True)
def _sinc_and_derivative(dtheta: float) -> tuple[float, float]:
    """sin(Δθ/2)/(Δθ/2) and its derivative d/dΔθ (kinematics.sinc_half[_derivative])."""
    u = 0.5 * dtheta
    if abs(u) < _SERIES_BELOW:
        # Horner form with reciprocal constants: a chain of divisions would cost ~40 ns.
        v = u * u
        f = 1.0 - v * (1.0 / 6.0) * (1.0 - v * (1.0 / 20.0) * (
            1.0 - v * (1.0 / 42.0) * (1.0 - v * (1.0 / 72.0))))
        # d/du sinc = −u/3 + u³/30 − u⁵/840 + u⁷/45360 − u⁹/3991680
        df = -u * (1.0 / 3.0) * (1.0 - v * (1.0 / 10.0) * (1.0 - v * (1.0 / 28.0) * (
            1.0 - v * (1.0 / 54.0) * (1.0 - v * (1.0 / 88.0)))))
        return f, 0.5 * df
    s = math.sin(u)
    return s / u, 0.5 * (u * math.cos(u) - s) / (u * u)


@numba.njit(cache=True, nogil=True, inline="always")
def _step_terms_one(
    k: int,
    theta: np.ndarray,
    dd: np.ndarray,
    dtheta: np.ndarray,
    cov_input: np.ndarray,
    method: int,
    terms: np.ndarray,
) -> None:
    """Per-step terms of step k: ``terms[:, k]`` = u = (−Δy, Δx) of F = I + u e_θ^T and
    the entries (b00, b01, b11, b02, b12, b22) of B = G Q G^T. The sines and cosines
    here are most of the work of the recursion."""
    d = dd[k]
    a = dtheta[k]
    # Heading of the displacement, chord factor f, f' and w = ∂heading/∂Δθ:
    # exact arc / midpoint use θ + Δθ/2; euler θ; classical (rotate α, then
    # translate D, Chong–Kleeman eq. 1) θ + α.
    if method == METHOD_EULER:
        h = theta[k]
        f, df, w = 1.0, 0.0, 0.0
    elif method == METHOD_CLASSICAL:
        h = theta[k] + a
        f, df, w = 1.0, 0.0, 1.0
    elif method == METHOD_MIDPOINT:
        h = theta[k] + 0.5 * a
        f, df, w = 1.0, 0.0, 0.5
    else:
        h = theta[k] + 0.5 * a
        f, df = _sinc_and_derivative(a)
        w = 0.5
    c = math.cos(h)
    s = math.sin(h)
    # G = [[g00, g01], [g10, g11], [0, 1]]: Chong–Kleeman eq. (17) in chord form.
    g00 = f * c
    g10 = f * s
    g01 = d * (df * c - w * f * s)
    g11 = d * (df * s + w * f * c)
    q00 = cov_input[k, 0, 0]
    q01 = 0.5 * (cov_input[k, 0, 1] + cov_input[k, 1, 0])
    q11 = cov_input[k, 1, 1]
    r00 = g00 * q00 + g01 * q01  # rows of G Q
    r01 = g00 * q01 + g01 * q11
    r10 = g10 * q00 + g11 * q01
    r11 = g10 * q01 + g11 * q11
    terms[0, k] = -d * g10  # −Δy
    terms[1, k] = d * g00   # Δx
    terms[2, k] = r00 * g00 + r01 * g01
    terms[3, k] = r00 * g10 + r01 * g11
    terms[4, k] = r10 * g10 + r11 * g11
    terms[5, k] = r01
    terms[6, k] = r11
    terms[7, k] = q11


# The same per-step pass twice: serial (the default: on a machine whose cores are busy
# with other work, every parallel region waits for a scheduler slice, ~5 ms a chunk)
# and with numba threads over the steps (``parallel=True`` in the engines). Each step's
# numbers do not depend on how steps are split across threads.
@numba.njit(cache=True, nogil=True)
def step_terms_serial(
    theta: np.ndarray, dd: np.ndarray, dtheta: np.ndarray, cov_input: np.ndarray,
    method: int, terms: np.ndarray,
) -> None:
    """terms (8, n) of every step, one thread."""
    for k in range(theta.shape[0]):
        _step_terms_one(k, theta, dd, dtheta, cov_input, method, terms)


@numba.njit(cache=True, nogil=True, parallel=True)
def step_terms_parallel(
    theta: np.ndarray, dd: np.ndarray, dtheta: np.ndarray, cov_input: np.ndarray,
    method: int, terms: np.ndarray,
) -> None:
    """terms (8, n) of every step, numba's threads."""
    for k in numba.prange(theta.shape[0]):
        _step_terms_one(k, theta, dd, dtheta, cov_input, method, terms)


@numba.njit(cache=True, nogil=True)
def recurrence_kernel(terms: np.ndarray, cov_start: np.ndarray, out: np.ndarray) -> None:
    """P_{k+1} = F_k P_k F_k^T + B_k over n steps; ``out[k]`` receives P after step k.

    terms : (8, n) from :func:`step_terms_serial`; cov_start : (3, 3); out : (n, 3, 3).
    """
    # Only the upper triangle (6 numbers) is carried and the lower one mirrored on
    # output: P is symmetric by construction, so round-off in F P F^T cannot make P_ij
    # and P_ji drift apart over 10^7 steps (filterpy symmetrises with (P + P^T)/2 for
    # the same reason; an asymmetric P breaks Cholesky and eigh downstream).
    p00 = cov_start[0, 0]
    p01 = 0.5 * (cov_start[0, 1] + cov_start[1, 0])
    p02 = 0.5 * (cov_start[0, 2] + cov_start[2, 0])
    p11 = cov_start[1, 1]
    p12 = 0.5 * (cov_start[1, 2] + cov_start[2, 1])
    p22 = cov_start[2, 2]
    for k in range(terms.shape[1]):
        u0 = terms[0, k]
        u1 = terms[1, k]
        # F P F^T with F = I + u e_θ^T (Chong–Kleeman eq. 16, chord form), then + B.
        n00 = p00 + 2.0 * u0 * p02 + u0 * u0 * p22
        n01 = p01 + u0 * p12 + u1 * p02 + u0 * u1 * p22
        n11 = p11 + 2.0 * u1 * p12 + u1 * u1 * p22
        n02 = p02 + u0 * p22
        n12 = p12 + u1 * p22
        p00 = n00 + terms[2, k]
        p01 = n01 + terms[3, k]
        p11 = n11 + terms[4, k]
        p02 = n02 + terms[5, k]
        p12 = n12 + terms[6, k]
        p22 = p22 + terms[7, k]
        o = out[k]
        o[0, 0] = p00
        o[0, 1] = p01
        o[1, 0] = p01
        o[0, 2] = p02
        o[2, 0] = p02
        o[1, 1] = p11
        o[1, 2] = p12
        o[2, 1] = p12
        o[2, 2] = p22


@numba.njit(cache=True, nogil=True)
def recursion_kernel(
    theta: np.ndarray,
    dd: np.ndarray,
    dtheta: np.ndarray,
    cov_input: np.ndarray,
    cov_start: np.ndarray,
    out: np.ndarray,
    method: int,
) -> None:
    """Run the recursion over n steps; ``out[i]`` receives P after step i.

    theta, dd, dtheta : (n,); cov_input : (n, 2, 2); cov_start : (3, 3) P before the
    first step; out : (n, 3, 3), written in place.
    """
    terms = np.empty((8, theta.shape[0]))
    step_terms_serial(theta, dd, dtheta, cov_input, method, terms)
    recurrence_kernel(terms, cov_start, out)


@numba.njit(cache=True, nogil=True)
def recursion_kernel_parallel(
    theta: np.ndarray,
    dd: np.ndarray,
    dtheta: np.ndarray,
    cov_input: np.ndarray,
    cov_start: np.ndarray,
    out: np.ndarray,
    method: int,
) -> None:
    """:func:`recursion_kernel` with the per-step pass spread over numba's threads."""
    terms = np.empty((8, theta.shape[0]))
    step_terms_parallel(theta, dd, dtheta, cov_input, method, terms)
    recurrence_kernel(terms, cov_start, out)
