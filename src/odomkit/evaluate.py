"""Tracks against ground truth: endpoint errors, ATE/RPE in 2-D, drift per distance, NEES.

All functions take poses as ``(N, 3)`` arrays ``[x, y, θ]`` sampled at the same rows;
heading differences are wrapped to [−π, π) (:func:`odomkit.angles.wrap_angle`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.errors import ModelError

__all__ = [
    "ellipse_points", "evaluate_track", "nees", "pose_errors", "relative_pose_errors", "TrackEvaluation",
]


def pose_errors(estimate: ArrayLike, truth: ArrayLike) -> NDArray[np.float64]:
    """``estimate − truth`` per row, shape (N, 3), heading wrapped."""
    est = validate.shape(estimate, "estimate", ("N", 3))
    ref = validate.shape(truth, "truth", (est.shape[0], 3))
    err = est - ref
    err[:, 2] = wrap_angle(err[:, 2])
    return err


def relative_pose_errors(estimate: ArrayLike, truth: ArrayLike, distance: float) -> NDArray[np.float64]:
    """RPE over windows of ``distance`` metres of true travel (evo's "delta" in metres).

    For every row i, j is the first row with true path length ≥ ``distance`` after i; the
    error is the motion i->j seen by the estimate expressed in the frame of pose i,
    minus the same for the truth. Returns (K, 3): [along, across, heading] errors.
    """
    est = np.asarray(estimate, dtype=float)
    ref = np.asarray(truth, dtype=float)
    s = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))))
    j = np.searchsorted(s, s + distance)
    i = np.flatnonzero(j < len(s))
    j = j[i]

    def local(p: NDArray[np.float64]) -> NDArray[np.float64]:
        d = p[j, :2] - p[i, :2]
        c, sn = np.cos(p[i, 2]), np.sin(p[i, 2])
        return np.column_stack((c * d[:, 0] + sn * d[:, 1], -sn * d[:, 0] + c * d[:, 1],
                                p[j, 2] - p[i, 2]))

    out = local(est) - local(ref)
    out[:, 2] = wrap_angle(out[:, 2])
    return out


def nees(errors: ArrayLike, cov: ArrayLike) -> NDArray[np.float64]:
    """Normalised estimation error squared eᵀ P⁻¹ e per row (NaN where P is singular).

    Parameters
    ----------
    errors : (N, d) errors
    cov : (N, d, d) covariances
    """
    e = np.asarray(errors, dtype=float)
    P = np.asarray(cov, dtype=float)
    out = np.full(e.shape[0], np.nan)
    ok = np.linalg.matrix_rank(P) == P.shape[-1]
    if ok.any():
        out[ok] = np.einsum("ni,ni->n", e[ok], np.linalg.solve(P[ok], e[ok][..., None])[..., 0])
    return out


@dataclass(frozen=True)
class TrackEvaluation:
    """Summary of a track against ground truth (metres, radians)."""

    final_position_error: float
    max_position_error: float
    final_heading_error: float
    ate_rmse: float
    true_path_length: float
    drift_per_distance: float
    nees_position_mean: float | None
    inside_95_fraction: float | None

    def to_dict(self) -> dict[str, float | None]:
        return dict(self.__dict__)


def evaluate_track(poses: ArrayLike, truth: ArrayLike, cov: ArrayLike | None = None) -> TrackEvaluation:
    """Compare a dead-reckoned track with its ground truth.

    ``drift_per_distance`` is the final position error over the true path length.
    With a covariance, the position NEES (2 dof) is averaged over rows with a regular
    covariance, and ``inside_95_fraction`` is the fraction of those rows whose true
    position lies inside the 95 % ellipse (χ²₂ = 5.991; a consistent model gives ≈ 0.95).
    """
    err = pose_errors(poses, truth)
    dist = np.hypot(err[:, 0], err[:, 1])
    ref = np.asarray(truth, dtype=float)
    length = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    nees_mean = inside = None
    if cov is not None:
        values = nees(err[:, :2], np.asarray(cov, dtype=float)[:, :2, :2])
        finite = values[np.isfinite(values)]
        if finite.size:
            nees_mean = float(finite.mean())
            inside = float(np.mean(finite <= chi2.ppf(0.95, 2)))
    return TrackEvaluation(
        final_position_error=float(dist[-1]),
        max_position_error=float(dist.max()),
        final_heading_error=float(err[-1, 2]),
        ate_rmse=float(np.sqrt(np.mean(dist**2))),
        true_path_length=length,
        drift_per_distance=float(dist[-1] / length) if length > 0 else float("nan"),
        nees_position_mean=nees_mean,
        inside_95_fraction=inside,
    )


def ellipse_points(cov: ArrayLike, center: ArrayLike = (0.0, 0.0), prob: float = 0.95,
                   n: int = 100) -> NDArray[np.float64]:
    """Boundary of the 2-D Gaussian region holding probability ``prob``.

    The radius in Mahalanobis units is sqrt(χ²₂(prob)) = sqrt(−2 ln(1 − prob)): 2.448 for
    95 % (5.991), not the 1-D 1.96 (see papers/README: a 1σ ellipse holds 39.3 %).

    Returns
    -------
    ndarray, shape (n, 2)

    Examples
    --------
    >>> p = ellipse_points(np.diag([4.0, 1.0]), n=4)   # semi-axes 2·2.448 and 1·2.448
    >>> sorted(np.round(np.hypot(p[:, 0], p[:, 1]), 3).tolist())
    [2.448, 2.448, 4.895, 4.895]
    """
    cov = np.asarray(cov, dtype=float)
    if cov.shape != (2, 2):
        raise ModelError(f"ellipse needs a 2x2 covariance, got shape {cov.shape}")
    if not 0 < prob < 1:
        raise ModelError(f"prob must be in (0, 1), got {prob}")
    radius = np.sqrt(-2.0 * np.log1p(-prob))  # χ²₂ quantile, closed form
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    circle = np.stack([np.cos(t), np.sin(t)], axis=1)
    return np.asarray(center, dtype=float) + radius * (circle * np.sqrt(np.clip(vals, 0, None))) @ vecs.T
