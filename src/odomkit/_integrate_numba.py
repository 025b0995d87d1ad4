"""Numba kernel for dead reckoning (optional ``fast`` extra): :func:`dead_reckon_kernel`.

One compiled pass per chunk of :data:`CHUNK` steps turns the inputs, body steps (Δd, Δθ)
or the two wheels' travels, into pose rows written straight into the caller's (M+1, 3)
array. Apart from that array only a 34 kB work buffer is used: no temporary arrays, so
memory stays bounded however long the log. The numpy path
(:func:`odomkit.integrate.dead_reckon`) takes three transcendental calls per step; here
the heading is carried as a unit vector (cos θ, sin θ) and turned by each step's half
angle φ = Δθ/2, whose sine and cosine come from the series of :mod:`odomkit.angles`.
Each chunk runs in four stages (``benchmarks/dead_reckoning.py`` times each):

1. ``_load``: Δd and Δθ of each step into the work buffer; from wheel travels with the
   operations of :func:`odomkit.kinematics.diff_body_steps`, so the same bits. This is
   where the inputs are read from memory; vectorised.
2. ``_anchors``: the chunk is cut into :data:`LANES` blocks of ``ANCHOR`` steps. Each
   block starts from a real cos/sin of its first heading (θ at the chunk start plus the
   sums of Δθ of the blocks before it), so the rounding of repeated rotations cannot
   build up over more than ``ANCHOR`` steps (~1e-14).
3. ``_turn_*``: within a block the turns form a chain (each heading is the previous one
   turned), which one core runs step after step: ~40 flops a step, which set the pace
   (~4 ns a step) when the kernel was a single loop. The blocks are independent, so all
   :data:`LANES` of them turn at once, one SIMD lane each (~0.8 ns a step). This needs a
   branch-free series: the short one of :mod:`odomkit.angles` when every |φ| of the chunk
   is below ``SHORT_BELOW``, else the full one below ``SERIES_BELOW``; a chunk with a
   larger turn (beyond 1 rad, or 2 rad of Δθ) runs the same loop through
   :func:`odomkit.angles.sin_cos_sinc`, which calls libm there.
4. ``_emit``: one sequential pass adds up θ, x and y and writes the pose rows. θ is the
   plain sum θ_0 + Δθ_0 + … in step order: the very bits of the numpy path's cumulative
   sum (the tests check this), which the covariance kernel (:mod:`odomkit.propagate._numba`)
   recognises as consistent headings. Long outputs are written with streaming stores
   (:mod:`odomkit._stores`).

Positions agree with the numpy path to about 1e-15 relative. Loaded by
:func:`odomkit.jit.load`; importing this module imports numba.
"""

from __future__ import annotations

import math

import numpy as np

from odomkit import angles
from odomkit._stores import store_fence, stream_store
from odomkit.angles import ANCHOR, SERIES_BELOW, SHORT_BELOW
from odomkit.jit import njit

# inline="always" inlines the series into each stage, compiled with that stage's flags.
sin_cos_sinc = njit(angles.sin_cos_sinc, inline="always")
sin_cos_sinc_series = njit(angles.sin_cos_sinc_series, inline="always")
sin_cos_sinc_short = njit(angles.sin_cos_sinc_short, inline="always")

__all__ = ["BODY", "CHUNK", "EULER", "EXACT", "LANES", "MIDPOINT", "STREAM_FROM", "WHEELS", "WORK",
           "dead_reckon_kernel"]

EULER, MIDPOINT, EXACT = 0, 1, 2
#: What the kernel's two input arrays hold: body steps (Δd, Δθ) or wheel travels.
BODY, WHEELS = 0, 1

#: Blocks turned side by side in stage 3: eight doubles fill one AVX-512 register (two
#: AVX2 ones). Sixteen measured no faster.
LANES = 8
#: Steps per chunk; the work buffer (:data:`WORK` doubles) then stays in the L1 cache.
CHUNK = LANES * ANCHOR

# Work-buffer layout. One buffer with compile-time offsets rather than several arrays:
# LLVM can then prove that the lanes' rows do not overlap, which it must know to
# vectorise stage 3 (it cannot for separate numba arrays).
_A = 0  # Δθ of each step, step order
_D = _A + CHUNK  # Δd of each step, step order
_HX = _D + CHUNK  # direction (hx, hy) of each step's displacement Δd·(hx, hy),
_HY = _HX + CHUNK  # lane-major: [j * LANES + lane] for step lane * ANCHOR + j
_C = _HY + CHUNK  # heading vector (cos, sin) carried by each lane
_S = _C + LANES
_BIG = _S + LANES  # largest |φ| each lane has met in the chunk
WORK = _BIG + LANES

#: From this many steps on the pose rows are written with streaming stores: 6 MB of
#: output and more would not stay in the cache anyway. Below, ordinary stores leave the
#: poses in the cache for whoever reads them next.
STREAM_FROM = 1 << 18

_FAST = {"contract"}


@njit
def _load(first: np.ndarray, second: np.ndarray, mode: int, scale_first: float,
          scale_second: float, wheel_base: float, c0: int, m: int, w: np.ndarray) -> None:
    """Stage 1: Δd, Δθ of steps c0 … c0+m−1 into ``w``, zeros up to CHUNK (no fastmath)."""
    # Views, so that every index is a loop counter known to be >= 0: LLVM then drops the
    # negative-index wraparound and vectorises (with it, it gathers element by element).
    one = first[c0:c0 + m]
    two = second[c0:c0 + m]
    if mode == WHEELS:
        for i in range(m):
            # kinematics.diff_body_steps after the per-wheel scale, operation for operation.
            left = one[i] * scale_first
            right = two[i] * scale_second
            w[_D + i] = 0.5 * (right + left)
            w[_A + i] = (right - left) / wheel_base
    else:
        for i in range(m):
            w[_D + i] = one[i]
            w[_A + i] = two[i]
    for i in range(m, CHUNK):
        w[_D + i] = 0.0
        w[_A + i] = 0.0


# Reassociation lets LLVM vectorise the block sums; they only place the anchors.
@njit(fastmath={"reassoc"})
def _anchors(w: np.ndarray, theta: float) -> None:
    """Stage 2: cos/sin of each block's first heading into ``w``: θ at the chunk start
    plus the blocks' sums of Δθ (a few ulp of θ from the sequential sum of stage 4)."""
    for lane in range(LANES):
        w[_C + lane] = math.cos(theta)
        w[_S + lane] = math.sin(theta)
        w[_BIG + lane] = 0.0
        total = 0.0
        for j in range(ANCHOR):
            total += w[_A + lane * ANCHOR + j]
        theta += total


@njit(inline="always")
def _turn(w: np.ndarray, j: int, lane: int, phi: float, sp: float, cp: float, sinc: float,
          method: int) -> None:
    """One step of one lane: its displacement direction into ``w``, the lane's heading
    vector turned, and its largest |φ| updated. (sp, cp, sinc) are sin φ, cos φ,
    sin φ/φ of the step's turn φ: Δθ for euler, Δθ/2 otherwise."""
    c = w[_C + lane]
    s = w[_S + lane]
    if method == EULER:
        hx, hy = c, s
        c, s = c * cp - s * sp, s * cp + c * sp
    else:
        cm, sm = c * cp - s * sp, s * cp + c * sp  # heading at the middle of the step
        f = sinc if method == EXACT else 1.0  # chord factor of the exact arc
        hx, hy = f * cm, f * sm
        # The full turn by 2φ from double angles, so the next heading comes straight from
        # this one rather than through the middle one (a shorter dependency chain).
        c2, s2 = 1.0 - 2.0 * sp * sp, 2.0 * sp * cp
        c, s = c * c2 - s * s2, s * c2 + c * s2
    w[_HX + j * LANES + lane] = hx
    w[_HY + j * LANES + lane] = hy
    w[_C + lane] = c
    w[_S + lane] = s
    # An elementwise maximum per lane vectorises; a reduction over the chunk would not.
    big = w[_BIG + lane]
    w[_BIG + lane] = abs(phi) if abs(phi) > big else big


@njit(inline="always")
def _largest(w: np.ndarray) -> float:
    """Largest |φ| over all lanes (after stage 3)."""
    big = 0.0
    for lane in range(LANES):
        big = max(big, w[_BIG + lane])
    return big


# Contraction into FMAs: fewer, faster operations. (No flag that assumes finite numbers:
# the caller checks the inputs only when the last pose comes out non-finite.) The loop
# over the lanes is the inner one, so it is the one vectorised.
@njit(fastmath=_FAST)
def _turn_short(w: np.ndarray, method: int) -> float:
    """Stage 3 with the short series; valid if the returned largest |φ| < SHORT_BELOW."""
    half = 1.0 if method == EULER else 0.5
    for j in range(ANCHOR):
        for lane in range(LANES):
            phi = half * w[_A + lane * ANCHOR + j]
            sp, cp, sinc = sin_cos_sinc_short(phi)
            _turn(w, j, lane, phi, sp, cp, sinc, method)
    return _largest(w)


@njit(fastmath=_FAST)
def _turn_series(w: np.ndarray, method: int) -> float:
    """Stage 3 with the full series; valid if the returned largest |φ| < SERIES_BELOW."""
    half = 1.0 if method == EULER else 0.5
    for j in range(ANCHOR):
        for lane in range(LANES):
            phi = half * w[_A + lane * ANCHOR + j]
            sp, cp, sinc = sin_cos_sinc_series(phi)
            _turn(w, j, lane, phi, sp, cp, sinc, method)
    return _largest(w)


@njit(fastmath=_FAST)
def _turn_any(w: np.ndarray, method: int) -> None:
    """Stage 3 for any turn (libm beyond the series; not vectorised)."""
    half = 1.0 if method == EULER else 0.5
    for j in range(ANCHOR):
        for lane in range(LANES):
            phi = half * w[_A + lane * ANCHOR + j]
            sp, cp, sinc = sin_cos_sinc(phi)
            _turn(w, j, lane, phi, sp, cp, sinc, method)


@njit
def _emit(w: np.ndarray, c0: int, m: int, x: float, y: float, theta: float, out: np.ndarray,
          stream: bool) -> tuple[float, float, float]:
    """Stage 4: poses after steps c0 … c0+m−1 into rows c0+1 … of ``out``; returns the
    last pose. Sequential sums, no fastmath: θ gets the numpy path's bits."""
    rows = out[c0 + 1:c0 + 1 + m]  # a view: indices >= 0 (see _load)
    for lane in range(LANES):
        first = lane * ANCHOR
        for j in range(min(ANCHOR, m - first)):
            i = first + j
            d = w[_D + i]
            x += d * w[_HX + j * LANES + lane]
            y += d * w[_HY + j * LANES + lane]
            theta += w[_A + i]
            if stream:
                stream_store(rows, i, 0, x)
                stream_store(rows, i, 1, y)
                stream_store(rows, i, 2, theta)
            else:
                rows[i, 0] = x
                rows[i, 1] = y
                rows[i, 2] = theta
    return x, y, theta


@njit
def dead_reckon_kernel(first: np.ndarray, second: np.ndarray, mode: int, scale_first: float,
                       scale_second: float, wheel_base: float, x0: float, y0: float,
                       theta0: float, method: int, out: np.ndarray) -> None:
    """Fill ``out`` (M+1, 3) with the poses; see :func:`odomkit.integrate.dead_reckon`.

    ``first``, ``second`` (M,) are Δd [m] and Δθ [rad] (``mode`` BODY; the scales and
    ``wheel_base`` are unused), or the left and right wheels' travels in any unit (mode
    WHEELS): ``scale_first``, ``scale_second`` [m per unit] turn them into metres and
    ``wheel_base`` [m] into (Δd, Δθ). ``method`` is EULER, MIDPOINT or EXACT. A NaN or
    infinite input makes every later pose non-finite (sums keep them), so the caller
    need only look at the last pose to know whether to search the inputs.
    """
    n = first.size
    w = np.empty(WORK)
    x, y, theta = x0, y0, theta0
    out[0, 0], out[0, 1], out[0, 2] = x, y, theta
    stream = n >= STREAM_FROM
    for c0 in range(0, n, CHUNK):
        m = min(CHUNK, n - c0)
        _load(first, second, mode, scale_first, scale_second, wheel_base, c0, m, w)
        _anchors(w, theta)
        if not _turn_short(w, method) < SHORT_BELOW:
            _anchors(w, theta)
            if not _turn_series(w, method) < SERIES_BELOW:
                _anchors(w, theta)
                _turn_any(w, method)
        x, y, theta = _emit(w, c0, m, x, y, theta, out, stream)
    if stream:
        store_fence()
