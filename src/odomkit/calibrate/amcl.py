"""nav2 AMCL's odometry motion models, and their α parameters fitted to data by maximum
likelihood (``odomkit fit-amcl``).

AMCL moves its particles between filter updates with a sampled version of the odometry
increment. An update is taken when the odometry has moved more than ``update_min_d`` in
x or in y (each in the odom frame) or turned more than ``update_min_a`` since the last
one (nav2 ``amcl_node.cpp``, ``shouldUpdateFilter``: ``|Δx| > d || |Δy| > d || |Δθ| > a``).

**Differential model** (nav2 ``differential_motion_model.cpp``; Thrun, Burgard, Fox,
*Probabilistic Robotics*, table 5.6, ``sample_motion_model_odometry``). The increment is
split into a turn, a straight move and a turn:
rot1 = atan2(Δy, Δx) − θ₀ (taken as 0 when the move is shorter than
:data:`BEARING_MIN_TRANS` = 0.01 m), trans = √(Δx² + Δy²), rot2 = Δθ − rot1, all
angles wrapped. Backward motion is treated like forward motion: the noise uses
r̃ = min(|rot|, |rot − π|) (wrapped) instead of |rot|. Each particle draws

======  ============================================================
part    variance of its Gaussian error (nav2 draws σ = √ of this)
======  ============================================================
rot1    α1·r̃1² + α2·trans²
trans   α3·trans² + α4·(r̃1² + r̃2²)
rot2    α1·r̃2² + α2·trans²
======  ============================================================

so α1 [rad²/rad²] and α3 [m²/m²] are dimensionless, α2 is rad²/m² and α4 m²/rad²: the
α's multiply *squared* motions and give *variances* (nav2 takes the square root before
sampling). The true increment is the odometry's minus the errors.

**Omni model** (nav2 ``omni_motion_model.cpp``): trans = √(Δx² + Δy²), rot = Δθ (not
folded), the direction of travel relative to the start heading is kept, and a strafe
perpendicular to it is added:

======  ==========================
part    variance
======  ==========================
trans   α3·trans² + α4·rot²
rot     α1·rot² + α2·trans²
strafe  α4·rot² + α5·trans²
======  ==========================

**The fit.** For each update, the truth's increment is decomposed the same way, on the
branch nearest the odometry's (a true move backwards gives trans < 0 rather than a
bearing off by π), and the residual e = odometry − truth is Gaussian with covariance
C = diag(A α) + T: A holds the squared motions above (from the *odometry*, as AMCL
computes them), T the truth's own noise (``truth_sigma`` per axis at both ends of the
update; the bearing of a move of length t then has variance 2σ²/t²). A move shorter than
0.01 m has no bearing in nav2, so there only the heading change (variance of rot1 plus
rot2) and the move along the start heading are compared. The updates are taken as
independent, and α ≥ 0 maximises Σ −½(log det C + eᵀC⁻¹e) (L-BFGS-B from a
non-negative least-squares start). Intervals are profile-likelihood intervals: every α
whose profile deviance is below χ²₁(level) (3.84 for 95 %); an α the data cannot bound
gets an open upper end and a warning.

Odometry with systematic errors (uncalibrated wheels) shows as large α's: AMCL's model
has no bias, so the fit spreads a bias into noise. Calibrate first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.errors import InputError, ModelError

__all__ = [
    "ALPHA_NAMES", "AMCL_MODELS", "AmclData", "AmclFit", "AmclModel", "BEARING_MIN_TRANS", "amcl_data",
    "amcl_update_rows", "diff_motion", "fit_amcl", "log_likelihood", "NAV2_UPDATE_MIN_A", "NAV2_UPDATE_MIN_D",
]

AmclModel = Literal["diff", "omni"]
AMCL_MODELS: tuple[str, ...] = ("diff", "omni")
ALPHA_NAMES: dict[str, tuple[str, ...]] = {
    "diff": ("alpha1", "alpha2", "alpha3", "alpha4"),
    "omni": ("alpha1", "alpha2", "alpha3", "alpha4", "alpha5"),
}
#: nav2's defaults of ``update_min_d`` [m] and ``update_min_a`` [rad].
NAV2_UPDATE_MIN_D = 0.25
NAV2_UPDATE_MIN_A = 0.2
#: Below this move [m] nav2's differential model takes no bearing (rot1 = 0).
BEARING_MIN_TRANS = 0.01
# A variance floor [rad² or m²] so that an exactly repeated increment (simulated data) keeps
# a finite likelihood; far below any sensor's noise.
_VARIANCE_FLOOR = 1e-14


def _poses(values: ArrayLike, name: str) -> NDArray[np.float64]:
    return validate.finite_array(values, name, ("n", 3), error=InputError)


def amcl_update_rows(poses: ArrayLike, update_min_d: float = NAV2_UPDATE_MIN_D,
                     update_min_a: float = NAV2_UPDATE_MIN_A) -> NDArray[np.intp]:
    """The rows of an odometry track at which AMCL updates its filter.

    Row 0 initialises the filter; each later row is an update when, since the last
    update, |Δx| > ``update_min_d`` or |Δy| > ``update_min_d`` (odom frame) or the wrapped
    |Δθ| > ``update_min_a`` (nav2 ``amcl_node.cpp``). AMCL tests this at each laser scan;
    here every odometry row stands for a scan.

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        Odometry poses [m, m, rad].
    update_min_d : float
        [m], > 0.
    update_min_a : float
        [rad], > 0.

    Returns
    -------
    ndarray of int, shape (U + 1,)
        Row 0 and the U update rows, increasing.

    Examples
    --------
    >>> x = np.linspace(0.0, 1.0, 11)
    >>> amcl_update_rows(np.column_stack((x, 0 * x, 0 * x)), 0.25, 0.2).tolist()
    [0, 3, 6, 9]
    """
    p = _poses(poses, "odometry poses")
    d = validate.positive(update_min_d, "update_min_d", unit="m", error=InputError)
    a = validate.positive(update_min_a, "update_min_a", unit="rad", error=InputError)
    rows = [0]
    x0, y0, t0 = p[0]
    xs, ys, ts = p[:, 0].tolist(), p[:, 1].tolist(), p[:, 2].tolist()
    for i in range(1, len(xs)):
        turn = math.remainder(ts[i] - t0, 2 * math.pi)  # nearest-angle difference
        if abs(xs[i] - x0) > d or abs(ys[i] - y0) > d or abs(turn) > a:
            rows.append(i)
            x0, y0, t0 = xs[i], ys[i], ts[i]
    return np.asarray(rows, dtype=np.intp)


def _fold(rot: NDArray[np.float64]) -> NDArray[np.float64]:
    """nav2's symmetric treatment of backward motion: min(|rot|, |rot − π|), wrapped."""
    return np.minimum(np.abs(wrap_angle(rot)), np.abs(wrap_angle(rot - np.pi)))


def diff_motion(start: ArrayLike, end: ArrayLike) -> tuple[NDArray[np.float64], ...]:
    """nav2's rot1–trans–rot2 split of odometry increments (differential model).

    Parameters
    ----------
    start, end : array_like, shape (n, 3)
        Odometry poses at the start and end of each update [m, m, rad].

    Returns
    -------
    rot1, trans, rot2 : ndarray, shape (n,)
        [rad], [m] (≥ 0), [rad]; rot1 = 0 below :data:`BEARING_MIN_TRANS`.

    Examples
    --------
    Half a metre straight backwards: rot1 = π, rot2 = −π, and the folded rot1 (the noise
    AMCL applies) is 0.

    >>> r1, t, r2 = diff_motion([[0.0, 0.0, 0.0]], [[-0.5, 0.0, 0.0]])
    >>> float(abs(r1[0])), float(t[0]), float(_fold(r1)[0])
    (3.141592653589793, 0.5, 0.0)
    """
    p0, p1 = np.atleast_2d(np.asarray(start, dtype=float)), np.atleast_2d(np.asarray(end, dtype=float))
    dx, dy = p1[:, 0] - p0[:, 0], p1[:, 1] - p0[:, 1]
    trans = np.hypot(dx, dy)
    rot1 = np.where(trans < BEARING_MIN_TRANS, 0.0, wrap_angle(np.arctan2(dy, dx) - p0[:, 2]))
    rot2 = wrap_angle(wrap_angle(p1[:, 2] - p0[:, 2]) - rot1)
    return rot1, trans, rot2


@dataclass(frozen=True)
class AmclData:
    """The residuals of AMCL updates and their variance design (see :func:`amcl_data`).

    Parameters
    ----------
    model : {"diff", "omni"}
    residual : ndarray, shape (n, 3)
        Odometry minus truth per update: diff (rot1 [rad], trans [m], rot2 [rad]), or for
        a move shorter than 0.01 m (heading change [rad], move along the heading [m], 0);
        omni (trans [m], strafe [m], rot [rad]).
    design : ndarray, shape (n, 3, K)
        Variance of residual component j = design[:, j] @ α (K = 4 diff, 5 omni).
    known : ndarray, shape (n, 3, 3)
        Covariance the α's do not explain (the truth's noise; 1 on an unused component).
    """

    model: str
    residual: NDArray[np.float64]
    design: NDArray[np.float64]
    known: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.residual.shape[0])

    @cached_property
    def diagonal(self) -> bool:
        """Whether every ``known`` matrix is diagonal (the likelihood then separates)."""
        off = self.known.copy()
        idx = np.arange(3)
        off[:, idx, idx] = 0.0
        return not bool(np.any(off))

    @cached_property
    def blocks(self) -> bool:
        """Whether component 1 is uncorrelated with 0 and 2 in every ``known`` matrix (the
        covariance is then a scalar and a 2×2 block)."""
        k = self.known
        return not bool(np.any(k[:, 0, 1]) or np.any(k[:, 1, 0]) or np.any(k[:, 1, 2]) or np.any(k[:, 2, 1]))

    @staticmethod
    def concatenate(parts: Sequence[AmclData]) -> AmclData:
        """One data set from several (e.g. one per log); all of one model."""
        models = {p.model for p in parts}
        if len(models) != 1:
            raise ModelError(f"cannot pool AMCL data of models {sorted(models)}")
        return AmclData(models.pop(), np.concatenate([p.residual for p in parts]),
                        np.concatenate([p.design for p in parts]), np.concatenate([p.known for p in parts]))


def amcl_data(odom_start: ArrayLike, odom_end: ArrayLike, truth_start: ArrayLike, truth_end: ArrayLike,
              model: str = "diff", truth_sigma: float = 0.0) -> AmclData:
    """Residuals of the truth's increments against AMCL's motion model of the odometry's.

    Parameters
    ----------
    odom_start, odom_end : array_like, shape (n, 3)
        Odometry poses at the start and end of each update [m, m, rad].
    truth_start, truth_end : array_like, shape (n, 3)
        True poses at the same times (any fixed frame; θ continuous or wrapped).
    model : {"diff", "omni"}
    truth_sigma : float
        Standard deviation of each truth position per axis [m].

    Returns
    -------
    AmclData
    """
    if model not in AMCL_MODELS:
        raise InputError(f"the AMCL model must be one of {', '.join(AMCL_MODELS)}, got {model!r}")
    o0, o1 = _poses(odom_start, "odometry start poses"), _poses(odom_end, "odometry end poses")
    g0, g1 = _poses(truth_start, "truth start poses"), _poses(truth_end, "truth end poses")
    n = o0.shape[0]
    if not (o1.shape[0] == g0.shape[0] == g1.shape[0] == n):
        raise InputError("the odometry and truth poses must have one row per update each")
    var_truth = 2.0 * validate.non_negative(truth_sigma, "truth_sigma", unit="m", error=InputError) ** 2
    if model == "diff":
        return _diff_data(o0, o1, g0, g1, var_truth)
    return _omni_data(o0, o1, g0, g1, var_truth)


def _diff_data(o0: NDArray[np.float64], o1: NDArray[np.float64], g0: NDArray[np.float64],
               g1: NDArray[np.float64], var_truth: float) -> AmclData:
    n = o0.shape[0]
    rot1, trans, rot2 = diff_motion(o0, o1)
    f1, f2 = _fold(rot1), _fold(rot2)
    t2 = trans**2
    # The truth on the branch nearest the odometry's: bearing b with +t, or b + π with −t.
    gd = g1[:, :2] - g0[:, :2]
    g_len = np.hypot(gd[:, 0], gd[:, 1])
    bearing = wrap_angle(np.arctan2(gd[:, 1], gd[:, 0]) - g0[:, 2])
    flip = np.abs(wrap_angle(bearing - rot1)) > 0.5 * np.pi
    g_rot1 = np.where(flip, wrap_angle(bearing + np.pi), bearing)
    g_trans = np.where(flip, -g_len, g_len)
    g_turn = g1[:, 2] - g0[:, 2]
    short = trans < BEARING_MIN_TRANS
    residual = np.empty((n, 3))
    design = np.zeros((n, 3, 4))
    known = np.zeros((n, 3, 3))
    # Full updates: Probabilistic Robotics table 5.6 in nav2's variance form.
    residual[:, 0] = wrap_angle(rot1 - g_rot1)
    residual[:, 1] = trans - g_trans
    residual[:, 2] = wrap_angle(rot2 - (g_turn - g_rot1))
    design[:, 0, 0], design[:, 0, 1] = f1**2, t2
    design[:, 1, 2], design[:, 1, 3] = t2, f1**2 + f2**2
    design[:, 2, 0], design[:, 2, 1] = f2**2, t2
    # The truth's position noise: the bearing of a move of length t has variance 2σ²/t²,
    # and rot2 = Δθ − rot1 carries it with the opposite sign.
    var_bearing = var_truth / np.maximum(g_len, BEARING_MIN_TRANS) ** 2
    known[:, 0, 0] = known[:, 2, 2] = var_bearing
    known[:, 0, 2] = known[:, 2, 0] = -var_bearing
    known[:, 1, 1] = var_truth
    # Moves below 0.01 m: nav2 takes rot1 = 0, so only the heading change (rot1 + rot2
    # errors) and the move along the start heading are compared; component 2 is unused.
    if short.any():
        s = short
        along = gd[s, 0] * np.cos(g0[s, 2]) + gd[s, 1] * np.sin(g0[s, 2])
        residual[s, 0] = wrap_angle(wrap_angle(o1[s, 2] - o0[s, 2]) - g_turn[s])
        residual[s, 1] = trans[s] - along
        residual[s, 2] = 0.0
        design[s] = 0.0
        design[s, 0, 0], design[s, 0, 1] = f1[s] ** 2 + f2[s] ** 2, 2 * t2[s]
        design[s, 1, 2], design[s, 1, 3] = t2[s], f1[s] ** 2 + f2[s] ** 2
        known[s] = 0.0
        known[s, 1, 1] = var_truth
        known[s, 2, 2] = 1.0
    return AmclData("diff", residual, design, known)


def _omni_data(o0: NDArray[np.float64], o1: NDArray[np.float64], g0: NDArray[np.float64],
               g1: NDArray[np.float64], var_truth: float) -> AmclData:
    n = o0.shape[0]
    od = o1[:, :2] - o0[:, :2]
    trans = np.hypot(od[:, 0], od[:, 1])
    rot = wrap_angle(o1[:, 2] - o0[:, 2])
    # The direction of travel relative to the start heading, carried to the truth's start.
    beta = wrap_angle(np.arctan2(od[:, 1], od[:, 0]) - o0[:, 2]) + g0[:, 2]
    gd = g1[:, :2] - g0[:, :2]
    c, s = np.cos(beta), np.sin(beta)
    g_trans = gd[:, 0] * c + gd[:, 1] * s
    g_strafe = gd[:, 0] * s - gd[:, 1] * c  # nav2: x += t·cos β + s·sin β, y += t·sin β − s·cos β
    residual = np.column_stack((trans - g_trans, -g_strafe, wrap_angle(rot - (g1[:, 2] - g0[:, 2]))))
    t2, r2 = trans**2, rot**2
    design = np.zeros((n, 3, 5))
    design[:, 0, 2], design[:, 0, 3] = t2, r2  # trans: α3·t² + α4·rot²
    design[:, 1, 3], design[:, 1, 4] = r2, t2  # strafe: α4·rot² + α5·t²
    design[:, 2, 0], design[:, 2, 1] = r2, t2  # rot: α1·rot² + α2·t²
    known = np.zeros((n, 3, 3))
    known[:, 0, 0] = known[:, 1, 1] = var_truth
    return AmclData("omni", residual, design, known)


# --- the likelihood -------------------------------------------------------------------

def _neg_loglik(alpha: NDArray[np.float64], data: AmclData) -> tuple[float, NDArray[np.float64]]:
    """½ Σ (log det C + eᵀC⁻¹e) and its gradient in α (C = diag(A α) + T)."""
    var = np.einsum("njk,k->nj", data.design, alpha) + _VARIANCE_FLOOR
    if data.diagonal:
        # No truth noise across components (the usual case): three scalar residuals each.
        v = var + np.diagonal(data.known, axis1=1, axis2=2)
        if np.any(v <= 0):
            return math.inf, np.zeros_like(alpha)
        r2 = data.residual**2
        value = 0.5 * float(np.sum(np.log(v) + r2 / v))
        return value, 0.5 * np.einsum("njk,nj->k", data.design, 1.0 / v - r2 / v**2)
    if data.blocks:
        # Component 1 alone; components 0 and 2 (rot1, rot2 sharing the truth's bearing
        # noise) as a 2×2 block with its explicit inverse.
        k, e = data.known, data.residual
        v1 = var[:, 1] + k[:, 1, 1]
        a, b, d = var[:, 0] + k[:, 0, 0], k[:, 0, 2], var[:, 2] + k[:, 2, 2]
        det = a * d - b * b
        if np.any(v1 <= 0) or np.any(a <= 0) or np.any(det <= 0):
            return math.inf, np.zeros_like(alpha)
        w00, w02, w22 = d / det, -b / det, a / det
        u0, u2 = w00 * e[:, 0] + w02 * e[:, 2], w02 * e[:, 0] + w22 * e[:, 2]
        u1 = e[:, 1] / v1
        value = 0.5 * float(np.sum(np.log(v1) + np.log(det) + e[:, 1] * u1 + e[:, 0] * u0 + e[:, 2] * u2))
        dw = np.column_stack((w00 - u0**2, 1.0 / v1 - u1**2, w22 - u2**2))
        return value, 0.5 * np.einsum("njk,nj->k", data.design, dw)
    cov = data.known.copy()
    idx = np.arange(3)
    cov[:, idx, idx] += var
    sign, logdet = np.linalg.slogdet(cov)
    if np.any(sign <= 0):
        return math.inf, np.zeros_like(alpha)
    inv = np.linalg.inv(cov)
    u = np.einsum("nij,nj->ni", inv, data.residual)
    value = 0.5 * float(np.sum(logdet) + np.einsum("ni,ni->", data.residual, u))
    # ∂/∂α_k = ½ Σ_j A_jk (W_jj − u_j²), W = C⁻¹, u = W e.
    grad = 0.5 * np.einsum("njk,nj->k", data.design, inv[:, idx, idx] - u**2)
    return value, grad


def log_likelihood(alpha: ArrayLike, data: AmclData) -> tuple[float, NDArray[np.float64]]:
    """The Gaussian log-likelihood of the residuals under α, and its gradient.

    Σ_n log N(e_n; 0, diag(A_n α) + T_n) (an unused component, with T = 1 and e = 0, adds
    the constant −½ log 2π).

    Parameters
    ----------
    alpha : array_like, shape (K,)
    data : AmclData

    Returns
    -------
    value : float
    gradient : ndarray, shape (K,)
    """
    a = np.asarray(alpha, dtype=float)
    value, grad = _neg_loglik(a, data)
    return -value - 1.5 * len(data) * math.log(2.0 * math.pi), -grad


def _start(data: AmclData) -> NDArray[np.float64]:
    """Method-of-moments start: E[e_j²] ≈ (A α)_j + T_jj, solved for α ≥ 0 (NNLS)."""
    from scipy.optimize import nnls

    k = data.design.shape[-1]
    A = data.design.reshape(-1, k)
    target = (data.residual**2 - np.diagonal(data.known, axis1=1, axis2=2)).reshape(-1)
    used = np.any(A > 0, axis=1)
    # Each component scaled by its own size, so metres and radians weigh alike.
    w = 1.0 / np.maximum(A[used].sum(axis=1), 1e-300)
    alpha, _ = nnls(A[used] * w[:, None], np.maximum(target[used], 0.0) * w)
    return np.asarray(alpha, dtype=float)


def _maximise(data: AmclData, start: NDArray[np.float64], fixed: dict[int, float] | None = None
              ) -> tuple[NDArray[np.float64], float]:
    """α ≥ 0 maximising the likelihood with the ``fixed`` components held; (α, −log L)."""
    from scipy.optimize import minimize

    fixed = fixed or {}
    k = start.size
    free = [i for i in range(k) if i not in fixed]
    full = start.astype(float).copy()
    for i, v in fixed.items():
        full[i] = v
    if not free:
        return full, _neg_loglik(full, data)[0]
    # Work in units of a typical α so that L-BFGS-B sees numbers of order one.
    scale = np.maximum(full[free], 1e-3 * max(float(np.max(full)), 1e-12))

    def objective(beta: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        a = full.copy()
        a[free] = beta * scale
        value, grad = _neg_loglik(a, data)
        return value, grad[free] * scale

    best = minimize(objective, full[free] / scale, jac=True, method="L-BFGS-B",
                    bounds=[(0.0, None)] * len(free), options={"maxiter": 500, "ftol": 1e-14, "gtol": 1e-9})
    full[free] = np.maximum(best.x, 0.0) * scale
    return full, _neg_loglik(full, data)[0]


@dataclass(frozen=True)
class AmclFit:
    """Maximum-likelihood AMCL α's (see :func:`fit_amcl`).

    Parameters
    ----------
    model : {"diff", "omni"}
    names : tuple of str
        ``alpha1`` … ``alpha4`` (``alpha5`` for omni).
    alpha : ndarray, shape (K,)
        The estimates (units in the module docstring).
    interval : ndarray, shape (K, 2)
        Profile-likelihood interval of each; ``inf`` where the data give no upper end.
    level : float
        Confidence level of ``interval``.
    updates : int
        Number of AMCL updates the fit used.
    log_likelihood : float
        At the estimate.
    warnings : tuple of str
    """

    model: str
    names: tuple[str, ...]
    alpha: NDArray[np.float64]
    interval: NDArray[np.float64]
    level: float
    updates: int
    log_likelihood: float
    warnings: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``alpha``, ``interval95`` (None for an open end), ``updates``, ...."""
        key = f"interval{100 * self.level:g}".replace(".", "_")
        return {
            "model": self.model,
            "alpha": {n: float(v) for n, v in zip(self.names, self.alpha, strict=True)},
            key: {n: [float(lo), float(hi) if math.isfinite(hi) else None]
                  for n, (lo, hi) in zip(self.names, self.interval, strict=True)},
            "updates": self.updates,
            "log_likelihood": self.log_likelihood,
            "warnings": list(self.warnings),
        }


def _profile_end(data: AmclData, k: int, alpha: NDArray[np.float64], best: float, limit: float,
                 upward: bool) -> float:
    """Where the profile deviance of α_k reaches ``limit`` above (or below) the estimate."""
    from scipy.optimize import brentq

    cache: dict[float, NDArray[np.float64]] = {}

    def excess(x: float) -> float:
        # From the estimate and from the nearest point already profiled: the better one
        # (a start far out on the profile can leave L-BFGS-B badly scaled, and vice versa).
        found, value = _maximise(data, alpha, {k: x})
        if cache:
            near = min(cache.items(), key=lambda kv: abs(kv[0] - x))[1]
            other, other_value = _maximise(data, near, {k: x})
            if other_value < value:
                found, value = other, other_value
        cache[x] = found
        return 2.0 * (min(value, math.inf) - best) - limit

    here = float(alpha[k])
    if not upward:
        if here <= 0.0 or excess(0.0) <= 0.0:
            return 0.0
        return float(brentq(excess, 0.0, here, xtol=1e-12 + 1e-6 * here, rtol=1e-6))
    step = here if here > 0 else 1e-3 * max(float(np.max(alpha)), 1e-6)
    lo, x = here, here + step
    for _ in range(60):
        if excess(x) > 0.0:
            return float(brentq(excess, lo, x, xtol=1e-12 + 1e-6 * x, rtol=1e-6))
        lo, x = x, x + 2.0 * (x - here)
        if x > 1e6 * max(step, 1.0):
            break
    return math.inf


def fit_amcl(data: AmclData | Sequence[AmclData], level: float = 0.95) -> AmclFit:
    """Maximum-likelihood α's of AMCL's motion model, with profile-likelihood intervals.

    Parameters
    ----------
    data : AmclData, or several (pooled)
        From :func:`amcl_data`.
    level : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    AmclFit

    Examples
    --------
    Updates of 0.3 m straight moves whose truth is 3 cm short or long (α3 = 0.01) and
    straight (α2 = 0):

    >>> o0 = np.zeros((40, 3)); o1 = np.tile([0.3, 0.0, 0.0], (40, 1))
    >>> g1 = o1.copy(); g1[:, 0] += 0.03 * np.tile([1.0, -1.0], 20)
    >>> fit = fit_amcl(amcl_data(o0, o1, o0, g1, "diff"))
    >>> round(float(fit.alpha[2]), 6), float(fit.alpha[1]) < 1e-9
    (0.01, True)
    """
    from scipy.stats import chi2

    parts = [data] if isinstance(data, AmclData) else list(data)
    if not parts:
        raise InputError("no AMCL updates to fit")
    pooled = AmclData.concatenate(parts)
    if not 0.0 < level < 1.0:
        raise InputError(f"the confidence level must be in (0, 1), got {level!r}")
    names = ALPHA_NAMES[pooled.model]
    if len(pooled) < len(names) + 1:
        raise InputError(f"{len(pooled)} AMCL update(s) are too few to fit {len(names)} alphas: drive "
                         "further or lower --update-min-d / --update-min-a")
    alpha, value = _maximise(pooled, _start(pooled))
    limit = float(chi2.ppf(level, 1))
    interval = np.array([[_profile_end(pooled, k, alpha, value, limit, upward=False),
                          _profile_end(pooled, k, alpha, value, limit, upward=True)]
                         for k in range(len(names))])
    notes = []
    for k, name in enumerate(names):
        if not math.isfinite(interval[k, 1]):
            notes.append(f"{name} is not bounded above by these data ({_WHAT_IDENTIFIES[pooled.model][k]})")
    best = log_likelihood(alpha, pooled)[0]
    return AmclFit(pooled.model, names, alpha, interval, level, len(pooled), best, tuple(notes))


# What motion informs each α, for the warning when one is unbounded.
_WHAT_IDENTIFIES = {
    "diff": ("turns between updates inform it: record turns and spins in place",
             "straight driving informs it: record straight runs",
             "driving informs it: record longer straight runs",
             "turns inform it: record spins in place and turns"),
    "omni": ("turns inform it: record spins in place", "driving informs it: record straight runs",
             "driving informs it: record straight runs", "turns inform it: record spins in place",
             "driving informs it: record straight runs"),
}
