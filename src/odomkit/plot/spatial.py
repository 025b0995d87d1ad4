"""Figures in the plane: a track with its confidence ellipses, Monte Carlo end points with
the predicted ellipse, and UMBmark's return errors.

Every ``draw_*`` function draws on a matplotlib Axes it is given and returns the artists
it added; inputs are numpy arrays in SI units (metres, radians). The ellipse of
probability p is :func:`odomkit.evaluate.ellipse_points`: the 2-D region eᵀP⁻¹e ≤ χ²₂(p),
χ²₂(p) = −2 ln(1 − p) (5.991 for 95 %, not the 1-D 1.96²).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.angles import wrap_angle
from odomkit.errors import InputError
from odomkit.evaluate import coverage, ellipse_points
from odomkit.plot.figure import new_figure, save_figure, thin

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

    from odomkit.calibrate.noise_fit import WheelNoiseFit
    from odomkit.track import Track

__all__ = ["draw_monte_carlo", "draw_track", "draw_umbmark", "legend", "plot_noise_fit", "plot_tracks"]

_UNITS = ("m", "m", "rad")
_NAMES = ("x", "y", "θ")


def _chi2_2dof(probability: float) -> float:
    """χ²₂ quantile, closed form −2 ln(1 − p)."""
    if not 0 < probability < 1:
        raise InputError(f"the probability must be in (0, 1), got {probability!r}")
    return float(-2.0 * np.log1p(-probability))


def _pct(probability: float) -> str:
    return f"{100 * probability:g} %"


def legend(ax: Axes, **kwargs: Any) -> None:
    """The legend of ``ax`` with each label once (several tracks may each draw "ground
    truth"), small type, half-transparent frame; ``kwargs`` go to ``ax.legend``."""
    handles, labels = ax.get_legend_handles_labels()
    seen: dict[str, Artist] = {}
    for h, lab in zip(handles, labels, strict=True):
        seen.setdefault(lab, h)
    if seen:
        options: dict[str, Any] = {"fontsize": "small", "framealpha": 0.8, "loc": "best"}
        options.update(kwargs)
        ax.legend(list(seen.values()), list(seen), **options)


def _ellipse_rows(xy: NDArray[np.float64], count: int) -> NDArray[np.intp]:
    """Rows evenly spaced along the travelled path (the last row included), so a robot
    that stands still does not pile its ellipses up."""
    if count <= 0 or xy.shape[0] < 2:
        return np.zeros(0, dtype=np.intp)
    step = np.hypot(*np.diff(xy, axis=0).T)
    s = np.concatenate(([0.0], np.cumsum(np.where(np.isfinite(step), step, 0.0))))
    if s[-1] > 0:
        rows = np.searchsorted(s, np.linspace(0.0, s[-1], count + 1)[1:])
    else:
        rows = np.linspace(0, xy.shape[0] - 1, count + 1).round().astype(np.intp)[1:]
    return np.unique(np.clip(rows, 0, xy.shape[0] - 1))


def _closed(points: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.vstack([points, points[:1]])


def draw_track(
    ax: Axes,
    poses: ArrayLike,
    cov: ArrayLike | None = None,
    *,
    truth: ArrayLike | None = None,
    probability: float = 0.95,
    n_ellipses: int = 12,
    label: str = "odometry",
    color: str | None = None,
    truth_label: str = "ground truth",
    ellipse_scale: float = 1.0,
    truth_points: bool = False,
) -> list[Artist]:
    """A dead-reckoned track with position confidence ellipses, against ground truth.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    poses : array_like, shape (N, 3)
        [x, y, θ] [m, m, rad].
    cov : array_like, shape (N, 3, 3), optional
        Pose covariances [m², m·rad, rad²]; the x–y block of ``n_ellipses`` poses evenly
        spaced along the path (the last one included) is drawn as the ellipse holding
        ``probability``, scaled by the χ²₂ quantile.
    truth : array_like, shape (M, 2) or (M, 3), optional
        True positions [m] (NaN rows break the line).
    probability : float
        Of each ellipse, printed in the legend with its χ²₂ quantile.
    n_ellipses : int
    label : str
        Legend entry of the track.
    color : str, optional
        Of the track and its ellipses (default: the next colour of the axes' cycle).
    truth_label : str
    ellipse_scale : float
        Draw the ellipses this many times larger (said in the legend); 1 draws them true
        to scale.
    truth_points : bool
        Draw the truth as separate points (sparse fixes such as GPS, each its own
        measurement) rather than a line.

    Returns
    -------
    list of Artist
        The track line, the truth line and the ellipses, in that order.

    Examples
    --------
    >>> from odomkit.plot import new_figure
    >>> fig, (ax,) = new_figure()
    >>> poses = np.column_stack([np.linspace(0, 2, 50), np.zeros(50), np.zeros(50)])
    >>> cov = np.linspace(0, 1e-3, 50)[:, None, None] * np.eye(3)
    >>> len(draw_track(ax, poses, cov, n_ellipses=4))   # the track and 4 ellipses
    5
    >>> ax.get_legend().get_texts()[1].get_text()
    '95 % confidence ellipses (χ²₂ = 5.99)'
    """
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"poses must have shape (N, 3), got {p.shape}")
    q = _chi2_2dof(probability)
    rows = thin(p.shape[0])
    (line,) = ax.plot(p[rows, 0], p[rows, 1], "-", color=color, lw=1.4, label=label)
    artists: list[Artist] = [line]
    colour = line.get_color()
    if truth is not None:
        g = np.asarray(truth, dtype=float)
        if g.ndim != 2 or g.shape[1] not in (2, 3):
            raise InputError(f"truth must have shape (M, 2) or (M, 3), got {g.shape}")
        keep = thin(g.shape[0])
        if truth_points:
            (tl,) = ax.plot(g[keep, 0], g[keep, 1], ".", ls="none", color="black", ms=3.0, alpha=0.6,
                            label=truth_label)
        else:
            (tl,) = ax.plot(g[keep, 0], g[keep, 1], "--", color="black", lw=1.0, alpha=0.7,
                            label=truth_label)
        artists.append(tl)
    if cov is not None:
        P = np.asarray(cov, dtype=float)
        if P.shape != (p.shape[0], 3, 3):
            raise InputError(f"cov must have shape ({p.shape[0]}, 3, 3), got {P.shape}")
        text = f"{_pct(probability)} confidence ellipses (χ²₂ = {q:.2f})"
        if ellipse_scale != 1.0:
            text += f", drawn ×{ellipse_scale:g}"
        for i in _ellipse_rows(p[:, :2], n_ellipses):
            block = P[i, :2, :2]
            if not np.all(np.isfinite(block)) or not np.any(block):
                continue
            pts = ellipse_points(ellipse_scale**2 * block, p[i, :2], probability, 72)
            (el,) = ax.plot(*_closed(pts).T, "-", color=colour, lw=0.9, label=text)
            text = "_nolegend_"
            artists.append(el)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.4, alpha=0.5)
    legend(ax)
    return artists


def draw_monte_carlo(
    ax: Axes,
    endpoints: ArrayLike,
    mean: ArrayLike,
    cov: ArrayLike,
    *,
    probability: float = 0.95,
    components: tuple[int, int] = (0, 1),
    max_points: int = 5000,
) -> list[Artist]:
    """Monte Carlo end poses with the predicted ellipse, and the fraction inside it.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    endpoints : array_like, shape (M, 2) or (M, 3)
        The runs' end poses [m, m, rad].
    mean : array_like, shape (2,) or (3,)
        The predicted end pose.
    cov : array_like, shape (2, 2) or (3, 3)
        Its predicted covariance.
    probability : float
        Of the ellipse; the legend prints it and the fraction of *all* M runs inside
        (:func:`odomkit.evaluate.coverage`; a consistent prediction gives about
        ``probability``).
    components : (int, int)
        Which two of x, y, θ (0, 1, 2) to show; a heading difference is wrapped.
    max_points : int
        At most this many end points are drawn (the first ones; runs are independent).

    Returns
    -------
    list of Artist
        The points, the predicted mean and the ellipse.
    """
    e = np.asarray(endpoints, dtype=float)
    m = np.asarray(mean, dtype=float)
    P = np.asarray(cov, dtype=float)
    if e.ndim != 2 or e.shape[1] not in (2, 3) or m.shape != (e.shape[1],) or P.shape != (e.shape[1],) * 2:
        raise InputError(f"endpoints (M, k), mean (k,) and cov (k, k) with k = 2 or 3 must match, got "
                         f"{e.shape}, {m.shape}, {P.shape}")
    a, b = components
    sub = P[np.ix_([a, b], [a, b])]
    d = e[:, [a, b]] - m[[a, b]]
    for col, comp in enumerate((a, b)):
        if comp == 2:
            d[:, col] = wrap_angle(d[:, col])
    inside = coverage(d, np.broadcast_to(sub, (d.shape[0], 2, 2)), (probability,))[f"{probability:g}"]
    shown = d[:max_points] + m[[a, b]]
    what = f"{e.shape[0]} runs" if e.shape[0] <= max_points else f"{max_points} of {e.shape[0]} runs"
    pts = ax.scatter(shown[:, 0], shown[:, 1], s=5, alpha=0.35, color="tab:blue", linewidths=0,
                     label=f"end poses ({what})", rasterized=e.shape[0] > 2000)
    (centre,) = ax.plot(m[a], m[b], "+", color="black", ms=12, mew=1.6, label="predicted mean")
    if np.all(np.isfinite(sub)):
        ring = _closed(ellipse_points(sub, m[[a, b]], probability, 144))
    else:  # the prediction leaves this plane undefined
        ring, inside = np.full((1, 2), np.nan), None
    text = (f"predicted {_pct(probability)} ellipse: {inside:.3f} of runs inside" if inside is not None
            else f"predicted {_pct(probability)} ellipse: none (singular or undefined covariance)")
    (el,) = ax.plot(*ring.T, "-", color="tab:red", lw=1.6, label=text)
    ax.set_xlabel(f"{_NAMES[a]} [{_UNITS[a]}]")
    ax.set_ylabel(f"{_NAMES[b]} [{_UNITS[b]}]")
    if a < 2 and b < 2:
        ax.set_aspect("equal", adjustable="datalim")
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(5))  # long tick labels of a small spread far from 0
    ax.grid(True, lw=0.4, alpha=0.5)
    # Above the axes: a cloud of points leaves no free corner for it.
    legend(ax, loc="lower center", bbox_to_anchor=(0.5, 1.01), borderaxespad=0.0)
    return [pts, centre, el]


def draw_umbmark(
    ax: Axes,
    cw: ArrayLike,
    ccw: ArrayLike,
    *,
    cw_after: ArrayLike | None = None,
    ccw_after: ArrayLike | None = None,
) -> list[Artist]:
    """UMBmark's return position errors: each run, each direction's centre of gravity and
    E_max,syst, before and (optionally) after calibration (Borenstein–Feng 1996, Fig. 6
    and Fig. 11). Drawn in millimetres.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    cw, ccw : array_like, shape (n, 2) and (m, 2)
        Return position errors (ε_x, ε_y) [m] of the clockwise and counter-clockwise runs
        (Borenstein–Feng eq. 3.1), at least one run each.
    cw_after, ccw_after : array_like, optional
        The same runs after calibration (both or neither).

    Returns
    -------
    list of Artist
        Runs, centres of gravity and the E_max,syst circle of each set drawn.

    Notes
    -----
    The centres of gravity are eq. (3.2), their distances eq. (3.3) and E_max,syst
    eq. (3.4), by :func:`odomkit.calibrate.umbmark.e_max_syst`; the dashed circle about
    the origin has radius E_max,syst, so the worse centre lies on it.
    """
    from odomkit.calibrate.umbmark import e_max_syst

    if (cw_after is None) != (ccw_after is None):
        raise InputError("give both cw_after and ccw_after, or neither")
    sets = [("before", cw, ccw, False)]
    if cw_after is not None and ccw_after is not None:
        sets = [("before calibration", cw, ccw, False), ("after calibration", cw_after, ccw_after, True)]
    artists: list[Artist] = []
    t = np.linspace(0, 2 * np.pi, 181)
    for name, a, b, filled in sets:
        e_max = e_max_syst(a, b)  # validates both: (n, 2), finite, a run each
        lines = []
        for errors, marker, colour, direction in ((a, "s", "tab:red", "CW"), (b, "o", "tab:blue", "CCW")):
            mm = 1000.0 * np.asarray(errors, dtype=float)
            cg = mm.mean(axis=0)  # Borenstein–Feng eq. (3.2)
            face = colour if filled else "none"
            (runs,) = ax.plot(mm[:, 0], mm[:, 1], marker, ls="none", mfc=face, mec=colour, ms=6,
                              label=f"{direction} runs, {name}")
            (centre,) = ax.plot(*cg, marker="X", ls="none", color=colour, mec="black", ms=11,
                                alpha=1.0 if filled or len(sets) == 1 else 0.6,
                                label=f"{direction} centre of gravity, {name}")
            lines += [runs, centre]
        (circle,) = ax.plot(1000 * e_max * np.cos(t), 1000 * e_max * np.sin(t), ":" if filled else "--",
                            color="0.3", lw=1.0, label=f"E_max,syst = {1000 * e_max:.2f} mm, {name}")
        artists += lines + [circle]
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel("return error ε_x [mm]")
    ax.set_ylabel("return error ε_y [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.4, alpha=0.5)
    legend(ax, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return artists


def plot_tracks(
    tracks: Sequence[tuple[str, Track, NDArray[np.float64] | None]],
    path: str | Path,
    ellipses: int = 12,
) -> Path:
    """Dead-reckoned tracks (with 95 % position ellipses when a track has a covariance)
    and their ground truth, in one x–y figure saved to ``path`` (:func:`draw_track`).

    Parameters
    ----------
    tracks : sequence of (label, Track, truth (N, 3) or None)
    path : .png, .svg or .pdf file
    ellipses : ellipses per track
    """
    fig, axes = new_figure(size=(9.0, 6.0))
    ax = axes[0] if isinstance(axes, list) else next(iter(axes.values()))
    for label, track, truth in tracks:
        draw_track(ax, track.poses, track.cov, truth=truth, n_ellipses=ellipses, label=f"{label} odometry")
    legend(ax, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.set_title("Dead reckoning with 95 % position ellipses")
    return save_figure(fig, path)


def plot_noise_fit(fit: WheelNoiseFit, path: str | Path) -> Path:
    """Chong–Kleeman Fig. 4 style: the runs' end errors against each other, with the
    empirical (solid) and fitted k_L, k_R (dashed) 95 % ellipses (χ²₂ = 5.991); saved to
    ``path`` (.png, .svg or .pdf)."""
    comps = list(fit.components)
    pairs = [(a, b) for i, a in enumerate(comps) for b in comps[i + 1:]]
    fig, axes = new_figure(1, max(len(pairs), 1), size=(4.4 * max(len(pairs), 1), 4.0))
    assert isinstance(axes, list)
    unit = {"x": "m", "y": "m", "theta": "rad"}
    symbol = {"x": "x", "y": "y", "theta": "θ"}
    if not pairs:  # one component: the errors along a line, with the 1-D 95 % ranges
        ax, name = axes[0], comps[0]
        if fit.errors is not None:
            ax.plot(fit.errors[:, 0], np.arange(1, fit.errors.shape[0] + 1), ".", color="0.3", label="runs")
        for cov, style, text in ((fit.cov_empirical, "-", "empirical"),
                                 (fit.cov_fitted, "--", "fitted k_L, k_R")):
            half = 1.959964 * float(np.sqrt(max(cov[0, 0], 0.0)))
            for sign in (-1.0, 1.0):
                ax.axvline(fit.mean[0] + sign * half, ls=style, color="C0" if style == "-" else "C1",
                           label=f"{text} 95 % range")
        ax.set_xlabel(f"end error in {symbol[name]} [{unit[name]}]")
        ax.set_ylabel("run")
    for ax, (a, b) in zip(axes, pairs, strict=False):
        i, j = comps.index(a), comps.index(b)
        if fit.errors is not None:
            ax.plot(fit.errors[:, i], fit.errors[:, j], ".", color="0.3", label="runs")
        emp = fit.ellipse((a, b), 0.95, empirical=True)
        fitted = fit.ellipse((a, b), 0.95)
        ax.plot(*_closed(emp).T, "-", label="empirical 95 %")
        ax.plot(*_closed(fitted).T, "--", label="fitted k_L, k_R, 95 %")
        ax.set_xlabel(f"end error in {symbol[a]} [{unit[a]}]")
        ax.set_ylabel(f"end error in {symbol[b]} [{unit[b]}]")
        if unit[a] == unit[b] == "m":
            ax.set_aspect("equal", adjustable="datalim")
    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
    legend(axes[0])
    fig.suptitle(f"k_L = {fit.k_left:.3g}, k_R = {fit.k_right:.3g} m^1/2 ({fit.n_runs} runs)")
    return save_figure(fig, path)
