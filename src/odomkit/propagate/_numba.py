"""The numba kernels of the step recursion (Chong–Kleeman eq. 2).

The recurrence P_{k+1} = F_k P_k F_k^T + G_k Q_k G_k^T cannot be vectorised as written.
:func:`recursion_kernel` runs it in one compiled pass: each step forms F_k and
G_k Q_k G_k^T inline from (θ, Δd, Δθ) and applies them at once, so no (M, 3, 3) Jacobian
array and no per-step term array is ever materialised. The Jacobians are the same as
:func:`odomkit.kinematics.step_jacobians` (and, for ``METHOD_CLASSICAL``,
:func:`odomkit.propagate.inputs.classical_step_jacobians`); the tests compare them.

Where the time went (10^7 wheel-noise steps, one core: ~70 ns a step before, ~19 ns now;
benchmarks/propagation.py):

* The per-step terms pass, mostly cos and sin of each heading (~42 ns). The heading is
  now carried as a unit vector (cos, sin) turned by each step's half angle φ = Δθ/2,
  whose sine and cosine come from Taylor polynomials (exact to rounding;
  :func:`odomkit.angles.sin_cos_sinc`), as :mod:`odomkit._integrate_numba` does for dead
  reckoning. This is valid only when the headings satisfy θ_{k+1} = θ_k + Δθ_k, which
  the caller does not promise. So the kernel also carries the scalar sum θ_a + Σ Δθ
  from the last anchor a and compares it with θ_k at every step (one subtraction). If
  they differ by more than ``heading_tolerance(θ_k)``, the vector is re-anchored at that
  step with a real cos/sin of θ_k. Arbitrary headings thus re-anchor at every step,
  which is the exact per-step computation (~40 ns a step). A dead-reckoned track
  (:func:`odomkit.integrate.dead_reckon` sums headings in this same order) matches bit
  for bit and re-anchors only every ``ANCHOR`` steps, so the rounding of repeated
  rotations cannot build up.
* The per-wheel input covariance: ``QMODE_WHEEL`` forms Q_k from (d_L, d_R) in the
  kernel, with the very operations of :func:`odomkit.noise.wheel.wheel_input_cov`,
  instead of a (n, 2, 2) numpy array per chunk (~8 ns a step).
* A second pass over an (8, n) term array, and contiguous copies (~10 ns a step).

Anchors sit at global step indices that are multiples of ``ANCHOR`` (plus the forced
ones), and the carried (cos, sin, θ) passes from one chunk to the next in ``state``, so
the numbers do not depend on the chunk size. No fastmath: without it LLVM may not
contract a·b + c into an FMA, which keeps the serial kernel, the parallel kernel (terms
stored, then the recurrence) and every chunking bit-identical. Contraction would save
only ~11 % (18.6 -> 16.5 ns a step).

Importing this module imports numba; :mod:`odomkit.propagate.recursion` loads it lazily
through :func:`odomkit.jit.load` and falls back to a numpy loop when numba is missing.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from odomkit import angles
from odomkit.angles import ANCHOR
from odomkit.jit import njit

__all__ = [
    "METHOD_CLASSICAL", "METHOD_EULER", "METHOD_EXACT", "METHOD_MIDPOINT", "QMODE_ARRAY", "QMODE_WHEEL",
    "STATE_SIZE", "heading_tolerance", "recurrence_kernel", "recursion_kernel", "recursion_kernel_parallel"
]

# Method codes shared with recursion.py.
METHOD_EXACT = 0
METHOD_MIDPOINT = 1
METHOD_EULER = 2
METHOD_CLASSICAL = 3

# Where Q_k comes from: the (n, 2, 2) cov_input array, or formed from the wheel travels.
QMODE_ARRAY = 0
QMODE_WHEEL = 1

# ``state`` layout, carried from one chunk to the next: heading unit vector, carried
# heading sum, 1.0 once the first three are valid, count of anchors (real cos/sin).
STATE_SIZE = 5


# Carried heading sum and θ_k may differ by this much before the step re-anchors:
# 1e-12 rad absolute (a heading error δ changes the terms by ~δ relative), widened by
# 64 ulp of |θ_k| because θ_k itself, summed by another integrator (e.g. θ_0 + cumsum),
# drifts by a few ulp a step from our sum. A dead-reckoned track matches exactly.
_TOL_ABS = 1e-12
_TOL_REL = 64.0 * np.finfo(float).eps

# sin, cos and sinc of the half angle, and the derivative of sinc: the series and the
# threshold of odomkit.angles, inlined into each kernel.
sin_cos_sinc = njit(angles.sin_cos_sinc, inline="always")
sinc_derivative = njit(angles.sinc_derivative_scalar, inline="always")


@njit(inline="always")
def heading_tolerance(theta_k: float) -> float:
    """Largest |carried heading − θ_k| [rad] that keeps the rotated heading vector."""
    return _TOL_ABS + _TOL_REL * abs(theta_k)


@njit(inline="always")
def _step(k, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method,
          c, s, th, force_anchor):
    """Terms of step k and the heading state after it.

    (c, s) is the carried unit vector of θ_k and th the carried heading sum. Returns
    u0, u1 (F = I + u e_θ^T, u = (−Δy, Δx)), the entries b00, b01, b11, b02, b12, b22 of
    B = G Q G^T, then (c, s, th) of step k+1 and 1 if this step re-anchored.
    """
    theta_k = theta[k]
    anchored = 0
    # ``not (… <= tol)`` so that a NaN heading re-anchors (and propagates as NaN).
    if force_anchor or not (abs(th - theta_k) <= heading_tolerance(theta_k)):
        c = math.cos(theta_k)
        s = math.sin(theta_k)
        th = theta_k
        anchored = 1
    d = dd[k]
    a = dtheta[k]
    # Heading of the displacement (hc, hs), chord factor f, f' and w = ∂heading/∂Δθ:
    # exact arc / midpoint use θ + Δθ/2; euler θ; classical (rotate α, then translate D,
    # Chong–Kleeman eq. 1) θ + α. Each turns the carried vector; the next step's heading
    # is θ + Δθ in all four maps.
    if method == METHOD_EULER:
        sp, cp, _ = sin_cos_sinc(a)
        hc, hs = c, s
        c, s = c * cp - s * sp, s * cp + c * sp
        f, df, w = 1.0, 0.0, 0.0
    elif method == METHOD_CLASSICAL:
        sp, cp, _ = sin_cos_sinc(a)
        hc, hs = c * cp - s * sp, s * cp + c * sp
        c, s = hc, hs
        f, df, w = 1.0, 0.0, 1.0
    else:
        u = 0.5 * a
        sp, cp, sinc = sin_cos_sinc(u)
        hc, hs = c * cp - s * sp, s * cp + c * sp
        c, s = hc * cp - hs * sp, hs * cp + hc * sp
        if method == METHOD_MIDPOINT:
            f, df, w = 1.0, 0.0, 0.5
        else:
            # d/dΔθ sinc(Δθ/2) = ½ sinc′(u) (angles.sinc_half_derivative)
            f, df, w = sinc, 0.5 * sinc_derivative(u, sp, cp), 0.5
    th = th + a
    if qmode == QMODE_WHEEL:
        # inputs.wheel_input_cov, operation for operation: Cov(d_L, d_R) =
        # diag(k_L²|d_L|, k_R²|d_R|) (Chong–Kleeman eq. 4) mapped by
        # J = [[½, ½], [−1/b, 1/b]]; wheel = (k_L², k_R², J00², J01·J11, J11²).
        var_l = abs(d_left[k]) * wheel[0]
        var_r = abs(d_right[k]) * wheel[1]
        var_sum = var_l + var_r
        var_diff = var_r - var_l
        q00 = wheel[2] * var_sum
        q01 = wheel[3] * var_diff
        q11 = wheel[4] * var_sum
    else:
        q00 = cov_input[k, 0, 0]
        q01 = 0.5 * (cov_input[k, 0, 1] + cov_input[k, 1, 0])
        q11 = cov_input[k, 1, 1]
    # G = [[g00, g01], [g10, g11], [0, 1]]: Chong–Kleeman eq. (17) in chord form.
    g00 = f * hc
    g10 = f * hs
    g01 = d * (df * hc - w * f * hs)
    g11 = d * (df * hs + w * f * hc)
    r00 = g00 * q00 + g01 * q01  # rows of G Q
    r01 = g00 * q01 + g01 * q11
    r10 = g10 * q00 + g11 * q01
    r11 = g10 * q01 + g11 * q11
    return (-d * g10, d * g00, r00 * g00 + r01 * g01, r00 * g10 + r01 * g11,
            r10 * g10 + r11 * g11, r01, r11, q11, c, s, th, anchored)


@njit(inline="always")
def _upper(cov: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """(p00, p01, p02, p11, p12, p22) of a 3×3 covariance, off-diagonals averaged.

    Only the upper triangle is carried and the lower one mirrored on output: P is then
    symmetric by construction, so round-off in F P F^T cannot make P_ij and P_ji drift
    apart over 10^7 steps (filterpy symmetrises with (P + P^T)/2 for the same reason; an
    asymmetric P breaks Cholesky and eigh downstream).
    """
    return (cov[0, 0], 0.5 * (cov[0, 1] + cov[1, 0]), 0.5 * (cov[0, 2] + cov[2, 0]),
            cov[1, 1], 0.5 * (cov[1, 2] + cov[2, 1]), cov[2, 2])


@njit(inline="always")
def _advance(p00: float, p01: float, p02: float, p11: float, p12: float, p22: float,
             u0: float, u1: float, b00: float, b01: float, b11: float, b02: float,
             b12: float, b22: float) -> tuple[float, float, float, float, float, float]:
    """F P F^T + B with F = I + u e_θ^T (Chong–Kleeman eq. 16, chord form), upper triangle."""
    n00 = p00 + 2.0 * u0 * p02 + u0 * u0 * p22
    n01 = p01 + u0 * p12 + u1 * p02 + u0 * u1 * p22
    n11 = p11 + 2.0 * u1 * p12 + u1 * u1 * p22
    n02 = p02 + u0 * p22
    n12 = p12 + u1 * p22
    return n00 + b00, n01 + b01, n02 + b02, n11 + b11, n12 + b12, p22 + b22


@njit(inline="always")
def _store(o: np.ndarray, p00: float, p01: float, p02: float, p11: float, p12: float,
           p22: float) -> None:
    """Write the upper triangle and its mirror into the 3×3 ``o``."""
    o[0, 0] = p00
    o[0, 1] = p01
    o[1, 0] = p01
    o[0, 2] = p02
    o[2, 0] = p02
    o[1, 1] = p11
    o[1, 2] = p12
    o[2, 1] = p12
    o[2, 2] = p22


@njit
def recursion_kernel(
    theta: np.ndarray, dd: np.ndarray, dtheta: np.ndarray, cov_input: np.ndarray,
    d_left: np.ndarray, d_right: np.ndarray, wheel: np.ndarray, qmode: int, method: int,
    start: int, state: np.ndarray, cov_start: np.ndarray, out: np.ndarray,
) -> None:
    """Run the recursion over n steps; ``out[i]`` receives P after step i.

    theta, dd, dtheta : (n,); cov_input : (n, 2, 2) (QMODE_ARRAY) or d_left, d_right :
    (n,) with wheel (5,) (QMODE_WHEEL); start : global index of the first step (anchors
    sit at multiples of ANCHOR); state : (STATE_SIZE,) carried heading, updated;
    cov_start : (3, 3) P before the first step; out : (n, 3, 3), written in place.
    """
    p00, p01, p02, p11, p12, p22 = _upper(cov_start)
    c, s, th = state[0], state[1], state[2]
    valid = state[3] != 0.0
    anchors = 0
    for k in range(theta.shape[0]):
        force = (not valid) or (start + k) % ANCHOR == 0
        valid = True
        (u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored) = _step(
            k, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method,
            c, s, th, force)
        anchors += anchored
        p00, p01, p02, p11, p12, p22 = _advance(p00, p01, p02, p11, p12, p22,
                                                u0, u1, b00, b01, b11, b02, b12, b22)
        _store(out[k], p00, p01, p02, p11, p12, p22)
    state[0], state[1], state[2] = c, s, th
    state[3] = 1.0 if valid else state[3]
    state[4] += anchors


@njit
def _terms_range(k0, k1, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode,
                 method, start, c, s, th, valid, terms):
    """Terms of steps k0 … k1−1 into ``terms`` (8, n), as :func:`recursion_kernel`
    forms them; returns the heading state after k1−1 and the anchor count."""
    anchors = 0
    for k in range(k0, k1):
        force = (not valid) or (start + k) % ANCHOR == 0
        valid = True
        (u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored) = _step(
            k, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method,
            c, s, th, force)
        anchors += anchored
        terms[0, k] = u0
        terms[1, k] = u1
        terms[2, k] = b00
        terms[3, k] = b01
        terms[4, k] = b11
        terms[5, k] = b02
        terms[6, k] = b12
        terms[7, k] = b22
    return c, s, th, anchors


@njit
def recurrence_kernel(terms: np.ndarray, cov_start: np.ndarray, out: np.ndarray) -> None:
    """P_{k+1} = F_k P_k F_k^T + B_k over n steps from terms (8, n); ``out[k]`` receives
    P after step k (the same operations as :func:`recursion_kernel`)."""
    p00, p01, p02, p11, p12, p22 = _upper(cov_start)
    for k in range(terms.shape[1]):
        p00, p01, p02, p11, p12, p22 = _advance(
            p00, p01, p02, p11, p12, p22, terms[0, k], terms[1, k], terms[2, k],
            terms[3, k], terms[4, k], terms[5, k], terms[6, k], terms[7, k])
        _store(out[k], p00, p01, p02, p11, p12, p22)


@njit(parallel=True)
def recursion_kernel_parallel(
    theta: np.ndarray, dd: np.ndarray, dtheta: np.ndarray, cov_input: np.ndarray,
    d_left: np.ndarray, d_right: np.ndarray, wheel: np.ndarray, qmode: int, method: int,
    start: int, state: np.ndarray, cov_start: np.ndarray, out: np.ndarray,
) -> None:
    """:func:`recursion_kernel` with the per-step terms spread over numba's threads.

    The blocks between two regular anchors are independent (each starts with a real
    cos/sin), so they run in parallel; the part before the first regular anchor of the
    chunk continues the carried state. Same operations as the serial kernel, so the
    same bits; then the cheap sequential recurrence.
    """
    n = theta.shape[0]
    terms = np.empty((8, n))
    head = min((ANCHOR - start % ANCHOR) % ANCHOR, n)
    c, s, th, anchors = _terms_range(0, head, theta, dd, dtheta, cov_input, d_left,
                                     d_right, wheel, qmode, method, start, state[0],
                                     state[1], state[2], state[3] != 0.0, terms)
    if head > 0:
        state[0], state[1], state[2], state[3] = c, s, th, 1.0
    blocks = (n - head + ANCHOR - 1) // ANCHOR
    for i in numba.prange(blocks):
        k0 = head + i * ANCHOR
        k1 = min(k0 + ANCHOR, n)
        cb, sb, thb, nb = _terms_range(k0, k1, theta, dd, dtheta, cov_input, d_left,
                                       d_right, wheel, qmode, method, start, 1.0, 0.0,
                                       0.0, False, terms)
        anchors += nb
        if k1 == n:
            state[0], state[1], state[2], state[3] = cb, sb, thb, 1.0
    state[4] += anchors
    recurrence_kernel(terms, cov_start, out)
