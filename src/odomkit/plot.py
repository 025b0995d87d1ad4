"""Figures (matplotlib is an optional extra, imported here only)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from odomkit.track import Track

#: Chi-square quantile with 2 degrees of freedom for a 95 % ellipse. A "1σ ellipse" in
#: two dimensions holds only 39.3 % (not 68.3 %), see the papers README.
CHI2_2DOF_95 = 5.991464547107979


def covariance_ellipse(mean: NDArray[np.float64], cov2: NDArray[np.float64],
                       chi2: float = CHI2_2DOF_95, points: int = 72) -> NDArray[np.float64]:
    """Points (points, 2) of the ellipse {p : (p−m)ᵀ C⁻¹ (p−m) = chi2}.

    >>> e = covariance_ellipse(np.zeros(2), np.eye(2), chi2=1.0, points=4)
    >>> np.allclose(np.hypot(e[:, 0], e[:, 1]), 1.0)
    True
    """
    vals, vecs = np.linalg.eigh(0.5 * (cov2 + cov2.T))
    angles = np.linspace(0.0, 2.0 * np.pi, points, endpoint=False)
    unit = np.column_stack((np.cos(angles), np.sin(angles)))
    return mean + (unit * np.sqrt(np.clip(vals, 0.0, None) * chi2)) @ vecs.T


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

    fig, ax = plt.subplots(figsize=(7, 6))
    for label, track, truth in tracks:
        line, = ax.plot(track.poses[:, 0], track.poses[:, 1], label=f"{label} odometry")
        if truth is not None:
            ax.plot(truth[:, 0], truth[:, 1], "--", color=line.get_color(), alpha=0.6,
                    label=f"{label} ground truth")
        if track.cov is not None:
            for i in np.linspace(0, len(track.poses) - 1, ellipses).astype(int)[1:]:
                e = covariance_ellipse(track.poses[i, :2], track.cov[i, :2, :2])
                ax.plot(e[:, 0], e[:, 1], color=line.get_color(), lw=0.8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.set_title("Dead reckoning with 95 % position ellipses (χ²₂ = 5.99)")
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
