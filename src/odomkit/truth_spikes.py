"""Spikes in a truth's positions: single fixes (or a few) that jump off the path and back.

A GPS under trees or beside buildings (multipath) now and then puts one fix metres away
from its neighbours 0.2 s before and after, which no vehicle can do. Such a fix is the
truth's error, not the odometry's: scored as a window's end it reads as an odometry error
of metres, and in a start heading fitted to the positions around it, it turns the start
the wrong way (on a real car logged at 5 Hz, one such fix 8 m off turned a window's fitted
start heading by about 3 rad, against a claimed σ of 0.26 rad, and scored it at NEES 4361).

A fix is a spike when it lies off the path its neighbours give, on every side that can
tell: three straight lines predict it, through its two neighbours (interpolated at its
time), through the two fixes before it and through the two after it (extrapolated), and it
must lie off each by more than both

* :data:`SPIKE_SIGMAS` × what the truth's own noise puts there: the scatter of every fix
  about its neighbours' line (a robust estimate: the median distance / √(ln 4), the median
  of a 2-D Gaussian's radius), scaled by how much each line amplifies the noise of the
  fixes it is drawn through; honest noise passes 6 σ with probability e⁻¹⁸, and
* the most a vehicle could leave that line by accelerating at :data:`MAX_ACCELERATION`
  (a line through fixes at t₁, t₂ misses a path of acceleration a at t by at most
  a·|t − t₁|·|t − t₂|/2), so a real manoeuvre, however sharp, is never one.

A line that reaches across a gap (a spacing over twice the truth's median spacing) says
nothing and is not asked; a fix no line can be asked of is kept. The lines on either side
keep a spike's honest neighbours: each has one line that does not pass through the spike.
So a spike of one or two fixes is found; a jump that lasts three fixes or more looks like
a shift of the whole path, and is not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

__all__ = ["MAX_ACCELERATION", "SPIKE_SIGMAS", "Spikes", "spike_fixes"]

#: No wheeled vehicle accelerates harder than this [m/s²] (2 g): a fix whose departure from
#: its neighbours' line needs more is not the vehicle's motion.
MAX_ACCELERATION = 20.0
#: A spike lies this many times the truth's robust neighbour scatter off its neighbours' line.
SPIKE_SIGMAS = 6.0


@dataclass(frozen=True)
class Spikes:
    """The spikes :func:`spike_fixes` found.

    Parameters
    ----------
    index : ndarray of int, shape (S,)
        Indices of the spike fixes in the truth, increasing.
    t : ndarray, shape (S,)
        Their times [s].
    off : ndarray, shape (S,)
        How far each lies off the line through its two neighbours [m] (beside a gap, where
        that line is not asked, off the farthest line that found it).
    scatter : float
        The truth's robust noise σ per axis [m], from the fixes' scatter about their
        neighbours' lines.
    """

    index: NDArray[np.intp]
    t: NDArray[np.float64]
    off: NDArray[np.float64]
    scatter: float

    def __len__(self) -> int:
        return int(self.index.size)


def _departure(t: NDArray[np.float64], xy: NDArray[np.float64], i: NDArray[np.intp],
               a: NDArray[np.intp], b: NDArray[np.intp]
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """How far each fix ``i`` lies off the line through fixes ``a`` and ``b`` [m], the factor
    by which that line amplifies the fixes' noise variance (1 + w_a² + w_b², its weights
    w), and the most a vehicle's acceleration could put it there [m]."""
    w_b = ((t[i] - t[a]) / (t[b] - t[a]))[:, None]
    line = xy[a] + w_b * (xy[b] - xy[a])
    off = np.hypot(*(xy[i] - line).T)
    noise = 1.0 + (1.0 - w_b[:, 0]) ** 2 + w_b[:, 0] ** 2
    reach = 0.5 * MAX_ACCELERATION * np.abs(t[i] - t[a]) * np.abs(t[i] - t[b])
    return off, noise, reach


def spike_fixes(t: NDArray[np.float64], xy: NDArray[np.float64]) -> Spikes:
    """The fixes that jump off the path and back (see the module's docstring).

    Parameters
    ----------
    t : ndarray, shape (K,)
        Strictly increasing times of the fixes [s].
    xy : ndarray, shape (K, 2)
        Their positions [m].

    Returns
    -------
    :class:`Spikes` (empty where there are fewer than 5 fixes, or none).

    Examples
    --------
    >>> t = np.arange(20) * 0.2
    >>> xy = np.column_stack((3.0 * t, np.zeros(20)))
    >>> xy[7] += (0.0, 8.0)
    >>> found = spike_fixes(t, xy)
    >>> found.index.tolist(), round(float(found.off[0]), 6)
    ([7], 8.0)
    """
    t = np.asarray(t, dtype=float)
    xy = np.asarray(xy, dtype=float)
    k = t.size
    none = Spikes(np.empty(0, dtype=np.intp), np.empty(0), np.empty(0), 0.0)
    if k < 5:
        return none
    step = np.diff(t)
    # Gaps before each fix: long[j] counts the spacings over twice the median among the first j.
    long = np.concatenate(([0], np.cumsum(step > 2.0 * float(np.median(step)))))
    every = np.arange(k)
    # The three lines of each fix: (first, second) fix indices, and whether both gaps are short.
    lines = []
    for da, db in ((-1, 1), (-2, -1), (1, 2)):
        a, b = every + da, every + db
        inside = (np.minimum(a, b) >= 0) & (np.maximum(a, b) < k)
        lo, hi = np.minimum(every, np.minimum(a, b)), np.maximum(every, np.maximum(a, b))
        lo, hi = lo.clip(0, k - 1), hi.clip(0, k - 1)
        asked = inside & (long[hi] == long[lo])  # no gap from its first fix to its last
        lines.append((a.clip(0, k - 1), b.clip(0, k - 1), asked))
    off_between, noise_between, _ = _departure(t, xy, every[1:-1], every[:-2], every[2:])
    usable = lines[0][2][1:-1]
    if not usable.any():
        return none
    # Robust unit scatter: the median radius of a 2-D Gaussian is σ√(ln 4).
    unit = off_between[usable] / np.sqrt(noise_between[usable])
    scatter = float(np.median(unit)) / math.sqrt(math.log(4.0))
    asked_any = np.zeros(k, dtype=bool)
    passed_any = np.zeros(k, dtype=bool)
    worst = np.zeros(k)
    for a, b, asked in lines:
        i = np.flatnonzero(asked)
        off, noise, reach = _departure(t, xy, i, a[i], b[i])
        fails = off > np.maximum(SPIKE_SIGMAS * scatter * np.sqrt(noise), reach)
        asked_any[i] = True
        passed_any[i[~fails]] = True
        worst[i] = np.maximum(worst[i], np.where(fails, off, 0.0))
    spike = asked_any & ~passed_any
    index = np.flatnonzero(spike).astype(np.intp)
    if index.size == 0:
        return replace(none, scatter=scatter)
    # How far off: the line between its neighbours where that was asked, else the worst asked.
    between = np.zeros(k)
    between[1:-1] = np.where(usable, off_between, 0.0)
    off_spike = np.where(between[index] > 0, between[index], worst[index])
    return Spikes(index, t[index], off_spike, scatter)

