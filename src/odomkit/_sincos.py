"""sin φ, cos φ and sin φ / φ of small angles for the numba kernels (``fast`` extra).

Dead reckoning (:mod:`odomkit._integrate_numba`) and the covariance recursion
(:mod:`odomkit.propagate._numba`) both carry the heading as a unit vector and turn it by
each step's half angle φ = Δθ/2, instead of calling cos and sin of the heading every
step. The turn needs sin φ and cos φ, and the exact-arc chord factor sin φ/φ; at usual
sampling rates φ is tiny and short Taylor polynomials give them to rounding, several
times faster than libm.
"""

from __future__ import annotations

import math

from numba import njit

#: A real cos/sin of the heading at least every ANCHOR steps: the rotated vector then
#: drifts by at most ~ANCHOR rounding errors (~1e-14) from (cos θ, sin θ).
ANCHOR = 128

# |φ| below this takes sin φ, cos φ, sinc φ from Taylor polynomials to φ^14: the first
# omitted term, φ^16/17!, is under 1e-24 there, far below double rounding.
POLY_LIMIT = 0.25
# Typical steps turn far less (|φ| < 0.015 for 99.99 % of a 100 Hz log), and there
# polynomials to φ^6 suffice: at |φ| = 0.025 the first omitted terms, φ^8/8! (cos) and
# φ^8/9! (sinc), are below 4e-18, a thirtieth of an ulp of 1. Horner's rule is a chain
# of dependent operations, so the shorter polynomials cut the latency of every step by
# about a quarter (measured 27 -> 19 ns a step in the covariance recursion).
SHORT_LIMIT = 0.025
S1, S2, S3, S4, S5, S6, S7 = ((-1.0) ** k / math.factorial(2 * k + 1) for k in range(1, 8))
C1, C2, C3, C4, C5, C6, C7 = ((-1.0) ** k / math.factorial(2 * k) for k in range(1, 8))


# inline="always" inlines the polynomial into each kernel, which compiles it with its own
# flags (the dead-reckoning kernel uses fastmath, the covariance kernel does not).
@njit(cache=True, nogil=True, inline="always")
def sin_cos_sinc(phi: float) -> tuple[float, float, float]:
    """sin φ, cos φ, sin φ / φ; polynomials below :data:`POLY_LIMIT`, libm above.

    Coefficients are multiplied, not divided: a division costs several products.
    """
    p2 = phi * phi
    if abs(phi) < SHORT_LIMIT:
        sinc = 1.0 + p2 * (S1 + p2 * (S2 + p2 * S3))
        cos = 1.0 + p2 * (C1 + p2 * (C2 + p2 * C3))
        return phi * sinc, cos, sinc
    if abs(phi) < POLY_LIMIT:
        sinc = 1.0 + p2 * (S1 + p2 * (S2 + p2 * (S3 + p2 * (S4 + p2 * (S5 + p2 * (
            S6 + p2 * S7))))))
        cos = 1.0 + p2 * (C1 + p2 * (C2 + p2 * (C3 + p2 * (C4 + p2 * (C5 + p2 * (
            C6 + p2 * C7))))))
        return phi * sinc, cos, sinc
    s = math.sin(phi)
    return s, math.cos(phi), s / phi
