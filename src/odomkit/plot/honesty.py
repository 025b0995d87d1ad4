"""Honesty at a glance: the coverage (reliability) diagram, and profile likelihoods.

A covariance is honest when the fraction of errors inside its p-ellipse is p at every p:
the reliability diagram puts the observed fractions against the predicted probabilities,
with the diagonal and the range n independent samples would scatter in (binomial). A
fitted noise parameter is as certain as its profile likelihood is narrow: the profile
with the χ²₁ threshold marks the profile-likelihood interval.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import InputError
from odomkit.plot.spatial import legend

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

__all__ = ["binomial_band", "draw_profile", "draw_reliability"]

_MARKERS = ("o", "s", "^", "D", "v", "P")


def binomial_band(p: ArrayLike, n: int, level: float = 0.95
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Central ``level`` range of the fraction of n independent samples inside an ellipse
    of probability p: the binomial quantiles divided by n, each
    :func:`odomkit.evaluate.coverage_range` (the range evaluate's verdict judges by).

    Parameters
    ----------
    p : array_like
        Predicted probabilities.
    n : int
        Samples scored.
    level : float

    Returns
    -------
    lo, hi : ndarray, like ``p``

    Examples
    --------
    >>> lo, hi = binomial_band([0.5, 0.95], 100)
    >>> lo.tolist(), hi.tolist()
    ([0.4, 0.9], [0.6, 0.99])
    """
    from odomkit.evaluate import coverage_range

    if not isinstance(n, int | np.integer) or n < 1:
        raise InputError(f"n_scored must be a positive integer, got {n!r}")
    q = np.asarray(p, dtype=float)
    ranges = np.array([coverage_range(int(n), float(x), level) for x in q.ravel()]).reshape(*q.shape, 2)
    return ranges[..., 0], ranges[..., 1]


def _levels(cover: Mapping[float, float | None] | Mapping[str, float | None]
            ) -> tuple[NDArray[np.float64], ...]:
    pairs = sorted((float(k), v) for k, v in cover.items() if v is not None)
    return np.array([k for k, _ in pairs]), np.array([v for _, v in pairs], dtype=float)


def draw_reliability(
    ax: Axes,
    coverages: Mapping[str, Mapping[float, float | None]] | Mapping[str, Mapping[str, float | None]],
    *,
    n_scored: int | Mapping[str, int] | None = None,
    band_level: float = 0.95,
) -> list[Artist]:
    """Coverage (reliability) diagram: predicted probability of each ellipse against the
    fraction of errors observed inside it, one series per label (white-only and
    white + bias side by side), with the diagonal of an honest covariance.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    coverages : mapping of label to {probability: fraction}
        E.g. ``{"white": {0.5: 0.41, 0.9: 0.80, 0.95: 0.86, 0.99: 0.93}}``; the
        probabilities may be written as strings (``"0.95"``, as
        :func:`odomkit.evaluate.coverage` gives them); None fractions are left out.
    n_scored : int or mapping of label to int, optional
        Independent samples behind the fractions: draws the central ``band_level`` binomial
        range (:func:`binomial_band`) around the diagonal, one per distinct n.
    band_level : float

    Returns
    -------
    list of Artist
        The diagonal, the band(s) and one line per series.
    """
    if not coverages:
        raise InputError("draw_reliability needs at least one series of coverages")
    artists: list[Artist] = []
    (diag,) = ax.plot([0, 1], [0, 1], "-", color="0.4", lw=1.0, label="honest (observed = predicted)")
    artists.append(diag)
    counts: dict[int, list[str]] = {}
    if isinstance(n_scored, Mapping):
        for label, n in n_scored.items():
            counts.setdefault(int(n), []).append(label)
    elif n_scored is not None:
        counts[int(n_scored)] = list(coverages)
    low = 0.45
    series = []
    for label, cover in coverages.items():
        p, frac = _levels(cover)
        series.append((label, p, frac))
        if frac.size:
            low = min(low, float(frac.min()) - 0.05)
    low = max(0.0, np.floor(low * 20) / 20)
    grid = np.linspace(max(low, 0.001), 0.999, 400)
    for k, (n, labels) in enumerate(sorted(counts.items())):
        lo, hi = binomial_band(grid, n, band_level)
        who = "" if len(counts) == 1 else f" ({', '.join(labels)})"
        band = ax.fill_between(grid, lo, hi, step="mid", color="0.5", alpha=0.18 + 0.07 * k, lw=0,
                               label=f"{100 * band_level:g} % range of {n} independent samples{who}")
        artists.append(band)
    for k, (label, p, frac) in enumerate(series):
        (line,) = ax.plot(p, frac, marker=_MARKERS[k % len(_MARKERS)], ms=7, lw=1.2, label=label)
        artists.append(line)
    ax.set_xlim(low, 1.0)
    ax.set_ylim(low, 1.0)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("predicted probability of the ellipse")
    ax.set_ylabel("observed fraction inside")
    ax.grid(True, lw=0.4, alpha=0.5)
    # Below the axes: points can lie on either side of the diagonal, anywhere.
    legend(ax, loc="upper center", bbox_to_anchor=(0.5, -0.17), borderaxespad=0.0)
    return artists


def draw_profile(
    ax: Axes,
    values: ArrayLike,
    log_likelihood: ArrayLike,
    *,
    interval: tuple[float, float] | None = None,
    name: str = "",
    unit: str = "",
    estimate: float | None = None,
    maximum: float | None = None,
    level: float = 0.95,
) -> list[Artist]:
    """A profile likelihood as the deviance 2(ℓ̂ − ℓ_p(v)), with the χ²₁ threshold line
    whose crossings are the ``level`` profile-likelihood interval.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    values : array_like, shape (K,)
        The parameter [its own unit, ``unit``], increasing.
    log_likelihood : array_like, shape (K,)
        The profile log-likelihood ℓ_p at each value (maximised over the other
        parameters; :mod:`odomkit.calibrate.profile`).
    interval : (float, float), optional
        The fit's interval, shaded (an infinite upper end: open above, to the right edge).
    name, unit : str
        The parameter's name and unit, for the axis label.
    estimate : float, optional
        The fitted value, marked.
    maximum : float, optional
        ℓ̂ (default: the largest ``log_likelihood``).
    level : float
        Of the threshold χ²₁(level) (3.84 for 95 %).

    Returns
    -------
    list of Artist
        The profile, the threshold, and the interval and estimate when given.
    """
    from scipy.stats import chi2

    x = np.asarray(values, dtype=float)
    ll = np.asarray(log_likelihood, dtype=float)
    if x.shape != ll.shape or x.ndim != 1:
        raise InputError(f"values and log_likelihood must be 1-D of one length, got {x.shape}, {ll.shape}")
    top = float(np.nanmax(ll)) if maximum is None else float(maximum)
    dev = 2.0 * (top - ll)
    threshold = float(chi2.ppf(level, 1))
    pct = f"{100 * level:g} %"
    (curve,) = ax.plot(x, dev, "-", color="tab:blue", lw=1.5, label="profile 2(ℓ̂ − ℓ_p)")
    line = ax.axhline(threshold, color="tab:red", ls="--", lw=1.0,
                      label=f"χ²₁ threshold {threshold:.2f} ({pct})")
    out: list[Artist] = [curve, line]
    if interval is not None:
        lo, hi = interval
        right = hi if np.isfinite(hi) else float(np.nanmax(x))
        shown = f"{hi:.3g}" if np.isfinite(hi) else "∞ (open: the data do not bound it)"
        out.append(ax.axvspan(lo, right, color="tab:orange", alpha=0.2, lw=0,
                              label=f"{pct} interval [{lo:.3g}, {shown}]"))
    if estimate is not None:
        out.append(ax.axvline(estimate, color="black", lw=1.0, label=f"estimate {estimate:.3g}"))
    finite = dev[np.isfinite(dev)]
    highest = float(finite.max()) if finite.size else 0.0
    ax.set_ylim(-0.05 * threshold, max(1.6 * threshold, min(highest, 3 * threshold)))
    ax.set_xlabel(f"{name} [{unit}]" if unit else name)
    ax.set_ylabel("2 (ℓ̂ − ℓ_p)")
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
    ax.grid(True, lw=0.4, alpha=0.5)
    legend(ax, loc="lower center", bbox_to_anchor=(0.5, 1.01), borderaxespad=0.0)
    return out
