"""Numba kernel for :func:`odomkit.integrate.dead_reckon` (optional ``fast`` extra).

The numpy path spends its time in three transcendental calls per sample (cos and sin of
the heading, sin of the half step for the chord factor). Here the heading is carried as a
unit vector (cos θ, sin θ) and turned by each step's half angle φ = Δθ/2, whose sine and
cosine come from the Taylor series of :mod:`odomkit.angles` when |φ| is small (always, at
usual sampling rates; :func:`odomkit.angles.sin_cos_sinc`). Every ``ANCHOR`` steps the
vector is recomputed from the summed heading, so the rounding of repeated rotations cannot
build up; the result agrees with the numpy path to about 1e-15 relative.

Loaded by :func:`odomkit.jit.load`; importing this module imports numba.
"""

from __future__ import annotations

import math

import numpy as np

from odomkit import angles
from odomkit.angles import ANCHOR
from odomkit.jit import njit

# inline="always" inlines the polynomials into the kernel, which compiles them with its
# own flags (fastmath here; the covariance kernel has none).
sin_cos_sinc = njit(angles.sin_cos_sinc, inline="always")

__all__ = ["dead_reckon_kernel"]

EULER, MIDPOINT, EXACT = 0, 1, 2


# fastmath halves the time (it lets LLVM reorder the independent polynomial work). The
# heading sum stays a plain sequential sum (a loop-carried dependence is not reordered),
# which the tests check bit for bit; inputs are checked finite by the caller, as the
# flags assume.
@njit(fastmath=True)
def dead_reckon_kernel(dd: np.ndarray, dtheta: np.ndarray, x0: float, y0: float,
                       theta0: float, method: int, out: np.ndarray) -> None:
    """Fill ``out`` (M+1, 3) with the poses; see ``integrate.dead_reckon``."""
    x, y, th = x0, y0, theta0
    out[0, 0], out[0, 1], out[0, 2] = x, y, th
    c, s = 1.0, 0.0
    for k in range(dd.size):
        if k % ANCHOR == 0:
            c, s = math.cos(th), math.sin(th)
        d = dd[k]
        if method == EULER:
            dx, dy = d * c, d * s
            sp, cp, _ = sin_cos_sinc(dtheta[k])
            c, s = c * cp - s * sp, s * cp + c * sp
        else:
            sp, cp, sinc = sin_cos_sinc(0.5 * dtheta[k])
            cm, sm = c * cp - s * sp, s * cp + c * sp  # heading at the middle of the step
            # The full turn by 2φ from double angles, so the next heading comes straight
            # from this one rather than through the middle one (a shorter dependency chain).
            c2, s2 = 1.0 - 2.0 * sp * sp, 2.0 * sp * cp
            length = d * sinc if method == EXACT else d
            dx, dy = length * cm, length * sm
            c, s = c * c2 - s * s2, s * c2 + c * s2
        x += dx
        y += dy
        th += dtheta[k]
        out[k + 1, 0], out[k + 1, 1], out[k + 1, 2] = x, y, th

