"""Figures (matplotlib is an optional extra, imported here only)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from odomkit.evaluate import ellipse_points
from odomkit.track import Track

if TYPE_CHECKING:
    from odomkit.calibrate.noise_fit import WheelNoiseFit

__all__ = ["have_matplotlib", "plot_noise_fit", "plot_tracks"]


def have_matplotlib() -> bool:
    """Whether the optional ``plot`` extra is installed."""
    import importlib.util

    return importlib.util.find_spec("matplotlib") is not None


def plot_tracks(
    tracks: Sequence[tuple[str, Track, NDArray[np.float64] | None]],
    path: str | Path,
    ellipses: int = 12,
) -> Path:
    """Plot dead-reckoned tracks (with 95 % position ellipses when the track has a
    covariance) and their ground truth; save to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6))
    for label, track, truth in tracks:
        line, = ax.plot(track.poses[:, 0], track.poses[:, 1], label=f"{label} odometry")
        if truth is not None:
            ax.plot(truth[:, 0], truth[:, 1], "--", color=line.get_color(), alpha=0.6,
                    label=f"{label} ground truth")
        if track.cov is not None:
            for i in np.linspace(0, len(track.poses) - 1, ellipses).astype(int)[1:]:
                e = ellipse_points(track.cov[i, :2, :2], track.poses[i, :2], 0.95, 72)
                ax.plot(e[:, 0], e[:, 1], color=line.get_color(), lw=0.8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.set_title("Dead reckoning with 95 % position ellipses (χ²₂ = 5.99)")
    # Outside the axes, so it never hides a track.
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def plot_noise_fit(fit: WheelNoiseFit, path: str | Path) -> Path:
    """Chong–Kleeman Fig. 4 style: the runs' end errors against each other, with the
    empirical (solid) and fitted k_L, k_R (dashed) 95 % ellipses (χ²₂ = 5.991)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    comps = list(fit.components)
    pairs = [(a, b) for i, a in enumerate(comps) for b in comps[i + 1:]]
    fig, axes = plt.subplots(1, len(pairs), figsize=(4.2 * len(pairs), 4), squeeze=False)
    unit = {"x": "m", "y": "m", "theta": "rad"}
    for ax, (a, b) in zip(axes[0], pairs, strict=True):
        i, j = comps.index(a), comps.index(b)
        if fit.errors is not None:
            ax.plot(fit.errors[:, i], fit.errors[:, j], ".", color="0.3", label="runs")
        emp = fit.ellipse((a, b), 0.95, empirical=True)
        fitted = fit.ellipse((a, b), 0.95)
        ax.plot(*np.vstack([emp, emp[:1]]).T, "-", label="empirical 95 %")
        ax.plot(*np.vstack([fitted, fitted[:1]]).T, "--", label="fitted k_L, k_R, 95 %")
        ax.set_xlabel(f"e_{a} [{unit[a]}]")
        ax.set_ylabel(f"e_{b} [{unit[b]}]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"k_L = {fit.k_left:.3g}, k_R = {fit.k_right:.3g} m^1/2 ({fit.n_runs} runs)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
