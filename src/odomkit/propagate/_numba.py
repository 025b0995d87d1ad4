"""The numba kernels of the step recursion (Chong–Kleeman eq. 2).

The recurrence P_{k+1} = F_k P_k F_k^T + G_k Q_k G_k^T cannot be vectorised as written.
:func:`recursion_kernel` runs it in one compiled pass: each step forms F_k and
G_k Q_k G_k^T inline from (θ, Δd, Δθ) and applies them at once, so no (M, 3, 3) Jacobian
array and no per-step term array is ever materialised. The Jacobians are the same as
:func:`odomkit.kinematics.step_jacobians` (and, for ``METHOD_CLASSICAL``,
:func:`odomkit.propagate.inputs.classical_step_jacobians`); the tests compare them.

How it runs (10^7 wheel-noise steps, one core; ``benchmarks/propagation.py --stages``
times each stage: ~70 ns a step originally, ~17 ns with the turned heading vector below,
~9 ns now, of which ~2.4 ns is writing the (N, 3, 3) output):

* The heading. Its cos and sin at every step cost ~42 ns. They are carried instead as a
  unit vector (cos, sin) turned by each step's half angle φ = Δθ/2, whose sine and
  cosine come from the series of :mod:`odomkit.angles`, as :mod:`odomkit._integrate_numba`
  does for dead reckoning. This is valid only when the headings satisfy
  θ_{k+1} = θ_k + Δθ_k, which the caller does not promise. So the kernel also carries
  the scalar sum θ_a + Σ Δθ from the last anchor a and compares it with θ_k at every
  step. If they differ by more than ``heading_tolerance(θ_k)``, the vector is re-anchored
  at that step with a real cos/sin of θ_k. Arbitrary headings thus re-anchor at every
  step, which is the exact per-step computation (~33 ns a step). A dead-reckoned track
  (:func:`odomkit.integrate.dead_reckon` sums headings in this same order) matches bit
  for bit and re-anchors only every ``ANCHOR`` steps, so the rounding of repeated
  rotations cannot build up.
* SIMD lanes. Within a block of ``ANCHOR`` steps the turns form a chain, but the blocks
  are independent: :func:`_lane_headings` turns :data:`LANES` blocks at once, one SIMD
  lane each, and :func:`_block_terms` then forms each step's F and G Q G^T (~60 flops,
  which set the pace at ~10 ns a step when done one step at a time) vectorised over the
  steps. The lanes take a block only if every turn is below ``SHORT_BELOW`` (the short
  series, branch-free) and every heading agrees with the carried sum; any other block
  is redone step by step by :func:`_step`. Both paths perform the same operations, so
  the numbers do not depend on which one ran.
* The per-wheel input covariance: ``QMODE_WHEEL`` forms Q_k from (d_L, d_R) in the
  kernel, with the very operations of :func:`odomkit.noise.wheel.wheel_input_cov`,
  instead of a (n, 2, 2) numpy array per chunk (~8 ns a step).
* The output: an (N, 3, 3) array of a long log is written with streaming stores
  (:mod:`odomkit._stores`), which do not first read each cache line they fill.

Anchors sit at global step indices that are multiples of ``ANCHOR`` (plus the forced
ones), and the carried (cos, sin, θ) passes from one chunk to the next in ``state``, so
the numbers do not depend on the chunk size. No fastmath: without it LLVM does not
contract a·b + c into an FMA, which keeps the step-by-step path, the SIMD lanes, the
parallel kernel (terms stored, then the recurrence) and every chunking bit-identical.
(Contraction measured no faster here: it lengthens the recurrence's dependency chain.)

Importing this module imports numba; :mod:`odomkit.propagate.recursion` loads it lazily
through :func:`odomkit.jit.load` and falls back to a numpy loop when numba is missing.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from odomkit import angles
from odomkit._stores import store_fence, stream_store
from odomkit.angles import ANCHOR, SHORT_BELOW
from odomkit.jit import njit

__all__ = [
    "CHUNK", "LANES", "METHOD_CLASSICAL", "METHOD_EULER", "METHOD_EXACT", "METHOD_MIDPOINT", "QMODE_ARRAY",
    "QMODE_WHEEL", "STATE_SIZE", "WORK", "heading_tolerance", "lateral_kernel", "recurrence_kernel",
    "recursion_kernel", "recursion_kernel_parallel"
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
# Their branch-free short forms, the same bits below SHORT_BELOW, for the SIMD lanes.
sin_cos_sinc_short = njit(angles.sin_cos_sinc_short, inline="always")
sinc_derivative_short = njit(angles.sinc_derivative_short, inline="always")

#: Blocks of ANCHOR steps whose terms are formed side by side, one SIMD lane each.
LANES = 8
#: Steps per pass of the lanes.
CHUNK = LANES * ANCHOR

# Work buffer of the lanes, one array with compile-time offsets so that LLVM can prove
# the rows disjoint and vectorise (see odomkit._integrate_numba): θ and Δθ in step order;
# the heading (hc, hs) of each step's displacement in step order (QMODE_ARRAY only) and
# lane-major, as the lanes write it ([j * LANES + lane] for step lane * ANCHOR + j); per
# lane the heading vector, the heading sum and the count of steps the lanes cannot take.
# (With the lane-major rows right after the rows the lanes read, LLVM did not vectorise
# the lanes.) The terms go to a second array, (8, CHUNK): the loops that form them read
# the first and the inputs and write only the second, which LLVM then vectorises (with
# both in one buffer it cannot rule out that a store feeds a later load).
_TH, _A, _HC, _HS, _LC, _LS = (i * CHUNK for i in range(6))
_C = 6 * CHUNK
_S = _C + LANES
_H = _S + LANES
_MISS = _H + LANES
WORK = _MISS + LANES


@njit(inline="always")
def heading_tolerance(theta_k: float) -> float:
    """Largest |carried heading − θ_k| [rad] that keeps the rotated heading vector."""
    return _TOL_ABS + _TOL_REL * abs(theta_k)


@njit(inline="always")
def _turned(method: int, c: float, s: float, sp: float, cp: float, sinc: float,
            dsinc: float) -> tuple[float, float, float, float, float, float, float]:
    """The heading part of a step: (hc, hs, f, f', w, c', s').

    (c, s) is the heading vector at the start of the step; (sp, cp, sinc) are sin, cos
    and sin/φ of its turn φ (Δθ for euler and classical, Δθ/2 otherwise) and ``dsinc``
    sinc′(φ) (used by the exact arc only). Returns the heading of the displacement
    (hc, hs), the chord factor f, f' = df/dΔθ and w = ∂heading/∂Δθ: exact arc / midpoint
    use θ + Δθ/2; euler θ; classical (rotate α, then translate D, Chong–Kleeman eq. 1)
    θ + α; and the heading vector (c', s') of θ + Δθ, the next step's, in all four maps.
    """
    if method == METHOD_EULER:
        return c, s, 1.0, 0.0, 0.0, c * cp - s * sp, s * cp + c * sp
    hc, hs = c * cp - s * sp, s * cp + c * sp
    if method == METHOD_CLASSICAL:
        return hc, hs, 1.0, 0.0, 1.0, hc, hs
    cn, sn = hc * cp - hs * sp, hs * cp + hc * sp
    if method == METHOD_MIDPOINT:
        return hc, hs, 1.0, 0.0, 0.5, cn, sn
    # d/dΔθ sinc(Δθ/2) = ½ sinc′(u) (angles.sinc_half_derivative)
    return hc, hs, sinc, 0.5 * dsinc, 0.5, cn, sn


@njit(inline="always")
def _wheel_q(d_left: float, d_right: float, kl2: float, kr2: float, j00_2: float,
             j01_j11: float, j11_2: float) -> tuple[float, float, float]:
    """Q = (q00, q01, q11) of one step from the wheel travels.

    noise.wheel.wheel_input_cov, operation for operation: Cov(d_L, d_R) =
    diag(k_L²|d_L|, k_R²|d_R|) (Chong–Kleeman eq. 4) mapped by J = [[½, ½], [−1/b, 1/b]];
    the kernels' ``wheel`` array holds (k_L², k_R², J00², J01·J11, J11²).
    """
    var_l = abs(d_left) * kl2
    var_r = abs(d_right) * kr2
    var_sum = var_l + var_r
    var_diff = var_r - var_l
    return j00_2 * var_sum, j01_j11 * var_diff, j11_2 * var_sum


@njit(inline="always")
def _step_terms(d: float, q00: float, q01: float, q11: float, hc: float, hs: float, f: float,
                df: float, w: float) -> tuple[float, float, float, float, float, float, float, float]:
    """u0, u1 (F = I + u e_θ^T, u = (−Δy, Δx)) and b00, b01, b11, b02, b12, b22 of
    B = G Q G^T, from the step's Δd, Q and heading part (:func:`_turned`)."""
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
            r10 * g10 + r11 * g11, r01, r11, q11)


@njit(inline="always")
def _q(k: int, cov_input: np.ndarray, d_left: np.ndarray, d_right: np.ndarray, wheel: np.ndarray,
       qmode: int) -> tuple[float, float, float]:
    """Q = (q00, q01, q11) of step k: formed from the wheel travels (QMODE_WHEEL) or read
    from ``cov_input``, its off-diagonal averaged."""
    if qmode == QMODE_WHEEL:
        return _wheel_q(d_left[k], d_right[k], wheel[0], wheel[1], wheel[2], wheel[3], wheel[4])
    return cov_input[k, 0, 0], 0.5 * (cov_input[k, 0, 1] + cov_input[k, 1, 0]), cov_input[k, 1, 1]


# _step takes numbers, not arrays: an inlined function that takes arrays gets reference
# counting around each call, which numba removes only from simple control flow; left in
# the loop it cost ~45 ns a step (10 atomic operations).
@njit(inline="always")
def _step(theta_k, d, a, q00, q01, q11, method, c, s, th, force_anchor):
    """Terms of one step and the heading state after it.

    (θ_k, Δd, Δθ, Q) are the step's; (c, s) is the carried unit vector of θ_k and th the
    carried heading sum. Returns the eight terms of :func:`_step_terms`, then (c, s, th)
    of the next step and 1 if this step re-anchored.
    """
    anchored = 0
    # ``not (… <= tol)`` so that a NaN heading re-anchors (and propagates as NaN).
    if force_anchor or not (abs(th - theta_k) <= heading_tolerance(theta_k)):
        c = math.cos(theta_k)
        s = math.sin(theta_k)
        th = theta_k
        anchored = 1
    phi = a if method == METHOD_EULER or method == METHOD_CLASSICAL else 0.5 * a
    sp, cp, sinc = sin_cos_sinc(phi)
    dsinc = sinc_derivative(phi, sp, cp) if method == METHOD_EXACT else 0.0
    hc, hs, f, df, w, c, s = _turned(method, c, s, sp, cp, sinc, dsinc)
    th = th + a
    u0, u1, b00, b01, b11, b02, b12, b22 = _step_terms(d, q00, q01, q11, hc, hs, f, df, w)
    return u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored


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


@njit(inline="always")
def _put(out: np.ndarray, flat: np.ndarray, k: int, p00: float, p01: float, p02: float,
         p11: float, p12: float, p22: float, stream: bool) -> None:
    """P after step k into ``out[k]`` (``flat`` is ``out`` as (n, 9)); with streaming
    stores (:mod:`odomkit._stores`) if ``stream``."""
    if stream:
        stream_store(flat, k, 0, p00)
        stream_store(flat, k, 1, p01)
        stream_store(flat, k, 2, p02)
        stream_store(flat, k, 3, p01)
        stream_store(flat, k, 4, p11)
        stream_store(flat, k, 5, p12)
        stream_store(flat, k, 6, p02)
        stream_store(flat, k, 7, p12)
        stream_store(flat, k, 8, p22)
    else:
        _store(out[k], p00, p01, p02, p11, p12, p22)


@njit
def _load_blocks(k0, m, theta, dtheta, w):
    """θ and Δθ of steps k0 … k0+m−1 into the lanes' buffer ``w`` (step order), zero up
    to CHUNK. Views keep the indices >= 0, so that LLVM drops the negative-index
    wraparound and vectorises."""
    th_v, a_v = theta[k0:k0 + m], dtheta[k0:k0 + m]
    for i in range(m):
        w[_TH + i] = th_v[i]
        w[_A + i] = a_v[i]
    for i in range(m, CHUNK):
        w[_TH + i] = 0.0
        w[_A + i] = 0.0


@njit
def _lane_headings(w: np.ndarray, method: int) -> None:
    """Headings (hc, hs) of the LANES blocks in ``w``, one SIMD lane per block.

    Each block starts with a real cos/sin of its first heading (as :func:`_step` does at
    a regular anchor) and then turns the vector step by step: the chain that one lane
    runs. The lanes use the short series and never re-anchor, so a block must be redone
    by :func:`_step` where a turn is beyond SHORT_BELOW or a heading disagrees with the
    carried sum: ``w[_MISS + lane]`` counts those steps. Elsewhere the operations are
    those of :func:`_step`, hence its bits.
    """
    for lane in range(LANES):
        theta0 = w[_TH + lane * ANCHOR]
        w[_C + lane] = math.cos(theta0)
        w[_S + lane] = math.sin(theta0)
        w[_H + lane] = theta0
        w[_MISS + lane] = 0.0
    half = method == METHOD_EXACT or method == METHOD_MIDPOINT
    for j in range(ANCHOR):
        for lane in range(LANES):
            theta_k = w[_TH + lane * ANCHOR + j]
            a = w[_A + lane * ANCHOR + j]
            th = w[_H + lane]
            phi = 0.5 * a if half else a
            sp, cp, sinc = sin_cos_sinc_short(phi)
            hc, hs, _, _, _, c, s = _turned(method, w[_C + lane], w[_S + lane], sp, cp, sinc, 0.0)
            w[_LC + j * LANES + lane] = hc
            w[_LS + j * LANES + lane] = hs
            w[_C + lane] = c
            w[_S + lane] = s
            w[_H + lane] = th + a
            # ``not (… <= …)``: a NaN heading is a miss too (then _step re-anchors).
            miss = not (abs(th - theta_k) <= heading_tolerance(theta_k)) or not (
                abs(phi) < SHORT_BELOW)
            w[_MISS + lane] += 1.0 if miss else 0.0


# LLVM's vectoriser is easily put off here: the wheel loop below vectorises only as
# written (one function, loop counters as indices, views per block, the headings read
# across the lanes); variants that split it into functions, indexed whole-chunk views or
# read the headings the same way in the array loop were 3-4x slower.
@njit
def _block_terms(w, t, method, nb, k0, dd, cov_input, d_left, d_right, wheel, qmode):
    """The eight terms of the steps of those of the first ``nb`` blocks that the lanes
    took (no miss), from their headings (:func:`_lane_headings`), into ``t`` (8, CHUNK);
    Δd and Q straight from the inputs (global steps k0 + …). Vectorised over the steps
    of a block: it reads ``w`` and the inputs and writes only ``t``."""
    # f, f' and w of _turned; only the exact arc's depend on the step.
    exact = method == METHOD_EXACT
    wgt = 0.5 if exact or method == METHOD_MIDPOINT else (1.0 if method == METHOD_CLASSICAL else 0.0)
    # Coefficients as scalars: LLVM cannot tell that no store to t changes ``wheel``.
    kl2, kr2, j00_2, j01_j11, j11_2 = wheel[0], wheel[1], wheel[2], wheel[3], wheel[4]
    for lane in range(nb):
        if w[_MISS + lane] != 0.0:
            continue
        b0 = lane * ANCHOR
        b = k0 + b0
        d_v = dd[b:b + ANCHOR]
        if qmode == QMODE_WHEEL:
            left, right = d_left[b:b + ANCHOR], d_right[b:b + ANCHOR]
            for j in range(ANCHOR):
                i = b0 + j
                u = 0.5 * w[_A + i]
                _, _, sinc = sin_cos_sinc_short(u)
                dsinc = sinc_derivative_short(u)  # computed always: a select, not a branch
                q00, q01, q11 = _wheel_q(left[j], right[j], kl2, kr2, j00_2, j01_j11, j11_2)
                (t[0, i], t[1, i], t[2, i], t[3, i], t[4, i], t[5, i], t[6, i], t[7, i]) = _step_terms(
                    d_v[j], q00, q01, q11, w[_LC + j * LANES + lane], w[_LS + j * LANES + lane],
                    sinc if exact else 1.0, 0.5 * dsinc if exact else 0.0, wgt)
        else:
            q = cov_input[b:b + ANCHOR]
            # The headings into step order first (reading them across the lanes here
            # stopped LLVM from vectorising the wheel loop above as well).
            for j in range(ANCHOR):
                w[_HC + b0 + j] = w[_LC + j * LANES + lane]
                w[_HS + b0 + j] = w[_LS + j * LANES + lane]
            for j in range(ANCHOR):
                i = b0 + j
                u = 0.5 * w[_A + i]
                _, _, sinc = sin_cos_sinc_short(u)
                dsinc = sinc_derivative_short(u)
                (t[0, i], t[1, i], t[2, i], t[3, i], t[4, i], t[5, i], t[6, i], t[7, i]) = _step_terms(
                    d_v[j], q[j, 0, 0], 0.5 * (q[j, 0, 1] + q[j, 1, 0]), q[j, 1, 1], w[_HC + i],
                    w[_HS + i], sinc if exact else 1.0, 0.5 * dsinc if exact else 0.0, wgt)


@njit
def _redo_block(k0, lane, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode,
                method, t):
    """Block ``lane`` of the lanes (global steps k0 + lane·ANCHOR …) by :func:`_step`,
    its terms into ``t``; returns its heading state after it and its anchor count."""
    c, s, th = 1.0, 0.0, 0.0
    anchors = 0
    for j in range(ANCHOR):
        g = k0 + lane * ANCHOR + j
        q00, q01, q11 = _q(g, cov_input, d_left, d_right, wheel, qmode)
        (u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored) = _step(
            theta[g], dd[g], dtheta[g], q00, q01, q11, method, c, s, th, j == 0)
        anchors += anchored
        i = lane * ANCHOR + j
        t[0, i], t[1, i], t[2, i], t[3, i] = u0, u1, b00, b01
        t[4, i], t[5, i], t[6, i], t[7, i] = b11, b02, b12, b22
    return c, s, th, anchors


@njit
def _scalar_steps(k0, k1, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method,
                  start, c, s, th, valid, p00, p01, p02, p11, p12, p22, out, flat, stream):
    """Steps k0 … k1−1 one by one (:func:`_step`), P after each into ``out``. Returns the
    heading state, the anchor count and P after step k1−1."""
    anchors = 0
    for k in range(k0, k1):
        force = (not valid) or (start + k) % ANCHOR == 0
        valid = True
        q00, q01, q11 = _q(k, cov_input, d_left, d_right, wheel, qmode)
        (u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored) = _step(
            theta[k], dd[k], dtheta[k], q00, q01, q11, method, c, s, th, force)
        anchors += anchored
        p00, p01, p02, p11, p12, p22 = _advance(p00, p01, p02, p11, p12, p22,
                                                u0, u1, b00, b01, b11, b02, b12, b22)
        _put(out, flat, k, p00, p01, p02, p11, p12, p22, stream)
    return c, s, th, anchors, p00, p01, p02, p11, p12, p22


@njit
def _recur(t, m, k0, p00, p01, p02, p11, p12, p22, out, flat, stream):
    """The recurrence over the m steps of ``t`` (8, ≥ m), P after each into rows k0 … of
    ``out``; returns P after the last."""
    for i in range(m):
        p00, p01, p02, p11, p12, p22 = _advance(
            p00, p01, p02, p11, p12, p22, t[0, i], t[1, i], t[2, i], t[3, i], t[4, i],
            t[5, i], t[6, i], t[7, i])
        _put(out, flat, k0 + i, p00, p01, p02, p11, p12, p22, stream)
    return p00, p01, p02, p11, p12, p22


# Each stage is a function of its own, each loop in it simple: numba then removes the
# reference counting of the arrays it passes to inlined helpers (in one big loop with
# branches it did not, at ~30 ns a step).
@njit
def recursion_kernel(
    theta: np.ndarray, dd: np.ndarray, dtheta: np.ndarray, cov_input: np.ndarray,
    d_left: np.ndarray, d_right: np.ndarray, wheel: np.ndarray, qmode: int, method: int,
    start: int, state: np.ndarray, cov_start: np.ndarray, out: np.ndarray, stream: bool,
) -> None:
    """Run the recursion over n steps; ``out[i]`` receives P after step i.

    theta, dd, dtheta : (n,); cov_input : (n, 2, 2) (QMODE_ARRAY) or d_left, d_right :
    (n,) with wheel (5,) (QMODE_WHEEL); start : global index of the first step (anchors
    sit at multiples of ANCHOR); state : (STATE_SIZE,) carried heading, updated;
    cov_start : (3, 3) P before the first step; out : (n, 3, 3) C-contiguous, written in
    place, with streaming stores if ``stream`` (for outputs larger than the cache).

    Steps before the first multiple of ANCHOR continue the carried heading one by one
    (:func:`_step`); then whole blocks of ANCHOR steps, LANES at a time, get their
    headings from the SIMD lanes (:func:`_lane_headings`) and their terms from
    :func:`_block_terms` (a block the lanes cannot take is redone by :func:`_step`) and
    go through the recurrence; a last partial block goes one by one again. Every step is
    computed by the operations of :func:`_step`, so the numbers do not depend on which
    path took it, nor on the chunking.
    """
    n = theta.shape[0]
    flat = out.reshape((out.shape[0], 9))
    p00, p01, p02, p11, p12, p22 = _upper(cov_start)
    c, s, th = state[0], state[1], state[2]
    valid = state[3] != 0.0
    head = min((ANCHOR - start % ANCHOR) % ANCHOR, n)
    blocks = (n - head) // ANCHOR
    c, s, th, anchors, p00, p01, p02, p11, p12, p22 = _scalar_steps(
        0, head, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method, start,
        c, s, th, valid, p00, p01, p02, p11, p12, p22, out, flat, stream)
    valid = valid or head > 0
    k = head
    if blocks > 0:
        w = np.empty(WORK)
        t = np.empty((8, CHUNK))
        while blocks > 0:
            nb = min(LANES, blocks)
            _load_blocks(k, nb * ANCHOR, theta, dtheta, w)
            _lane_headings(w, method)
            _block_terms(w, t, method, nb, k, dd, cov_input, d_left, d_right, wheel, qmode)
            for lane in range(nb):
                if w[_MISS + lane] == 0.0:
                    anchors += 1
                    c, s, th = w[_C + lane], w[_S + lane], w[_H + lane]
                else:
                    c, s, th, redone = _redo_block(k, lane, theta, dd, dtheta, cov_input,
                                                   d_left, d_right, wheel, qmode, method, t)
                    anchors += redone
            p00, p01, p02, p11, p12, p22 = _recur(t, nb * ANCHOR, k, p00, p01, p02, p11, p12,
                                                  p22, out, flat, stream)
            valid = True
            k += nb * ANCHOR
            blocks -= nb
    c, s, th, tail_anchors, p00, p01, p02, p11, p12, p22 = _scalar_steps(
        k, n, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode, method, start,
        c, s, th, valid, p00, p01, p02, p11, p12, p22, out, flat, stream)
    valid = valid or k < n
    if stream:
        store_fence()
    state[0], state[1], state[2] = c, s, th
    state[3] = 1.0 if valid else state[3]
    state[4] += anchors + tail_anchors


@njit
def _terms_range(k0, k1, theta, dd, dtheta, cov_input, d_left, d_right, wheel, qmode,
                 method, start, c, s, th, valid, terms):
    """Terms of steps k0 … k1−1 into ``terms`` (8, n), as :func:`recursion_kernel`
    forms them; returns the heading state after k1−1 and the anchor count."""
    anchors = 0
    for k in range(k0, k1):
        force = (not valid) or (start + k) % ANCHOR == 0
        valid = True
        q00, q01, q11 = _q(k, cov_input, d_left, d_right, wheel, qmode)
        (u0, u1, b00, b01, b11, b02, b12, b22, c, s, th, anchored) = _step(
            theta[k], dd[k], dtheta[k], q00, q01, q11, method, c, s, th, force)
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
    start: int, state: np.ndarray, cov_start: np.ndarray, out: np.ndarray, stream: bool,
) -> None:
    """:func:`recursion_kernel` with the per-step terms spread over numba's threads
    (``stream`` is accepted for a common signature; the output is written normally).

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


@njit
def lateral_kernel(theta: np.ndarray, dtheta: np.ndarray, var: np.ndarray, weight: float,
                   sums: np.ndarray, out: np.ndarray) -> None:
    """Add the running sums of a lateral slip to the x–y blocks of ``out`` (n, 3, 3), in
    place, in one pass (:func:`odomkit.propagate.lateral.lateral_sums`, the numpy
    reference, forms the same sums): step k moves across its chord θ_k + weight·Δθ_k
    with variance var[k]. ``sums`` (3,) = (xx, xy, yy) before the first step, updated.
    """
    xx, xy, yy = sums[0], sums[1], sums[2]
    for k in range(theta.shape[0]):
        h = theta[k] + weight * dtheta[k]
        c = math.cos(h)
        s = math.sin(h)
        v = var[k]
        xx = xx + v * s * s
        xy = xy + -(v * s * c)
        yy = yy + v * c * c
        out[k, 0, 0] += xx
        out[k, 0, 1] += xy
        out[k, 1, 0] += xy
        out[k, 1, 1] += yy
    sums[0], sums[1], sums[2] = xx, xy, yy
