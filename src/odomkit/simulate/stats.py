"""Monte Carlo statistics of final poses against a predicted mean and covariance.

Every simulated figure comes with its Monte Carlo standard error and a z-score against
the theory, so a reader sees at once which differences are sampling noise. Standard
errors for Gaussian samples of size N (Anderson, *An Introduction to Multivariate
Statistical Analysis*, 3rd ed., sections 3.3, 4.2, 7.3):

=================  =================================================================
figure             standard error
=================  =================================================================
mean               σ/√N
std                ≈ σ/√(2(N−1))
correlation ρ      ≈ (1−ρ²)/√(N−3) (Fisher z = atanh r has SE 1/√(N−3))
covariance σ_ij    √((σ_i²σ_j² + σ_ij²)/(N−1))  (Wishart variance of S_ij)
=================  =================================================================

z-scores use the standard errors under the theory (the null hypothesis); correlations
are compared on Fisher's z scale. The consistency checks, each at level ``alpha``:

1. *mean*: N·ēᵀP⁻¹ē ~ χ²(r) (known covariance P of rank r), ē the mean error;
2. *NEES*: the mean normalised estimation error squared of the runs,
   (1/N)·Σ eᵢᵀP⁻¹eᵢ ~ χ²(rN)/N, two-sided (Bar-Shalom, Li, Kirubarajan 2001, 5.4.2);
3. *covariance*: the likelihood-ratio test of H₀: Σ = P (Anderson 2003, 10.8),
   λ = n·[tr(P⁻¹S) − ln det(P⁻¹S) − r] with n = N − 1, S the sample covariance,
   asymptotically χ²(r(r+1)/2); accepted when λ ≤ the (1 − alpha) quantile.

Verdict: ``"consistent"`` when every check passes; ``"consistent to first order: ..."``
when some check fails (with 10⁴ runs second-order effects are detectable) but the mean
bias is at most ``bias_tolerance`` predicted σ (Mahalanobis length) and every variance
ratio (eigenvalue of P⁻¹S) lies in ``variance_tolerance``; otherwise
``"linear model breaks down: ..."`` with the failed checks and effect sizes.

θ is continuous (unwrapped) in every figure (docs/reference/commands/simulate.md): the final headings
and the predicted heading must be on the same branch, as :func:`odomkit.simulate.simulate_runs`
and :func:`odomkit.propagate.predict.predict` give them, so a run that ends a full turn
away from the prediction is 2π off. Wrapping the errors to [−π, π) would fold a heading
spread of a few radians onto the circle (Chong–Kleeman Table 7: σθ = 6.25 rad read as
1.8 rad) and call an exactly linear model broken. When P is singular (e.g. no heading
noise) the checks work in the span of P; errors outside it are reported.

When P is *nearly* singular (bias noise makes a path's end errors almost collinear) a
direction that both the theory and the simulation find negligible is left out of the
three checks and named in the verdict (``checks.left_out``): see :data:`NEGLIGIBLE_SHARE`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats as sps

from odomkit import validate
from odomkit.errors import ModelError

__all__ = [
    "BIAS_TOLERANCE", "CORR_PAIRS", "NAMES", "NEGLIGIBLE_SHARE", "VARIANCE_TOLERANCE", "compare",
    "correlations"
]

NAMES = ("x", "y", "theta")
# Chong–Kleeman section 6.1 call the model adequate where the mean is off by an order of
# magnitude less than σ and the std within a few %; with 10⁴ runs smaller second-order
# effects are detectable. These tolerances separate "detectable" from "matters": a bias
# up to 0.25 σ and σ within about ±11 % in every direction.
BIAS_TOLERANCE = 0.25
VARIANCE_TOLERANCE = (0.8, 1.25)
CORR_PAIRS = (("xy", 0, 1), ("xtheta", 0, 2), ("ytheta", 1, 2))
NEGLIGIBLE_SHARE = 0.001
"""Largest share of the largest standardised variance that the theory may give a direction, and
half the share the simulation may give it, for the direction to be left out of the checks.

Why: bias noise (one constant error per run) makes a path's end errors nearly collinear, and
the predicted covariance P then has directions with almost no variance (below 1e-5 of the
largest: correlations of ±0.99999). The first-order prediction there is of the size of the
terms it neglects (second order in the heading error: relative size σθ², e.g. the mean error
−L·δθ²/2 of a heading bias δθ), so the whitened errors in such a direction measure the
nonlinearity, not the linear model: the mean NEES reads 350, and the mean and covariance
tests fail, where every axis's σ agrees to 1 %. The directions are those of the standardised
covariance (P divided by the predicted σ of each axis, so that metres and radians do not
decide); one whose predicted variance is below this share (a σ below 3 % of the largest),
and whose simulated mean square error about the prediction is below twice it (the neglected
second-order terms add there), is left out, and the verdict names it with its own NEES.
Small on purpose: at 1 %, a theory with a third of the true lateral slip passed (its
directions held 0.3–0.5 %, NEES 1.8 and 2.0 there; a review's reproducer), where a real
wheel-base-bias breakdown sits at 1e-5. A direction the simulation fills (a noise the theory
misses) stays in, so a real disagreement still fails; the per-axis σ and correlations
(``z``) still cover every direction."""


def correlations(cov: ArrayLike) -> dict[str, float]:
    """Correlation coefficients ``xy``, ``xtheta``, ``ytheta`` of a 3×3 (x, y, θ)
    covariance; NaN where a standard deviation is 0.

    Examples
    --------
    >>> correlations([[4.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    {'xy': 0.5, 'xtheta': nan, 'ytheta': nan}
    """
    cov = np.asarray(cov, dtype=float)
    sigma = np.sqrt(np.diag(cov))
    out = {}
    for name, i, j in CORR_PAIRS:
        den = sigma[i] * sigma[j]
        out[name] = float(cov[i, j] / den) if den > 0 else math.nan
    return out


def _z(diff: float, se: float) -> float:
    if math.isnan(se) or math.isnan(diff):
        return math.nan
    if se > 0:
        return diff / se
    return 0.0 if diff == 0 else math.copysign(math.inf, diff)


def _span(cov: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Whitening W (r, 3) with W·P·Wᵀ = I on the span of P, and the null-space basis."""
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    tol = 1e-12 * max(float(np.max(np.abs(w))), 1e-300)
    keep = w > tol
    return (v[:, keep] / np.sqrt(w[keep])).T, v[:, ~keep]


def compare(
    final: ArrayLike,
    pose: ArrayLike,
    cov: ArrayLike,
    alpha: float = 0.01,
    bias_tolerance: float = BIAS_TOLERANCE,
    variance_tolerance: tuple[float, float] = VARIANCE_TOLERANCE,
) -> dict[str, Any]:
    """Statistics of the simulated final poses against the predicted pose and covariance.

    Parameters
    ----------
    final : array_like, shape (N, 3)
        Simulated final poses [m, m, rad], θ continuous.
    pose : array_like, shape (3,)
        Predicted (nominal) final pose, θ continuous on the same branch as ``final``.
    cov : array_like, shape (3, 3)
        Predicted covariance.
    alpha : float
        Level of each consistency check.
    bias_tolerance : float
        Largest mean bias, in predicted standard deviations (Mahalanobis length), that
        still counts as consistent to first order.
    variance_tolerance : (float, float)
        Range of the variance ratios (eigenvalues of P⁻¹S) that still counts as
        consistent to first order.

    Returns
    -------
    dict
        ``simulation`` {mean, mean_error, cov, std, corr, se: {mean, std, corr, cov}},
        ``z`` {mean, std, corr, cov}, ``checks`` {mean, nees, cov, effect, ...} with
        statistic, bounds or p-value and ``ok``; ``verdict`` (str); ``consistent``
        (every statistical check passed); ``linear_model_ok`` (also true when the
        deviations are detectable but within the tolerances).

    Examples
    --------
    Gaussian samples drawn from the predicted covariance are consistent:

    >>> rng = np.random.default_rng(0)
    >>> cov = np.diag([1e-4, 4e-4, 1e-2])
    >>> s = compare(rng.multivariate_normal([1, 2, 3], cov, 5000), [1, 2, 3], cov)
    >>> s["verdict"]
    'consistent'
    """
    final = validate.shape(final, "final poses", ("N", 3))
    pose = validate.pose(pose, "predicted pose")
    cov_p = np.asarray(cov, dtype=float).reshape(3, 3)  # may hold NaN: an undefined variance
    n = final.shape[0]
    if n < 4:
        raise ModelError(f"need at least 4 runs of shape (N, 3), got {final.shape}")
    err = final - pose  # θ continuous: no wrapping (see the module docstring)
    mean_err = err.mean(axis=0)
    cov_s = np.cov(err, rowvar=False)
    sigma_s = np.sqrt(np.diag(cov_s))
    sigma_p = np.sqrt(np.clip(np.diag(cov_p), 0.0, None))  # NaN stays NaN
    corr_s, corr_p = correlations(cov_s), correlations(cov_p)

    se_mean = sigma_s / math.sqrt(n)
    se_std = sigma_s / math.sqrt(2.0 * (n - 1))
    se_corr = {k: (1.0 - r * r) / math.sqrt(n - 3) for k, r in corr_s.items()}
    se_cov = np.sqrt((np.outer(sigma_s**2, sigma_s**2) + cov_s**2) / (n - 1))
    # under the null hypothesis (the theory is right)
    se0_mean = sigma_p / math.sqrt(n)
    se0_std = sigma_p / math.sqrt(2.0 * (n - 1))
    se0_cov = np.sqrt((np.outer(sigma_p**2, sigma_p**2) + cov_p**2) / (n - 1))
    z_corr = {}
    for k, r in corr_s.items():
        rho = corr_p[k]
        if math.isnan(r) or math.isnan(rho):
            z_corr[k] = math.nan
        else:
            clip = 1.0 - 1e-15  # |r| = 1 would make Fisher's z infinite
            fisher_r = math.atanh(max(-clip, min(clip, r)))
            fisher_rho = math.atanh(max(-clip, min(clip, rho)))
            z_corr[k] = (fisher_r - fisher_rho) * math.sqrt(n - 3)
    z = {
        "mean": [_z(float(mean_err[i]), float(se0_mean[i])) for i in range(3)],
        "std": [_z(float(sigma_s[i] - sigma_p[i]), float(se0_std[i])) for i in range(3)],
        "corr": z_corr,
        "cov": [[_z(float(cov_s[i, j] - cov_p[i, j]), float(se0_cov[i, j])) for j in range(3)]
                for i in range(3)],
    }
    # a component the theory leaves undefined (NaN, e.g. the compass model's θ) is left
    # out of the checks
    known = np.flatnonzero(np.isfinite(np.diag(cov_p)))
    sub = np.ix_(known, known)
    left = _negligible(err[:, known], cov_p[sub])
    if left is None:
        checks = _checks(err[:, known], mean_err[known], cov_s[sub], cov_p[sub], alpha)
    else:
        kept, basis, report = left
        e_k = err[:, known] @ kept  # the errors in the kept directions
        checks = _checks(e_k, mean_err[known] @ kept, kept.T @ cov_s[sub] @ kept,
                         kept.T @ cov_p[sub] @ kept, alpha)
        checks["left_out"] = [{**d, "direction": dict(zip((NAMES[i] for i in known), col.tolist(),
                                                          strict=True))}
                              for d, col in zip(report, basis.T, strict=True)]
    checks["components"] = [NAMES[i] for i in known]
    mean = pose + mean_err
    result: dict[str, Any] = {
        "simulation": {
            "mean": mean, "mean_error": mean_err, "cov": cov_s, "std": sigma_s,
            "corr": corr_s,
            "se": {"mean": se_mean, "std": se_std, "corr": se_corr, "cov": se_cov},
        },
        "z": z,
        "checks": checks,
        "alpha": alpha,
    }
    checks["effect"] = _effect(checks, bias_tolerance, variance_tolerance)
    result["verdict"], result["consistent"], result["linear_model_ok"] = _verdict(checks, z)
    return result


def _negligible(err: NDArray[np.float64], cov_p: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], list[dict[str, float]]] | None:
    """The directions to leave out of the checks (:data:`NEGLIGIBLE_SHARE`), or None.

    Returns (kept, left, report): ``kept`` (c, r') maps an error (c,) onto the r' kept
    directions, ``left`` (c, q) holds the left-out directions as the coefficients of the
    standardised error combination Σ_i u_i e_i/σ_i each measures, and ``report`` one dict
    per left-out direction: ``predicted_share`` (its predicted variance) and
    ``simulated_share`` (the runs' mean square error about the prediction) of the largest
    standardised variance, and ``nees``, the runs' mean squared whitened error there
    (their ratio).
    """
    sigma = np.sqrt(np.clip(np.diag(cov_p), 0.0, None))
    if sigma.size < 2 or not np.any(sigma > 0):
        return None
    # Standardise by the predicted σ of each axis (an axis of zero variance is left as it
    # is: its direction stays null and the span check still sees it).
    scale = np.where(sigma > 0, sigma, 1.0)
    cov_std = cov_p / np.outer(scale, scale)
    mu, vec = np.linalg.eigh(0.5 * (cov_std + cov_std.T))
    top = float(mu.max())
    e_std = err / scale
    square = np.mean((e_std @ vec) ** 2, axis=0)  # mean square about the prediction
    floor = NEGLIGIBLE_SHARE * top
    # 1e-12: the span's own tolerance (_span): an exactly null direction stays in the
    # checks, where an error in it is reported as outside the span.
    left = (mu > 1e-12 * top) & (mu < floor) & (square < 2 * floor)
    if not left.any():
        return None
    kept = vec[:, ~left] / scale[:, None]
    report = [{"predicted_share": float(mu[k] / top), "simulated_share": float(square[k] / top),
               "nees": float(square[k] / mu[k])} for k in np.flatnonzero(left)]
    return kept, vec[:, left], report


def _checks(err: NDArray[np.float64], mean_err: NDArray[np.float64], cov_s: NDArray[np.float64],
            cov_p: NDArray[np.float64], alpha: float) -> dict[str, Any]:
    n = err.shape[0]
    whiten, null = _span(cov_p)
    r = whiten.shape[0]
    checks: dict[str, Any] = {"rank": r, "n": n}
    # errors where the theory says there are none
    outside = float(np.max(np.abs(err @ null))) if null.shape[1] else 0.0
    checks["outside_span"] = {"max_abs": outside, "ok": outside <= 1e-9}
    if r == 0:
        return checks
    e_w = err @ whiten.T  # (N, r), identity covariance under H0
    m_w = mean_err @ whiten.T
    stat_mean = float(n * m_w @ m_w)
    checks["mean"] = {"statistic": stat_mean, "dof": r,
                      "p_value": float(sps.chi2.sf(stat_mean, r)),
                      "ok": bool(sps.chi2.sf(stat_mean, r) >= alpha)}
    nees = float(np.mean(np.sum(e_w**2, axis=1)))
    lo = float(sps.chi2.ppf(alpha / 2, r * n) / n)
    hi = float(sps.chi2.ppf(1 - alpha / 2, r * n) / n)
    checks["nees"] = {"mean": nees, "expected": float(r), "bounds": [lo, hi],
                      "ok": bool(lo <= nees <= hi)}
    s_w = whiten @ cov_s @ whiten.T  # P⁻¹S in the span, similar to a symmetric matrix
    eig = np.linalg.eigvalsh(0.5 * (s_w + s_w.T))
    if np.min(eig) <= 0:
        stat_cov = math.inf
    else:
        # Anderson (2003) 10.8: −2 log LR for H0: Σ = Σ0 with the mean unknown
        stat_cov = float((n - 1) * (np.sum(eig) - np.sum(np.log(eig)) - r))
    dof = r * (r + 1) // 2
    checks["cov"] = {"statistic": stat_cov, "dof": dof,
                     "critical": float(sps.chi2.ppf(1 - alpha, dof)),
                     "p_value": float(sps.chi2.sf(stat_cov, dof)),
                     "variance_ratios": eig.tolist(),
                     "ok": bool(stat_cov <= sps.chi2.ppf(1 - alpha, dof))}
    return checks


def _worst(z: dict[str, Any]) -> str:
    items = [(f"mean {NAMES[i]}", z["mean"][i]) for i in range(3)]
    items += [(f"std {NAMES[i]}", z["std"][i]) for i in range(3)]
    items += [(f"corr {k}", v) for k, v in z["corr"].items()]
    items = [(k, v) for k, v in items if not math.isnan(v)]
    items.sort(key=lambda kv: -abs(kv[1]))
    return ", ".join(f"{k} z={v:+.1f}" for k, v in items[:3] if abs(v) > 3)


def _effect(checks: dict[str, Any], bias_tolerance: float,
            variance_tolerance: tuple[float, float]) -> dict[str, Any]:
    if "cov" not in checks:
        return {"ok": checks["outside_span"]["ok"]}
    bias = math.sqrt(checks["mean"]["statistic"] / checks["n"])
    ratios = checks["cov"]["variance_ratios"]
    lo, hi = variance_tolerance
    return {"bias_sigma": bias, "bias_tolerance": bias_tolerance,
            "variance_ratio_range": [min(ratios), max(ratios)],
            "variance_tolerance": [lo, hi],
            "ok": bool(checks["outside_span"]["ok"] and bias <= bias_tolerance
                       and lo <= min(ratios) and max(ratios) <= hi)}


def _left_out_note(checks: dict[str, Any]) -> str:
    """What the verdict says of the directions left out of the checks ("" for none)."""
    left = checks.get("left_out")
    if not left:
        return ""
    many = len(left) > 1
    nees = ", ".join(f"{d['nees']:.3g}" for d in left)
    return (f"left out {len(left)} direction{'s' if many else ''} with under "
            f"{NEGLIGIBLE_SHARE:.1%} of the largest standardised variance in theory (and "
            f"under {2 * NEGLIGIBLE_SHARE:.1%} in the simulation): too small to hold a "
            f"first-order theory to, whose neglected second-order terms are of that size "
            f"(NEES there {nees}; see checks.left_out)")


def _verdict(checks: dict[str, Any], z: dict[str, Any]) -> tuple[str, bool, bool]:
    """(verdict, every check passed, deviations within the tolerances)."""
    failed = []
    if not checks["outside_span"]["ok"]:
        failed.append("errors outside the span of the predicted covariance")
    if "mean" in checks and not checks["mean"]["ok"]:
        failed.append(f"mean biased (p={checks['mean']['p_value']:.2g})")
    if "nees" in checks and not checks["nees"]["ok"]:
        lo, hi = checks["nees"]["bounds"]
        failed.append(f"mean NEES {checks['nees']['mean']:.3g} outside [{lo:.3g}, {hi:.3g}]")
    if "cov" in checks and not checks["cov"]["ok"]:
        failed.append(f"covariance rejected (LR {checks['cov']['statistic']:.3g} > "
                      f"{checks['cov']['critical']:.3g})")
    note = _left_out_note(checks)
    if not failed:
        return ("consistent" + (f" ({note})" if note else "")), True, True
    effect = checks["effect"]
    size = ""
    if "bias_sigma" in effect:
        lo, hi = effect["variance_ratio_range"]
        size = f"; bias {effect['bias_sigma']:.2g} σ, variance ratios {lo:.3g}–{hi:.3g}"
    worst = _worst(z)
    detail = "; ".join(failed) + size + (f"; largest |z|: {worst}" if worst else "") + (
        f"; {note}" if note else "")
    if effect["ok"]:
        tol_lo, tol_hi = effect["variance_tolerance"]
        return (f"consistent to first order: {detail} (detectable second-order effects, "
                f"within the tolerances {effect['bias_tolerance']:g} σ and "
                f"{tol_lo:g}–{tol_hi:g})"), False, True
    return "linear model breaks down: " + detail, False, False
