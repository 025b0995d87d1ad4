"""Tracks against ground truth: endpoint errors, ATE/RPE in 2-D, drift per distance, NEES.

All functions take poses as ``(N, 3)`` arrays ``[x, y, θ]`` sampled at the same rows;
heading differences are wrapped to [−π, π).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from odomkit.errors import ModelError


def wrap(angle: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to [−π, π).

    >>> float(wrap(3 * np.pi / 2))
    -1.5707963267948966
    """
    return (np.asarray(angle, dtype=float) + np.pi) % (2 * np.pi) - np.pi


def pose_errors(estimate: ArrayLike, truth: ArrayLike) -> NDArray[np.float64]:
    """``estimate − truth`` per row, shape (N, 3), heading wrapped."""
    est = np.asarray(estimate, dtype=float)
    ref = np.asarray(truth, dtype=float)
    if est.shape != ref.shape or est.ndim != 2 or est.shape[1] != 3:
        raise ModelError(f"estimate and truth must both be (N, 3); got {est.shape} and {ref.shape}")
    err = est - ref
    err[:, 2] = wrap(err[:, 2])
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
    out[:, 2] = wrap(out[:, 2])
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
