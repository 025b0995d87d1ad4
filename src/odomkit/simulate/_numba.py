"""The numba kernel of the Monte Carlo engine (imported only when used; see _kernels).

Exact-arc step, as :func:`odomkit.kinematics.step_displacement` with ``method="exact"``,
but carrying the unit heading vector (cos θ, sin θ) and turning it twice by Δθ/2, with
sin and cos of the small half angle from their Taylor series: exact to rounding for
|Δθ/2| < :data:`POLY_BELOW` (first omitted terms u¹²/13! < 1e-17 and u¹⁴/14! < 1e-19).
The vector is recomputed from the separately summed θ every :data:`RESYNC_EVERY`
partitions, counted from the start of the path. No fastmath: the arithmetic, and so
the numbers, cannot depend on vectorisation.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

RESYNC_EVERY = 64
POLY_BELOW = 0.25
_S1, _S2, _S3, _S4, _S5 = -1 / 6, 1 / 120, -1 / 5040, 1 / 362880, -1 / 39916800
_C1, _C2, _C3, _C4, _C5, _C6 = -1 / 2, 1 / 24, -1 / 720, 1 / 40320, -1 / 3628800, 1 / 479001600


@numba.njit(nogil=True, inline="always", cache=True)
def _series(u: float) -> tuple[float, float]:
    """(sin u / u, cos u) for small u."""
    u2 = u * u
    sinc = 1.0 + u2 * (_S1 + u2 * (_S2 + u2 * (_S3 + u2 * (_S4 + u2 * _S5))))
    cu = 1.0 + u2 * (_C1 + u2 * (_C2 + u2 * (_C3 + u2 * (_C4 + u2 * (_C5 + u2 * _C6)))))
    return sinc, cu


@numba.njit(nogil=True, inline="always", cache=True)
def _arc(x: Any, y: Any, th: Any, c: Any, s: Any, r: int, dd: float, dth: float, su: float,
         cu: float, sinc: float) -> None:
    cc = c[r]
    ss = s[r]
    # heading at the middle of the arc: (cos θ, sin θ) turned by Δθ/2
    cm = cc * cu - ss * su
    sm = ss * cu + cc * su
    length = dd * sinc  # chord of the arc, sinc(Δθ/2)·Δd
    x[r] += length * cm
    y[r] += length * sm
    th[r] += dth
    c[r] = cm * cu - sm * su
    s[r] = sm * cu + cm * su


@numba.njit(nogil=True, cache=True)
def _advance(x: Any, y: Any, th: Any, c: Any, s: Any, z: Any, coef: Any,
             first_partition: int) -> None:
    n_part, _, n_runs = z.shape
    dd0, ad, bd, dt0, at, bt = coef[0], coef[1], coef[2], coef[3], coef[4], coef[5]
    for p in range(n_part):
        z0 = z[p, 0]
        z1 = z[p, 1]
        if (first_partition + p) % RESYNC_EVERY == 0:
            for r in range(n_runs):
                c[r] = math.cos(th[r])
                s[r] = math.sin(th[r])
        u_max = 0.0
        for r in range(n_runs):
            u_max = max(u_max, abs(0.5 * (dt0 + at * z0[r] + bt * z1[r])))
        if u_max < POLY_BELOW:
            # branch-free, vectorised: every run of this partition takes the series
            for r in range(n_runs):
                dth = dt0 + at * z0[r] + bt * z1[r]
                u = 0.5 * dth
                sinc, cu = _series(u)
                _arc(x, y, th, c, s, r, dd0 + ad * z0[r] + bd * z1[r], dth, u * sinc, cu, sinc)
        else:
            # per run the same arithmetic as above where |u| is small, so a run's numbers
            # never depend on the other runs of its block
            for r in range(n_runs):
                dth = dt0 + at * z0[r] + bt * z1[r]
                u = 0.5 * dth
                if abs(u) < POLY_BELOW:
                    sinc, cu = _series(u)
                    su = u * sinc
                else:
                    su = math.sin(u)
                    cu = math.cos(u)
                    sinc = su / u
                _arc(x, y, th, c, s, r, dd0 + ad * z0[r] + bd * z1[r], dth, su, cu, sinc)


def advance_state(state: NDArray[np.float64], z: NDArray[np.float64],
                  coef: NDArray[np.float64], first_partition: int) -> None:
    """Advance ``state`` (5, B) = x, y, θ, cos θ, sin θ in place over ``z.shape[0]``
    partitions; ``z`` (P, 2, B) standard normals, ``coef`` as in _kernels."""
    _advance(state[0], state[1], state[2], state[3], state[4], z, coef, first_partition)
