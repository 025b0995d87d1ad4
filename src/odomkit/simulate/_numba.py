"""The numba kernel of the Monte Carlo engine (imported only when used; see _kernels).

Exact-arc step, as :func:`odomkit.kinematics.step_displacement` with ``method="exact"``,
but carrying the unit heading vector (cos θ, sin θ) and turning it twice by Δθ/2, with
sin and cos of the half angle from their Taylor series
(:func:`odomkit.angles.sin_cos_sinc_series`, exact to rounding below
:data:`odomkit.angles.SERIES_BELOW`). The vector is recomputed from the separately
summed θ every :data:`RESYNC_EVERY` partitions, counted from the start of the path. A
lateral slip moves each step across its chord (the turned half-angle vector): a variant
of the loop compiled only when z has its third row (``zl`` is None otherwise, a branch
numba removes at compile time), so the kernel without it is unchanged. No fastmath: the
arithmetic, and so the numbers, cannot depend on vectorisation. Loaded by
:func:`odomkit.jit.load` (through :func:`odomkit.simulate._kernels.advance_numba`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit import angles
from odomkit.jit import njit

__all__ = ["RESYNC_EVERY", "advance_state"]

RESYNC_EVERY = 64
_SERIES_BELOW = angles.SERIES_BELOW
sin_cos_sinc_series = njit(angles.sin_cos_sinc_series, inline="always")


@njit(inline="always")
def _arc(x: Any, y: Any, th: Any, c: Any, s: Any, r: int, dd: float, dth: float, su: float,
         cu: float, sinc: float) -> tuple[float, float]:
    """One exact-arc step of run r; returns the chord direction (cos θ̄, sin θ̄)."""
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
    return cm, sm


@njit(inline="always")
def _slip(x: Any, y: Any, r: int, eps: float, cm: float, sm: float) -> None:
    """Move run r by ε across its chord (cos θ̄, sin θ̄): along (−sin θ̄, cos θ̄)."""
    x[r] -= eps * sm
    y[r] += eps * cm


@njit
def _advance(x: Any, y: Any, th: Any, c: Any, s: Any, z: Any, coef: Any,
             first_partition: int, sd: Any, st: Any, zl: Any, sl: float) -> None:
    n_part, _, n_runs = z.shape
    dd0, ad, bd, dt0, at, bt = coef[0], coef[1], coef[2], coef[3], coef[4], coef[5]
    # sd, st (B,): each run's bias shift of Δd, Δθ (zeros without bias noise; adding 0.0
    # leaves every number as it was)
    for p in range(n_part):
        z0 = z[p, 0]
        z1 = z[p, 1]
        if (first_partition + p) % RESYNC_EVERY == 0:
            for r in range(n_runs):
                c[r] = math.cos(th[r])
                s[r] = math.sin(th[r])
        u_max = 0.0
        for r in range(n_runs):
            u_max = max(u_max, abs(0.5 * (dt0 + st[r] + at * z0[r] + bt * z1[r])))
        # The full series (not angles.sin_cos_sinc, whose extra branch to the short series
        # would stop the loop from vectorising), else the direct formulas.
        if u_max < _SERIES_BELOW:
            # branch-free, vectorised: every run of this partition takes the series
            for r in range(n_runs):
                dth = dt0 + st[r] + at * z0[r] + bt * z1[r]
                su, cu, sinc = sin_cos_sinc_series(0.5 * dth)
                cm, sm = _arc(x, y, th, c, s, r, dd0 + sd[r] + ad * z0[r] + bd * z1[r], dth, su, cu, sinc)
                if zl is not None:
                    _slip(x, y, r, sl * zl[p, r], cm, sm)
        else:
            # per run the same arithmetic as above where |u| is small, so a run's numbers
            # never depend on the other runs of its block
            for r in range(n_runs):
                dth = dt0 + st[r] + at * z0[r] + bt * z1[r]
                u = 0.5 * dth
                if abs(u) < _SERIES_BELOW:
                    su, cu, sinc = sin_cos_sinc_series(u)
                else:
                    su = math.sin(u)
                    cu = math.cos(u)
                    sinc = su / u
                cm, sm = _arc(x, y, th, c, s, r, dd0 + sd[r] + ad * z0[r] + bd * z1[r], dth, su, cu, sinc)
                if zl is not None:
                    _slip(x, y, r, sl * zl[p, r], cm, sm)


def advance_state(state: NDArray[np.float64], z: NDArray[np.float64],
                  coef: NDArray[np.float64], first_partition: int,
                  shift: NDArray[np.float64] | None = None, lateral: float | None = None) -> None:
    """Advance ``state`` (5, B) = x, y, θ, cos θ, sin θ in place over ``z.shape[0]``
    partitions; ``z`` (P, 2, B) standard normals ((P, 3, B) with a lateral slip),
    ``coef`` as in _kernels; ``shift`` (2, B) each run's bias added to every partition's
    (Δd, Δθ); ``lateral`` the σ [m] of each partition's sideways slip (times z[:, 2])."""
    if shift is None:
        shift = np.zeros((2, state.shape[1]))
    zl = None if lateral is None else np.ascontiguousarray(z[:, 2, :])
    _advance(state[0], state[1], state[2], state[3], state[4], z, coef, first_partition,
             np.ascontiguousarray(shift[0]), np.ascontiguousarray(shift[1]), zl,
             0.0 if lateral is None else float(lateral))
