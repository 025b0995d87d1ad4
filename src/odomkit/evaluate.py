"""Tracks against ground truth: alignment, ATE/RPE in 2-D, drift, NEES and ellipse coverage.

All functions take poses as ``(N, 3)`` arrays ``[x, y, θ]`` sampled at the same rows;
heading differences are wrapped to [−π, π) (:func:`odomkit.angles.wrap_angle`).

Alignment (:func:`align_track`): ``none``; ``start`` (the estimate moved rigidly so that its
first pose is the truth's, evo's ``--align_origin``); ``se2`` (the rigid motion that
minimises the squared position errors, Umeyama 1991 without scale, evo's ``--align``).
ATE is the RMS position error after alignment; RPE (:func:`relative_pose_errors`) is the
error of the motion over a given true travel, which no rigid alignment changes. The
consistency of a covariance is scored by the position NEES eᵀP⁻¹e (2 dof) and by the
fraction of poses inside the predicted ellipse of each probability (:func:`coverage`), and,
where the truth has heading, by the heading NEES e_θ²/σθ² (1 dof, :func:`heading_nees`) and
the fraction of headings inside the interval of each probability (:func:`heading_coverage`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.errors import ModelError

__all__ = [
    "ALIGNMENTS", "align_track", "COVERAGE_LEVELS", "coverage", "coverage_range", "coverage_verdicts",
    "ellipse_points", "evaluate_track", "heading_coverage", "heading_nees", "heading_nees_summary",
    "NEAR_SINGULAR", "nees", "nees_bounds", "nees_summary", "nees_verdict", "NO_ERROR",
    "overall_verdict", "pose_errors", "relative_pose_errors", "rpe_pairs", "singular_nees_note",
    "TrackEvaluation", "umeyama_se2", "VERDICTS",
]

ALIGNMENTS = ("none", "start", "se2")
#: Probabilities of the position ellipses whose coverage is reported.
COVERAGE_LEVELS = (0.5, 0.9, 0.95, 0.99)


def pose_errors(estimate: ArrayLike, truth: ArrayLike) -> NDArray[np.float64]:
    """``estimate − truth`` per row, shape (N, 3), heading wrapped.

    The opposite sign of the window-end errors of :func:`odomkit.window_errors.window_errors`
    and ``odomkit evaluate``'s ``window_ends`` (truth − odometry)."""
    est = validate.shape(estimate, "estimate", ("N", 3))
    ref = validate.shape(truth, "truth", (est.shape[0], 3))
    err = est - ref
    err[:, 2] = wrap_angle(err[:, 2])
    return err


def rpe_pairs(truth_xy: ArrayLike, distance: float, pairs: str = "consecutive"
              ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Row pairs (i, j) that are ``distance`` metres of true travel apart.

    ``pairs="consecutive"`` is evo's default (``filters.filter_pairs_by_path``): starting at
    row 0, the next row is the first whose path from the previous one reaches ``distance``,
    and each pair joins two successive such rows (non-overlapping). ``pairs="all"`` starts a
    pair at every row i, ending at the first row j whose path from i reaches ``distance``
    (overlapping pairs: more of them, but correlated).

    Parameters
    ----------
    truth_xy : array_like, shape (N, 2)
        True positions [m]; the path is the sum of the straight steps between them.
    distance : float
        Travel between the two rows of a pair [m].
    pairs : {"consecutive", "all"}

    Returns
    -------
    i, j : ndarray of int, shape (K,)

    Examples
    --------
    >>> xy = np.column_stack((np.arange(6.0), np.zeros(6)))
    >>> [a.tolist() for a in rpe_pairs(xy, 2.0)]
    [[0, 2], [2, 4]]
    """
    distance = validate.positive(distance, "RPE distance", unit="m")
    xy = np.asarray(truth_xy, dtype=float)[:, :2]
    s = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))))
    if pairs == "all":
        j = np.searchsorted(s, s + distance)
        i = np.flatnonzero(j < len(s))
        return i, j[i]
    if pairs != "consecutive":
        raise ModelError(f"pairs must be 'consecutive' or 'all', got {pairs!r}")
    ids = [0]
    while True:
        nxt = int(np.searchsorted(s, s[ids[-1]] + distance))
        if nxt >= len(s):
            break
        ids.append(max(nxt, ids[-1] + 1))
    rows = np.asarray(ids, dtype=np.intp)
    return rows[:-1], rows[1:]


def relative_pose_errors(estimate: ArrayLike, truth: ArrayLike, distance: float,
                         pairs: str = "all") -> NDArray[np.float64]:
    """RPE over ``distance`` metres of true travel (evo's "delta" in metres).

    For each pair of rows (i, j) from :func:`rpe_pairs` the error is the motion i->j seen
    by the estimate expressed in the frame of its pose i, minus the same for the truth.
    Its position part has the norm of the translation of evo's (Q_i⁻¹Q_j)⁻¹(P_i⁻¹P_j)
    (a rotation does not change a norm), so the RMS of the position norms with
    ``pairs="consecutive"`` is ``evo_rpe --delta D --delta_unit m --pairs_from_reference``.
    Returns (K, 3): [along, across, heading] errors.
    """
    est = np.asarray(estimate, dtype=float)
    ref = np.asarray(truth, dtype=float)
    i, j = rpe_pairs(ref[:, :2], distance, pairs)

    def local(p: NDArray[np.float64]) -> NDArray[np.float64]:
        d = p[j, :2] - p[i, :2]
        c, sn = np.cos(p[i, 2]), np.sin(p[i, 2])
        return np.column_stack((c * d[:, 0] + sn * d[:, 1], -sn * d[:, 0] + c * d[:, 1],
                                p[j, 2] - p[i, 2]))

    out = local(est) - local(ref)
    out[:, 2] = wrap_angle(out[:, 2])
    return out


def umeyama_se2(source: ArrayLike, target: ArrayLike) -> tuple[float, NDArray[np.float64]]:
    """The rotation φ and translation t minimising Σ |target_k − (R(φ) source_k + t)|².

    Umeyama, "Least-squares estimation of transformation parameters between two point
    patterns", IEEE PAMI 13(4), 1991, in 2-D and without scale (c = 1).

    Parameters
    ----------
    source, target : array_like, shape (N, 2)
        Matching points [m]: the estimate's positions and the truth's.

    Returns
    -------
    phi : float
        Rotation [rad].
    t : ndarray, shape (2,)
        Translation [m].

    Examples
    --------
    >>> src = np.array([[0.0, 0], [1, 0], [1, 2]])
    >>> c, s = np.cos(0.3), np.sin(0.3)
    >>> phi, t = umeyama_se2(src, src @ np.array([[c, -s], [s, c]]).T + [1.0, -2.0])
    >>> round(phi, 12), np.round(t, 12).tolist()
    (0.3, [1.0, -2.0])
    """
    x = validate.shape(source, "source points", ("N", 2))
    y = validate.shape(target, "target points", (x.shape[0], 2))
    if x.shape[0] < 2:
        raise ModelError("SE(2) alignment needs at least 2 points")
    mu_x, mu_y = x.mean(axis=0), y.mean(axis=0)  # eqs. (34), (35)
    sigma_xy = (y - mu_y).T @ (x - mu_x) / x.shape[0]  # eq. (38)
    u, d, vt = np.linalg.svd(sigma_xy)  # between eqs. (38) and (39)
    if d[0] <= np.finfo(float).eps * max(1.0, float(np.abs(sigma_xy).max())):
        raise ModelError("SE(2) alignment is undetermined: the points do not spread (no motion)")
    S = np.eye(2)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:  # eq. (43): a rotation, never a reflection
        S[1, 1] = -1.0
    R = u @ S @ vt  # eq. (40)
    t = mu_y - R @ mu_x  # eq. (41) with c = 1
    return float(np.arctan2(R[1, 0], R[0, 0])), t


def align_track(
    poses: ArrayLike, truth: ArrayLike, mode: str = "none", cov: ArrayLike | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """The track moved rigidly onto the truth, and its covariance rotated alike.

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        The estimate [m, m, rad].
    truth : array_like, shape (N, 3)
        The truth at the same rows; θ may be NaN (position-only truth).
    mode : {"none", "start", "se2"}
        ``start``: the first pose onto the truth's first pose (translation only when the
        truth has no heading there); ``se2``: :func:`umeyama_se2` on all positions.
    cov : array_like, shape (N, 3, 3), optional
        The estimate's covariance; a rotation φ turns it into J P Jᵀ with
        J = diag(R(φ), 1).

    Returns
    -------
    poses : ndarray, shape (N, 3)
    cov : ndarray, shape (N, 3, 3) or None
    """
    est = validate.shape(poses, "poses", ("N", 3))
    ref = validate.shape(truth, "truth", (est.shape[0], 3))
    if mode not in ALIGNMENTS:
        raise ModelError(f"alignment must be one of {', '.join(ALIGNMENTS)}, got {mode!r}")
    P = None if cov is None else np.asarray(cov, dtype=float)
    if mode == "none" or est.shape[0] == 0:
        return est.copy(), None if P is None else P.copy()
    if mode == "se2":
        phi, t = umeyama_se2(est[:, :2], ref[:, :2])
    else:
        phi = float(ref[0, 2] - est[0, 2]) if np.isfinite(ref[0, 2]) else 0.0
        c0, s0 = np.cos(phi), np.sin(phi)
        t = ref[0, :2] - np.array([[c0, -s0], [s0, c0]]) @ est[0, :2]
    c, s = np.cos(phi), np.sin(phi)
    R = np.array([[c, -s], [s, c]])
    out = np.column_stack((est[:, :2] @ R.T + t, est[:, 2] + phi))
    if P is not None:
        J = np.eye(3)
        J[:2, :2] = R
        P = J @ P @ J.T
    return out, P


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


#: A scored covariance whose smallest eigenvalue is below this fraction of its largest
#: (standard deviations 1000× apart) is nearly singular (:func:`singular_nees_note`).
NEAR_SINGULAR = 1e-6
#: A position error [m] below this counts as none (a track started at the truth pose it is
#: compared with), so a singular covariance there loses nothing.
NO_ERROR = 1e-9


def singular_nees_note(errors: ArrayLike, cov: ArrayLike) -> str | None:
    """One line on scored rows whose covariance is singular or nearly so, where they
    matter, else None: the warning of ``odomkit evaluate`` and :func:`evaluate_track` alike.

    A singular covariance has no NEES (:func:`nees` leaves the row out of the NEES and
    coverage): none is lost where the error is zero too (below :data:`NO_ERROR`: a track
    compared with the truth pose it started from), but a nonzero error's NEES would be
    infinite, and those rows are counted. A nearly singular one (:data:`NEAR_SINGULAR`) is
    kept: its NEES is well defined and true, but where the covariance comes from a pose
    known exactly (a track started at a truth pose with zero covariance) the error is mostly
    the truth's own noise, which the covariance lacks, and a few such rows make the whole
    mean; they are counted where they make more than half of the NEES summed over the rows.

    Parameters
    ----------
    errors : array_like, shape (n, 2)
        Position errors [m].
    cov : array_like, shape (n, 2, 2)
        Their covariances [m²].

    Examples
    --------
    >>> cov = np.array([np.diag([1e-2, 1e-12]), np.diag([1e-2, 1e-2])])
    >>> singular_nees_note(np.array([[0.0, 1e-3], [0.0, 1e-3]]), cov)[:47]
    '100 % of the summed NEES comes from 1 of 2 rows'
    """
    e = np.asarray(errors, dtype=float)
    P = np.asarray(cov, dtype=float)
    if P.shape[0] == 0:
        return None
    values = nees(e, P)
    singular = ~np.isfinite(values)
    lam = np.linalg.eigvalsh(P)  # ascending, per row
    near = ~singular & (lam[:, 0] < NEAR_SINGULAR * lam[:, 1])
    off = singular & (np.hypot(e[:, 0], e[:, 1]) > NO_ERROR)
    total = float(np.sum(values[~singular]))
    share = float(np.sum(values[near])) / total if total > 0 else 0.0
    parts = []
    if off.any():
        parts.append(f"{int(off.sum())} of {values.size} rows have a singular covariance but an error (an "
                     "infinite NEES) and are left out of the NEES and coverage")
    if share > 0.5:
        parts.append(f"{100 * share:.4g} % of the summed NEES comes from {int(near.sum())} of {values.size} "
                     "rows whose covariance is nearly singular (standard deviations over 1000x apart)")
    if not parts:
        return None
    return ("; ".join(parts) + ", as at the start of a track started from a truth pose with zero "
            "covariance: the truth's own noise alone falls far outside their ellipse, so their NEES "
            "judges the truth, not the covariance; give the truth's noise with --truth-sigma, or start "
            "the track with --initial-cov")


def _chi2_2dof(p: float) -> float:
    """Quantile of χ² with 2 dof, closed form: −2 ln(1 − p)."""
    return float(-2.0 * np.log1p(-p))


def nees_bounds(n: int, dof: int = 2, prob: float = 0.95) -> tuple[float, float]:
    """Two-sided ``prob`` bounds of the mean NEES of ``n`` independent samples of ``dof`` dof.

    n times the mean is χ² with n·dof degrees of freedom (Bar-Shalom, Li, Kirubarajan,
    "Estimation with Applications to Tracking and Navigation", 2001, §5.4.2), so the bounds
    are χ²⁻¹((1 ∓ prob)/2; n·dof)/n.

    Examples
    --------
    >>> [round(b, 4) for b in nees_bounds(50, 2)]
    [1.4844, 2.5912]
    """
    from scipy.special import gammaincinv  # scipy.stats costs 1.5 s of start-up, special 0.5 s

    n = validate.positive_int(n, "number of NEES samples")
    tail = (1.0 - prob) / 2.0
    # χ²_k quantile: 2·P⁻¹(k/2, p), P the regularised lower incomplete gamma function.
    lo, hi = (2.0 * gammaincinv(n * dof / 2.0, q) / n for q in (tail, 1.0 - tail))
    return float(lo), float(hi)


def nees_summary(errors: ArrayLike, covs: ArrayLike) -> dict[str, object]:
    """Mean and median NEES with the 95 % χ² bounds of the mean (rows with a singular
    covariance left out).

    Parameters
    ----------
    errors : array_like, shape (n, k)
    covs : array_like, shape (n, k, k)

    Returns
    -------
    dict with ``mean``, ``median`` (None without a usable row), ``bounds`` [lo, hi]
    (:func:`nees_bounds` with k dof, None without a usable row) and ``count``, the rows used.
    """
    e = np.asarray(errors, dtype=float)
    return _summary(nees(e, covs), e.shape[1])


def _summary(values: NDArray[np.float64], dof: int) -> dict[str, object]:
    """:func:`nees_summary`'s dict of NEES ``values`` (n,) of ``dof`` dof, non-finite left out."""
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"mean": None, "median": None, "bounds": None, "count": 0}
    return {"mean": float(values.mean()), "median": float(np.median(values)),
            "bounds": list(nees_bounds(values.size, dof)), "count": int(values.size)}


def heading_nees(errors: ArrayLike, variances: ArrayLike) -> NDArray[np.float64]:
    """The heading NEES e_θ²/σθ² per row (1 dof), e_θ wrapped to [−π, π).

    NaN where the error is NaN (truth without heading) or the variance is not positive
    and finite (no claim to score, as :func:`nees` leaves a singular covariance out).

    Parameters
    ----------
    errors : array_like, shape (n,)
        Heading errors [rad].
    variances : array_like, shape (n,)
        Their predicted variances σθ² [rad²].

    Examples
    --------
    >>> heading_nees([0.2, 2 * np.pi + 0.2, 0.1, np.nan], [0.01, 0.04, 0.0, 1.0]).round(12).tolist()
    [4.0, 1.0, nan, nan]
    """
    e = wrap_angle(np.asarray(errors, dtype=float).reshape(-1))
    v = validate.shape(variances, "heading variances", (e.size,))
    out = np.full(e.size, np.nan)
    ok = np.isfinite(e) & np.isfinite(v) & (v > 0)
    out[ok] = e[ok] ** 2 / v[ok]
    return out


def heading_nees_summary(errors: ArrayLike, variances: ArrayLike) -> dict[str, object]:
    """:func:`nees_summary` of the heading: mean and median of :func:`heading_nees` and the
    95 % χ² bounds of the mean with 1 dof (:func:`nees_bounds`), over the rows that have one.

    Parameters
    ----------
    errors : array_like, shape (n,)
        Heading errors [rad] (NaN where the truth has none).
    variances : array_like, shape (n,)
        Their predicted variances [rad²].
    """
    return _summary(heading_nees(errors, variances), 1)


def _chi2_1dof(p: float) -> float:
    """Quantile of χ² with 1 dof: the square of the standard normal's (1 + p)/2 point."""
    from statistics import NormalDist  # the standard library's: no scipy at start-up

    return float(NormalDist().inv_cdf((1.0 + p) / 2.0) ** 2)


def heading_coverage(errors: ArrayLike, variances: ArrayLike,
                     levels: tuple[float, ...] = COVERAGE_LEVELS) -> dict[str, float | None]:
    """Fraction of heading errors inside the predicted interval of each probability.

    The interval holding probability p of a 1-D Gaussian is |e_θ| ≤ z σθ with z the
    standard normal's (1 + p)/2 point (1.96 for 95 %), i.e. e_θ²/σθ² ≤ χ²₁(p). Rows without
    a heading NEES (:func:`heading_nees`: no truth heading, no positive variance) are left
    out, as :func:`coverage` leaves out a singular covariance.

    Parameters
    ----------
    errors : array_like, shape (n,)
        Heading errors [rad], wrapped here.
    variances : array_like, shape (n,)
        Their predicted variances [rad²].
    levels : probabilities in (0, 1)

    Returns
    -------
    dict mapping each level written with ``{:g}`` to a fraction, or to None when no row has
    a heading NEES.

    Examples
    --------
    >>> heading_coverage([0.5, 1.0, 3.0], [1.0, 1.0, 1.0], (0.5, 0.95))  # z 0.674, 1.96
    {'0.5': 0.3333333333333333, '0.95': 0.6666666666666666}
    """
    return _inside(heading_nees(errors, variances), levels, _chi2_1dof)


def coverage(errors_xy: ArrayLike, cov_xy: ArrayLike,
             levels: tuple[float, ...] = COVERAGE_LEVELS) -> dict[str, float | None]:
    """Fraction of errors inside the predicted position ellipse of each probability.

    The ellipse holding probability p of a 2-D Gaussian is eᵀP⁻¹e ≤ χ²₂(p) = −2 ln(1 − p).
    A consistent covariance gives coverage ≈ p at every level, when the errors are
    independent samples. Rows with a singular covariance are left out.

    Parameters
    ----------
    errors_xy : array_like, shape (n, 2)
        Position errors [m].
    cov_xy : array_like, shape (n, 2, 2)
        Their predicted covariances [m²].
    levels : probabilities in (0, 1)

    Returns
    -------
    dict mapping each level written with ``{:g}`` ("0.5", "0.9", ...) to a fraction, or to
    None when no row has a regular covariance.

    Examples
    --------
    >>> coverage([[0.5, 0.0], [3.0, 0.0]], np.broadcast_to(np.eye(2), (2, 2, 2)), (0.5, 0.99))
    {'0.5': 0.5, '0.99': 1.0}
    """
    return _inside(nees(validate.shape(errors_xy, "errors", ("n", 2)), cov_xy), levels, _chi2_2dof)


def _inside(values: NDArray[np.float64], levels: tuple[float, ...],
            quantile: Callable[[float], float]) -> dict[str, float | None]:
    """The fraction of the finite NEES ``values`` (n,) at or under ``quantile(p)`` (the χ²
    quantile of their dof) for each level p, keyed ``{:g}``; None where no value is finite."""
    values = values[np.isfinite(values)]
    out: dict[str, float | None] = {}
    for p in levels:
        if not 0 < p < 1:
            raise ModelError(f"coverage levels must be in (0, 1), got {p}")
        out[f"{p:g}"] = float(np.mean(values <= quantile(p))) if values.size else None
    return out


#: The verdicts of a covariance against its independent samples: ``optimistic`` (too small:
#: too few samples inside, NEES too large), ``consistent`` (inside the range an honest
#: covariance's figure falls in), ``pessimistic`` (too large); :func:`overall_verdict` adds
#: ``mixed`` for coverage that is optimistic at some levels and pessimistic at others.
VERDICTS = ("optimistic", "consistent", "pessimistic", "mixed")


def coverage_range(n: int, level: float, prob: float = 0.95) -> tuple[float, float]:
    """Where an honest covariance's coverage at ``level`` falls over ``n`` independent samples.

    The count of samples inside the ``level`` ellipse is Binomial(n, level), so the range is
    its (1 − prob)/2 and (1 + prob)/2 points over n: a consistent covariance's figure falls
    inside it with probability at least ``prob`` (the count is discrete, so a little more).

    Parameters
    ----------
    n : number of independent samples (window ends), ≥ 1
    level : the ellipse's probability, in (0, 1)
    prob : the probability the range holds

    Returns
    -------
    (low, high) fractions in [0, 1].

    Examples
    --------
    >>> coverage_range(6, 0.95)  # 4 to 6 of 6 ends inside
    (0.6666666666666666, 1.0)
    """
    from scipy.special import bdtr  # scipy.stats costs 1.5 s of start-up

    n = validate.positive_int(n, "number of coverage samples")
    if not 0 < level < 1 or not 0 < prob < 1:
        raise ModelError(f"coverage level and probability must be in (0, 1), got {level}, {prob}")
    cdf = bdtr(np.arange(n + 1), n, level)  # P(count ≤ k)
    tail = (1.0 - prob) / 2.0
    # The smallest k with P(count ≤ k) ≥ q: the binomial quantile (scipy.stats.binom.ppf).
    low, high = (int(np.searchsorted(cdf, q, side="left")) for q in (tail, 1.0 - tail))
    return min(low, n) / n, min(high, n) / n


def coverage_verdicts(fractions: dict[str, float | None], n: int, prob: float = 0.95
                      ) -> dict[str, str | None]:
    """Each level's coverage (:func:`coverage`'s dict) against :func:`coverage_range`.

    Parameters
    ----------
    fractions : {level text ("0.95"): fraction or None}
    n : the independent samples they were counted over (None verdicts when 0)
    prob : the probability each range holds

    Returns
    -------
    {level text: "optimistic" (below its range: the covariance too small), "pessimistic"
    (above: too large), "consistent", or None where the fraction is None}.

    Examples
    --------
    >>> coverage_verdicts({"0.5": 0.57, "0.95": 0.78}, 37)
    {'0.5': 'consistent', '0.95': 'optimistic'}
    """
    out: dict[str, str | None] = {}
    for level, value in fractions.items():
        if value is None or n < 1:
            out[level] = None
            continue
        low, high = coverage_range(n, float(level), prob)
        out[level] = "optimistic" if value < low else "pessimistic" if value > high else "consistent"
    return out


def overall_verdict(verdicts: dict[str, str | None]) -> str | None:
    """One word for the levels' verdicts (:func:`coverage_verdicts`): ``optimistic`` or
    ``pessimistic`` when some levels are and none the other way, ``mixed`` when both (heavy
    tails: the core of the errors narrower than predicted and their tails wider, which no
    scaling of the covariance mends), ``consistent`` when none is, None without any."""
    given = {v for v in verdicts.values() if v is not None}
    if not given:
        return None
    if {"optimistic", "pessimistic"} <= given:
        return "mixed"
    return ("optimistic" if "optimistic" in given else "pessimistic" if "pessimistic" in given
            else "consistent")


def nees_verdict(mean: float | None, bounds: tuple[float, float] | list[float] | None) -> str | None:
    """The mean NEES against its bounds (:func:`nees_bounds`): ``optimistic`` above them,
    ``pessimistic`` below, else ``consistent``; None without a mean."""
    if mean is None or bounds is None:
        return None
    low, high = bounds
    return "optimistic" if mean > high else "pessimistic" if mean < low else "consistent"


@dataclass(frozen=True)
class TrackEvaluation:
    """Summary of a track against ground truth (metres, radians), ``odomkit track --json``'s
    ``ground_truth``.

    Errors are estimate − truth (:func:`pose_errors`). ``nees_position_mean`` is the mean
    over the track's rows (one run's correlated rows), not the mean over window ends
    restarted from truth that ``odomkit evaluate --robot``
    (:func:`odomkit.workflows.evaluate.evaluate_logs`) reports under the same key: on one
    OptiOdom run, 246.9 over its rows against 17.96 at its one whole-run window end.
    """

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


def evaluate_track(poses: ArrayLike, truth: ArrayLike, cov: ArrayLike | None = None, *,
                   note_nees: bool = True) -> TrackEvaluation:
    """Compare a dead-reckoned track with its ground truth.

    ``drift_per_distance`` is the final position error over the true path length.
    With a covariance, the position NEES (2 dof) is averaged over rows with a regular
    covariance, and ``inside_95_fraction`` is the fraction of those rows whose true
    position lies inside the 95 % ellipse (χ²₂ = 5.991; a consistent model gives ≈ 0.95).
    Errors are estimate − truth; ``nees_position_mean`` is over the rows, not over the
    window ends of ``odomkit evaluate --robot`` (:class:`TrackEvaluation`).

    Where rows of a singular or nearly singular covariance make the NEES (a track started at
    the truth pose with zero covariance, scored against a truth with noise of its own), a
    UserWarning says so (:func:`singular_nees_note`, as ``odomkit evaluate`` warns), unless
    ``note_nees`` is False (a caller that shows no NEES: ``odomkit track``'s text).
    """
    err = pose_errors(poses, truth)
    dist = np.hypot(err[:, 0], err[:, 1])
    ref = np.asarray(truth, dtype=float)
    length = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    nees_mean = inside = None
    P = None if cov is None else np.asarray(cov, dtype=float)[:, :2, :2]
    if P is not None:
        values = nees(err[:, :2], P)
        finite = values[np.isfinite(values)]
        if finite.size:
            nees_mean = float(finite.mean())
            inside = float(np.mean(finite <= _chi2_2dof(0.95)))
    ate = float(np.sqrt(np.mean(dist**2)))
    # Errors that overflow (inf ATE) are the caller's error to report, not a note before it.
    note = (None if P is None or not note_nees or not np.isfinite(ate)
            else singular_nees_note(err[:, :2], P))
    if note:
        warnings.warn(note, stacklevel=2)
    return TrackEvaluation(
        final_position_error=float(dist[-1]),
        max_position_error=float(dist.max()),
        final_heading_error=float(err[-1, 2]),
        ate_rmse=ate,
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
