"""Figures over time or distance: the six covariance elements, the true error inside its
±2σ band, the difference between integration methods, and the NEES with its χ² band.

Every ``draw_*`` function draws on the matplotlib Axes it is given (one, or a sequence
where the figure has several panels) and returns the artists it added; inputs are numpy
arrays in SI units.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from odomkit.angles import wrap_angle
from odomkit.errors import InputError
from odomkit.plot.figure import thin
from odomkit.plot.spatial import legend

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

__all__ = ["COVARIANCE_ELEMENTS", "band_fraction", "draw_covariance_elements", "draw_error_band",
           "draw_method_differences", "draw_nees", "nees_band"]

#: The six distinct elements of a pose covariance, as Kelly (2004) Fig. 3 shows them:
#: (row, column, name, unit).
COVARIANCE_ELEMENTS = ((0, 0, "σ_xx", "m²"), (1, 1, "σ_yy", "m²"), (2, 2, "σ_θθ", "rad²"),
                       (0, 1, "σ_xy", "m²"), (0, 2, "σ_xθ", "m·rad"), (1, 2, "σ_yθ", "m·rad"))
_COMPONENTS = (("x", "m"), ("y", "m"), ("θ", "rad"))


def _axes(axes: Axes | Sequence[Axes], count: int, what: str) -> list[Axes]:
    out = list(axes) if isinstance(axes, Sequence) else [axes]
    if len(out) != count:
        raise InputError(f"{what} draws on {count} axes, got {len(out)}")
    return out


def draw_covariance_elements(axes: Sequence[Axes], s: ArrayLike, cov: ArrayLike, *,
                             s_label: str = "t [s]") -> list[Artist]:
    """The six covariance elements σ_xx, σ_yy, σ_θθ, σ_xy, σ_xθ, σ_yθ over time or
    distance, one panel each (Kelly 2004, Fig. 3).

    Parameters
    ----------
    axes : sequence of 6 matplotlib Axes
        In the order of :data:`COVARIANCE_ELEMENTS`.
    s : array_like, shape (N,)
        Time [s] or travelled distance [m]; say which in ``s_label``.
    cov : array_like, shape (N, 3, 3)
        Pose covariances [m², m·rad, rad²].
    s_label : str
        Label of the horizontal axis, with its unit.

    Returns
    -------
    list of Artist
        One line per element.
    """
    panels = _axes(axes, 6, "draw_covariance_elements")
    x = np.asarray(s, dtype=float)
    P = np.asarray(cov, dtype=float)
    if P.shape != (x.shape[0], 3, 3):
        raise InputError(f"cov must have shape ({x.shape[0]}, 3, 3) to match s, got {P.shape}")
    rows = thin(x.shape[0])
    out: list[Artist] = []
    for ax, (i, j, name, unit) in zip(panels, COVARIANCE_ELEMENTS, strict=True):
        (line,) = ax.plot(x[rows], P[rows, i, j], color="tab:blue" if i == j else "tab:purple", lw=1.3)
        ax.set_title(name, fontsize="medium")
        ax.set_xlabel(s_label)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 3))
        if i != j:
            ax.axhline(0.0, color="0.5", lw=0.6)
        ax.grid(True, lw=0.4, alpha=0.5)
        out.append(line)
    return out


def band_fraction(error: ArrayLike, sigma: ArrayLike, k: float = 2.0) -> float | None:
    """Fraction of the rows where |error| ≤ k·σ, over the rows where both are finite
    (None when there is none); the number :func:`draw_error_band` prints.

    >>> band_fraction([0.1, -0.3, 0.5, np.nan], [0.1, 0.1, 0.3, 1.0])
    0.6666666666666666
    """
    e = np.asarray(error, dtype=float)
    sd = np.asarray(sigma, dtype=float)
    ok = np.isfinite(e) & np.isfinite(sd)
    return float(np.mean(np.abs(e[ok]) <= k * sd[ok])) if ok.any() else None


def draw_error_band(axes: Sequence[Axes], t: ArrayLike, error: ArrayLike, sigma: ArrayLike, *,
                    k: float = 2.0, t_label: str = "t [s]") -> list[Artist]:
    """The true error of x, y and θ inside the ±kσ band of the predicted standard
    deviation, with the fraction of samples inside printed (the exercise's Fig. 3.16).

    Parameters
    ----------
    axes : sequence of 3 matplotlib Axes
        For x, y and θ.
    t : array_like, shape (N,)
        Time [s] (or distance [m]: say so in ``t_label``).
    error : array_like, shape (N, 3)
        Estimate − truth [m, m, rad] (the heading wrapped here); NaN where there is no
        truth.
    sigma : array_like, shape (N, 3)
        Predicted standard deviations [m, m, rad].
    k : float
        Half-width of the band in σ (2: a Gaussian error stays inside 95.45 % of the time).

    Returns
    -------
    list of Artist
        Per component: the error line and the band. The legend of each panel prints
        :func:`band_fraction`.
    """
    panels = _axes(axes, 3, "draw_error_band")
    x = np.asarray(t, dtype=float)
    e = np.array(error, dtype=float)
    sd = np.asarray(sigma, dtype=float)
    if e.shape != (x.shape[0], 3) or sd.shape != e.shape:
        raise InputError(f"error and sigma must have shape ({x.shape[0]}, 3), got {e.shape} and {sd.shape}")
    e[:, 2] = wrap_angle(e[:, 2])
    rows = thin(x.shape[0])
    out: list[Artist] = []
    for c, (ax, (name, unit)) in enumerate(zip(panels, _COMPONENTS, strict=True)):
        frac = band_fraction(e[:, c], sd[:, c], k)
        n = int(np.count_nonzero(np.isfinite(e[:, c]) & np.isfinite(sd[:, c])))
        text = (f"±{k:g}σ predicted (no true error to compare)" if frac is None
                else f"±{k:g}σ predicted: {frac:.3f} of {n} inside")
        band = ax.fill_between(x[rows], -k * sd[rows, c], k * sd[rows, c], color="tab:orange", alpha=0.3,
                               lw=0, label=text)
        (line,) = ax.plot(x[rows], e[rows, c], color="tab:blue", lw=1.0, label="true error")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(t_label)
        ax.set_ylabel(f"error in {name} [{unit}]")
        ax.grid(True, lw=0.4, alpha=0.5)
        legend(ax, loc="upper left")
        out += [line, band]
    return out


def draw_method_differences(ax: Axes, s: ArrayLike, tracks: Mapping[str, ArrayLike], *,
                            reference: str, s_label: str = "t [s]") -> list[Artist]:
    """How far each integration method (or sampling period) ends up from a reference: the
    position difference |p − p_ref| over time or distance (the exercise's Fig. 3.3, 3.11).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    s : array_like, shape (N,)
        The common time [s] or distance [m] of every track's rows.
    tracks : mapping of str to array_like of shape (N, 3)
        Poses [m, m, rad] by method name, all on ``s``; one of them is the ``reference``.
    reference : str
        The key the others are compared with.

    Returns
    -------
    list of Artist
        One line per track other than the reference. A logarithmic axis is used when the
        differences span more than two decades.
    """
    if reference not in tracks:
        raise InputError(f"reference {reference!r} is not one of the tracks: {', '.join(tracks)}")
    x = np.asarray(s, dtype=float)
    ref = np.asarray(tracks[reference], dtype=float)
    if ref.shape != (x.shape[0], 3):
        raise InputError(f"each track must have shape ({x.shape[0]}, 3), got {ref.shape} for {reference!r}")
    rows = thin(x.shape[0])
    out: list[Artist] = []
    peaks = []
    for name, poses in tracks.items():
        if name == reference:
            continue
        p = np.asarray(poses, dtype=float)
        if p.shape != ref.shape:
            raise InputError(f"each track must have shape {ref.shape}, got {p.shape} for {name!r}")
        d = np.hypot(p[:, 0] - ref[:, 0], p[:, 1] - ref[:, 1])
        peaks.append(float(np.nanmax(d)) if d.size else 0.0)
        (line,) = ax.plot(x[rows], d[rows], lw=1.3,
                          label=f"{name} − {reference} (final {d[-1]:.3g} m)" if d.size else name)
        out.append(line)
    positive = [p for p in peaks if p > 0]
    if len(positive) > 1 and max(positive) / min(positive) > 100:
        ax.set_yscale("log")
    ax.set_xlabel(s_label)
    ax.set_ylabel("position difference [m]")
    ax.grid(True, lw=0.4, alpha=0.5)
    legend(ax, loc="upper left")
    return out


def _sub(n: int) -> str:
    return str(n).translate(str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉"))


def nees_band(dof: int = 2, probability: float = 0.95) -> tuple[float, float]:
    """Two-sided ``probability`` range of one NEES sample, χ² with ``dof`` degrees of
    freedom: [χ²⁻¹((1 − p)/2), χ²⁻¹((1 + p)/2)] (Bar-Shalom, Li and Kirubarajan 2001, §5.4.2).

    >>> [round(v, 4) for v in nees_band(2, 0.95)]   # −2 ln(1 − q) for 2 dof
    [0.0506, 7.3778]
    """
    from scipy.stats import chi2

    tail = (1.0 - probability) / 2.0
    return float(chi2.ppf(tail, dof)), float(chi2.ppf(1.0 - tail, dof))


def draw_nees(ax: Axes, t: ArrayLike, nees: ArrayLike, *, dof: int = 2, probability: float = 0.95,
              t_label: str = "t [s]") -> list[Artist]:
    """NEES eᵀP⁻¹e of each sample over time, inside the χ² band a consistent covariance
    keeps it in, with the mean NEES and the fraction inside printed.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    t : array_like, shape (N,)
        Time [s] (or window number, distance: say so in ``t_label``).
    nees : array_like, shape (N,)
        NEES values (:func:`odomkit.evaluate.nees`); NaN rows are left out.
    dof : int
        Degrees of freedom (2 for a position, 3 for a pose).
    probability : float
        Of the band (:func:`nees_band`).

    Returns
    -------
    list of Artist
        The samples, the band and the line at the expected value ``dof``.

    Notes
    -----
    The band is for one sample. Consecutive rows of one run are correlated, so their
    fraction inside is one draw, not a statistic; window ends restarted from truth
    (``odomkit evaluate --window``) are independent samples.
    """
    x = np.asarray(t, dtype=float)
    v = np.asarray(nees, dtype=float)
    if v.shape != x.shape:
        raise InputError(f"t and nees must have the same shape, got {x.shape} and {v.shape}")
    lo, hi = nees_band(dof, probability)
    ok = np.isfinite(v)
    inside = float(np.mean((v[ok] >= lo) & (v[ok] <= hi))) if ok.any() else None
    mean = float(v[ok].mean()) if ok.any() else float("nan")
    rows = np.flatnonzero(ok)[thin(int(ok.sum()))]
    band = ax.axhspan(lo, hi, color="tab:green", alpha=0.15, lw=0,
                      label=f"{100 * probability:g} % χ²{_sub(dof)} band of one sample: "
                            f"{'n/a' if inside is None else f'{inside:.3f}'} inside")
    expected = ax.axhline(dof, color="tab:green", lw=1.0, label=f"expected value {dof}")
    style = "." if rows.size < 400 else "-"
    (line,) = ax.plot(x[rows], v[rows], style, color="tab:blue", lw=0.8, ms=4,
                      label=f"NEES (mean {mean:.3g} over {int(ok.sum())})")
    if ok.any() and np.nanmax(v[ok]) > 30 * hi:
        ax.set_yscale("log")
    ax.set_xlabel(t_label)
    ax.set_ylabel(f"NEES ({dof} dof)")
    ax.grid(True, lw=0.4, alpha=0.5)
    # Beside the axes: samples can lie at any height.
    legend(ax, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return [line, band, expected]
