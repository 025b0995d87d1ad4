"""Maximum-likelihood fit of the per-wheel noise coefficients k_L, k_R from repeated runs.

Chong–Kleeman (section 6) drove their robot 10 m forward and 10 m back 60 times and chose
k_L, k_R "by trial and error" so that the predicted 95 % ellipses matched the observed end
errors. Here the fit is a maximum-likelihood estimate. For the per-wheel model
(Chong–Kleeman eq. 4, 18) the first-order end-pose covariance of a run is *linear* in the
squared coefficients (Chong–Kleeman eq. 23 with Cov(S_0) = 0)::

    C(k_L, k_R) = k_L² A + k_R² B

where A (B) is the covariance that unit noise on the left (right) wheel alone would give.
A and B are computed once per run on that run's own odometry path; the likelihood of the
observed end errors e_i ~ N(μ, C_i) is then cheap to evaluate for any (k_L², k_R²).
The mean μ (the systematic error left after calibration) is estimated by generalised
least squares and the restricted (REML) likelihood is maximised, which removes the
(n−1)/n bias of plain ML variances; or μ is given.

Validity: the model is first order. On a path of length D with wheel base B the
second-order along-track error (≈ D·σθ²/2) is negligible only while k·D^1.5/B² ≪ 1; at
k = 0.003 m^½, D = 20 m, B = 0.4 m the along-track variance is about 60 % larger than
the first-order value and the fitted k comes out too large. The heading error is exactly
linear in the wheel errors; consider ``components=("y", "theta")`` on long paths.

Confidence intervals are **profile-likelihood** intervals: {k : 2·(ℓ_max − ℓ_profile(k)) ≤
χ²₁(level)}; they respect the k ≥ 0 boundary, which Fisher-information intervals do not.
Where the profile never rises above the χ² level (runs that say nothing about one wheel)
the interval is open: its upper end is ``inf``.

When the data cannot identify the fit, the result says so in ``warnings``:

* the two k's are confounded when the estimates of k_L² and k_R² correlate beyond
  :data:`odomkit.calibrate.fit_noise.CONFOUNDED_CORRELATION` (expected Fisher information
  of the Gaussian model, I_jk = ½ Σ_i tr(C_i⁻¹ ∂_j C_i C_i⁻¹ ∂_k C_i), e.g. Kay,
  *Fundamentals of Statistical Signal Processing I*, eq. 3.31). On a forward–spin–back
  path each wheel drives the other's side of the return leg and ρ ≈ −0.9997: only
  k_L² + k_R² is measured, and each interval alone means little;
* the runs leave the first-order regime when the fitted end-heading spread σθ exceeds
  :data:`odomkit.calibrate.fit_noise.FIRST_ORDER_SIGMA_THETA` (the along-track error's
  second-order term D·σθ²/2 is then no longer small, and the fitted k comes out too large).

Both thresholds are fit-noise's, kept in :mod:`odomkit.calibrate.fit_noise`: the same
quantities judged once (this module had its own, 0.99 and 0.3 rad, with no reason recorded).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq, minimize, minimize_scalar
from scipy.special import ndtri

from odomkit import validate
from odomkit.angles import wrap_angle
from odomkit.calibrate.fit_noise import CONFOUNDED_CORRELATION, FIRST_ORDER_SIGMA_THETA
from odomkit.errors import InputError, ModelError
from odomkit.evaluate import ellipse_points
from odomkit.integrate import dead_reckon
from odomkit.kinematics import Method, diff_body_jacobian, diff_body_steps, step_jacobians
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive

__all__ = ["fit_wheel_noise", "fit_wheel_noise_from_runs", "wheel_noise_basis", "WheelNoiseFit"]

_AXES = {"x": 0, "y": 1, "theta": 2}

# The upper end of an interval is searched up to this factor times the k that alone
# explains the whole observed spread: a k predicting a spread 10⁶ times the observed one
# that is still inside the interval means the profile never crosses.
_OPEN_BOUND_FACTOR = 1e3


def wheel_noise_basis(
    d_left: ArrayLike,
    d_right: ArrayLike,
    wheel_base: float,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    method: Method = "exact",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """End-pose covariance per unit k_L² and per unit k_R² along a wheel-travel path.

    Parameters
    ----------
    d_left, d_right : array_like, shape (M,)
        Wheel travel of every step [m].
    wheel_base : float
        Effective wheel base [m].
    pose0 : array_like, shape (3,)
    method : integration method the odometry uses.

    Returns
    -------
    cov_left, cov_right : ndarray, shape (3, 3)
        ``Σ_k |d_L,k| s_k s_kᵀ`` with s_k the sensitivity of the end pose to the left
        (right) wheel travel of step k, Chong–Kleeman eq. (23) with Cov(S_0) = 0 and
        Cov(u_k) of eq. (18). The product of state Jacobians from step k+1 to the end is
        [[1, 0, −(y_N − y_{k+1})], [0, 1, x_N − x_{k+1}], [0, 0, 1]] (the chord form of
        Chong–Kleeman eq. 21, valid for any path), so the sum is one vectorised pass.

    Examples
    --------
    A straight line D = 2 m, B = 0.5 m: Var θ = D (k_L² + k_R²)/B² (Chong–Kleeman eq. 27).

    >>> A, B = wheel_noise_basis(np.full(100, 0.02), np.full(100, 0.02), 0.5)
    >>> round(float(A[2, 2]), 9), round(float(B[2, 2]), 9)
    (8.0, 8.0)
    """
    d_left = np.asarray(d_left, dtype=float)
    d_right = np.asarray(d_right, dtype=float)
    dd, dtheta = diff_body_steps(d_left, d_right, wheel_base)
    poses = dead_reckon(dd, dtheta, pose0, method)
    _, G = step_jacobians(poses[:-1, 2], dd, dtheta, method)
    sens = G @ diff_body_jacobian(wheel_base)  # (M, 3, 2): ∂pose_{k+1}/∂(d_L, d_R)
    lever_x = poses[-1, 0] - poses[1:, 0]
    lever_y = poses[-1, 1] - poses[1:, 1]
    end = sens.copy()
    end[:, 0, :] -= lever_y[:, None] * sens[:, 2, :]
    end[:, 1, :] += lever_x[:, None] * sens[:, 2, :]
    cov_left = np.einsum("k,ki,kj->ij", np.abs(d_left), end[:, :, 0], end[:, :, 0])
    cov_right = np.einsum("k,ki,kj->ij", np.abs(d_right), end[:, :, 1], end[:, :, 1])
    return cov_left, cov_right


@dataclass(frozen=True)
class WheelNoiseFit:
    """Result of :func:`fit_wheel_noise`.

    Parameters
    ----------
    k_left, k_right : float
        ML (REML with an estimated mean) estimates [m^½].
    ci_left, ci_right : tuple of float
        Profile-likelihood confidence intervals at ``level`` [m^½]; the upper end is
        ``inf`` when the data do not bound that k from above (see ``warnings``).
    level : float
    mean : ndarray, shape (d,)
        Estimated (or given) mean end error.
    cov_fitted : ndarray, shape (d, d)
        ``k_L² Ā + k_R² B̄`` with the bases averaged over runs.
    cov_empirical : ndarray, shape (d, d)
        Sample covariance of the errors (divisor n − 1 with an estimated mean).
    components : tuple of str
    loglik : float
        Maximised (restricted) log-likelihood.
    n_runs : int
    errors : ndarray, shape (n, d), optional
        The end errors the fit used (for plotting them against the ellipses).
    k_correlation : float
        Correlation of the k_L² and k_R² estimates (expected Fisher information at the
        fit); NaN when the runs carry no information on one of them.
    sigma_theta : float
        Largest fitted end-heading standard deviation over the runs [rad].
    warnings : tuple of str
        Why the fit may not mean what it seems (confounded k's, an open interval, runs
        beyond the first-order regime); empty when none applies.
    """

    k_left: float
    k_right: float
    ci_left: tuple[float, float]
    ci_right: tuple[float, float]
    level: float
    mean: NDArray[np.float64]
    cov_fitted: NDArray[np.float64]
    cov_empirical: NDArray[np.float64]
    components: tuple[str, ...]
    loglik: float
    n_runs: int
    errors: NDArray[np.float64] | None = None
    k_correlation: float = float("nan")
    sigma_theta: float = float("nan")
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` object (an open interval end ``inf`` is written as null)."""
        return {
            "k_left": self.k_left, "k_right": self.k_right,
            "ci_left": list(self.ci_left), "ci_right": list(self.ci_right),
            "level": self.level, "ci_method": "profile likelihood",
            "mean": self.mean.tolist(), "components": list(self.components),
            "cov_fitted": self.cov_fitted.tolist(), "cov_empirical": self.cov_empirical.tolist(),
            "loglik": self.loglik, "n_runs": self.n_runs, "warnings": list(self.warnings),
        }

    def ellipse(self, axes: tuple[str, str] = ("x", "y"), prob: float = 0.95,
                empirical: bool = False, n: int = 100) -> NDArray[np.float64]:
        """Points (n, 2) of the fitted (or empirical) ``prob`` ellipse around the mean in
        the plane of two components; see :func:`ellipse_points`."""
        idx = [self.components.index(a) for a in axes]
        cov = self.cov_empirical if empirical else self.cov_fitted
        return ellipse_points(cov[np.ix_(idx, idx)], self.mean[idx], prob, n)


class _Likelihood:
    def __init__(self, errors: NDArray[np.float64], A: NDArray[np.float64], B: NDArray[np.float64],
                 mean: NDArray[np.float64] | None, shared: bool):
        self.e, self.A, self.B, self.mean, self.shared = errors, A, B, mean, shared
        if shared:
            # One covariance for all runs: the scatter matrix is a sufficient statistic.
            self.mu_shared = errors.mean(axis=0) if mean is None else mean
            r = errors - self.mu_shared
            self.scatter = r.T @ r

    def __call__(self, q: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        """(restricted) log-likelihood at q = (k_L², k_R²) and the mean used."""
        if self.shared:
            return self._shared(q)
        return self._per_run(q)

    def _shared(self, q: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        C = q[0] * self.A[0] + q[1] * self.B[0]
        sign, logdet = np.linalg.slogdet(C)
        if sign <= 0 or not np.isfinite(logdet):
            return -np.inf, self.mu_shared
        n, d = self.e.shape
        quad = float(np.trace(np.linalg.solve(C, self.scatter)))
        ll = -0.5 * (n * logdet + quad)
        if self.mean is None:
            ll -= 0.5 * (d * np.log(n) - logdet)  # REML: −½ log det(n C⁻¹)
        return float(ll), self.mu_shared

    def _per_run(self, q: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        C = q[0] * self.A + q[1] * self.B
        try:
            L = np.linalg.cholesky(C)
            Cinv = np.linalg.inv(C)
        except np.linalg.LinAlgError:
            return -np.inf, np.zeros(self.e.shape[1])
        logdet = 2.0 * np.sum(np.log(np.abs(np.diagonal(L, axis1=1, axis2=2))), axis=1)
        extra = 0.0
        if self.mean is None:
            # GLS mean and the REML term −½ log det(Σ C_i⁻¹) (Patterson–Thompson).
            S = Cinv.sum(axis=0)
            mu = np.linalg.solve(S, np.einsum("nij,nj->i", Cinv, self.e))
            extra = -0.5 * np.linalg.slogdet(S)[1]
        else:
            mu = self.mean
        r = self.e - mu
        quad = np.einsum("ni,nij,nj->n", r, Cinv, r)
        return float(-0.5 * np.sum(logdet + quad) + extra), mu


def fit_wheel_noise(
    errors: ArrayLike,
    cov_left: ArrayLike,
    cov_right: ArrayLike,
    *,
    mean: ArrayLike | None = None,
    components: Sequence[str] = ("x", "y", "theta"),
    level: float = 0.95,
) -> WheelNoiseFit:
    """Maximum-likelihood k_L, k_R from repeated end-pose errors.

    Parameters
    ----------
    errors : array_like, shape (n, 3)
        End-pose errors of n runs [m, m, rad] (truth minus odometry; the sign does not
        matter for a covariance).
    cov_left, cov_right : array_like, shape (n, 3, 3) or (3, 3)
        Per-run bases from :func:`wheel_noise_basis` (or one pair shared by all runs).
    mean : array_like, shape (d,), optional
        Known mean error (e.g. zeros); default: estimated (REML).
    components : subset of ("x", "y", "theta")
        Which components enter the likelihood (Chong–Kleeman found the off-track error
        unreliable; leave it out with ``("x", "theta")``).
    level : float
        Confidence level of the profile-likelihood intervals.

    Returns
    -------
    WheelNoiseFit

    Examples
    --------
    >>> A, B = wheel_noise_basis(np.full(50, 0.2), np.full(50, 0.2), 0.5)
    >>> rng = np.random.default_rng(1)
    >>> e = rng.multivariate_normal(np.zeros(3), 0.002**2 * A + 0.001**2 * B, size=400)
    >>> fit = fit_wheel_noise(e, A, B, mean=np.zeros(3))
    >>> fit.ci_left[0] < 0.002 < fit.ci_left[1], fit.ci_right[0] < 0.001 < fit.ci_right[1]
    (True, True)
    """
    e = validate.shape(errors, "errors [x, y, theta]", ("n", 3), error=InputError)
    n = e.shape[0]
    if n < 2:
        raise InputError(f"fitting k_L, k_R needs at least two runs, got {n}")
    try:
        idx = [_AXES[c] for c in components]
    except KeyError:
        raise ModelError(f"components must be among {list(_AXES)}, got {list(components)}") from None
    shared = np.ndim(cov_left) == 2 and np.ndim(cov_right) == 2
    A_full = np.broadcast_to(np.asarray(cov_left, dtype=float), (n, 3, 3))
    B_full = np.broadcast_to(np.asarray(cov_right, dtype=float), (n, 3, 3))
    A = A_full[:, idx][:, :, idx]
    B = B_full[:, idx][:, :, idx]
    e = e[:, idx]
    mu_known = None if mean is None else np.asarray(mean, dtype=float).reshape(-1)
    if mu_known is not None and mu_known.shape != (len(idx),):
        raise InputError(f"mean must have {len(idx)} components, got {mu_known.shape}")
    if mu_known is None and n < 3:
        raise InputError("with an estimated mean, fitting k_L, k_R needs at least three runs")
    # Scale q so both coordinates are O(1): match each basis's trace to the observed spread.
    spread = float(np.trace(np.cov(e.T).reshape(len(idx), len(idx))))
    if mu_known is not None and not spread > 0:
        spread = float(np.sum((e - mu_known) ** 2) / n)
    if not np.isfinite(spread):
        raise ModelError(f"the spread of the runs' end errors overflows ({spread!r}): the errors "
                         "are out of range (check units and the robot file)")
    if not spread > 0:
        raise InputError("the runs' end errors have no spread to fit noise to: are the runs "
                         "copies of one log?")
    traces = np.array([np.trace(A.mean(axis=0)), np.trace(B.mean(axis=0))])
    if not (np.all(np.isfinite(traces)) and traces.max() > 0):
        raise ModelError("the runs' wheel travel predicts no error in the fitted components "
                         f"{list(components)}: nothing to fit k_L, k_R to")
    # A wheel whose noise does not reach the components (it never moves) has a zero
    # basis; floor its scale so that its (unidentified) coordinate stays finite.
    qs = spread / np.maximum(traces, 1e-12 * traces.max())
    lik = _Likelihood(e, A, B, mu_known, shared)
    with np.errstate(all="ignore"):
        q_hat, ll_max, mu_hat = _maximise(lik, qs)
        identified = traces > 0
        q_hat = np.where(identified, q_hat, 0.0)  # the likelihood is flat in that k
        crit = float(ndtri(0.5 * (1.0 + level)) ** 2)  # χ²₁ quantile = (z_{(1+level)/2})²
        ci = [_profile_interval(lik, which, q_hat, qs, ll_max, crit) for which in (0, 1)]
        rho = _k_correlation(A, B, q_hat)
        sigma_theta = float(np.sqrt(np.max(q_hat[0] * A_full[:, 2, 2] + q_hat[1] * B_full[:, 2, 2])))
    notes = _warnings(rho, identified, ci, sigma_theta, level)

    ddof = 1 if mu_known is None else 0
    r = e - (mu_hat if mu_known is None else mu_known)
    cov_emp = r.T @ r / (n - ddof)
    return WheelNoiseFit(
        k_left=float(np.sqrt(q_hat[0])), k_right=float(np.sqrt(q_hat[1])),
        ci_left=ci[0], ci_right=ci[1], level=level, mean=np.asarray(mu_hat),
        cov_fitted=q_hat[0] * A.mean(axis=0) + q_hat[1] * B.mean(axis=0), cov_empirical=cov_emp,
        components=tuple(components), loglik=ll_max, n_runs=n, errors=e,
        k_correlation=rho, sigma_theta=sigma_theta, warnings=tuple(notes),
    )


def _maximise(lik: _Likelihood, qs: NDArray[np.float64]
              ) -> tuple[NDArray[np.float64], float, NDArray[np.float64]]:
    """(q̂, ℓ_max, μ̂): the (restricted) likelihood maximised over q = qs·exp(z)."""
    def nll(z: NDArray[np.float64]) -> float:
        # log-parametrised: q = qs·exp(z) > 0; the boundary k = 0 is approached as z → −∞.
        val = lik(np.exp(np.clip(z, -60.0, 60.0)) * qs)[0]
        return 1e300 if not np.isfinite(val) else -val

    best = None
    for start in ([np.log(0.5), np.log(0.5)], [np.log(0.9), np.log(0.1)], [np.log(0.1), np.log(0.9)]):
        res = minimize(nll, np.array(start), method="Nelder-Mead",
                       options={"xatol": 1e-7, "fatol": 1e-10, "maxiter": 2000})
        if best is None or res.fun < best.fun:
            best = res
    assert best is not None
    q_hat = np.exp(np.clip(best.x, -60.0, 60.0)) * qs
    ll_max, mu_hat = lik(q_hat)
    if not np.isfinite(ll_max):
        raise ModelError("the likelihood of k_L, k_R is not finite anywhere the fit looked: the "
                         "runs' errors or wheel travel are out of range (check units and the robot file)")
    return q_hat, float(ll_max), mu_hat


def _profile(lik: _Likelihood, which: int, q_hat: NDArray[np.float64],
             qs: NDArray[np.float64], ll_max: float, crit: float) -> Callable[[float], float]:
    """k ↦ 2·(ℓ_max − ℓ_profile(k)) − χ²: ≤ 0 inside the interval, > 0 outside."""
    other = 1 - which

    def loglik(k: float, z: float) -> float:
        q = np.empty(2)
        q[which], q[other] = np.float64(k) ** 2, max(z, 1e-12) * qs[other]
        return float(lik(q)[0])

    def f(k: float) -> float:
        def neg(z: float) -> float:
            val = loglik(k, z)
            return 1e300 if not np.isfinite(val) else -val
        hi = max(50.0, 10 * q_hat[other] / qs[other])
        r = minimize_scalar(neg, bounds=(1e-12, hi), method="bounded", options={"xatol": 1e-8})
        # The other k's fitted value is a candidate too, so that the profile at k̂ is ℓ_max.
        best = max(-float(r.fun), loglik(k, q_hat[other] / qs[other]))
        return 2.0 * (ll_max - best) - crit if np.isfinite(best) else np.inf

    return f


def _profile_interval(lik: _Likelihood, which: int, q_hat: NDArray[np.float64],
                      qs: NDArray[np.float64], ll_max: float, crit: float) -> tuple[float, float]:
    """Profile-likelihood interval of k_which: [0 or the lower crossing, the upper crossing
    or ``inf`` when the profile never crosses below :data:`_OPEN_BOUND_FACTOR` times the k
    that alone explains the observed spread]."""
    f = _profile(lik, which, q_hat, qs, ll_max, crit)
    k_hat = float(np.sqrt(q_hat[which]))
    lo = 0.0
    if k_hat > 0:
        a = 1e-9 * max(k_hat, 1e-12)
        if f(a) > 0 and f(k_hat) < 0:
            lo = brentq(f, a, k_hat, xtol=1e-7 * k_hat + 1e-15)
    k_cap = _OPEN_BOUND_FACTOR * max(float(np.sqrt(qs[which])), k_hat)
    hi_k = 2.0 * k_hat + 1e-12
    while f(hi_k) <= 0:
        if hi_k > k_cap:
            return float(lo), np.inf
        hi_k *= 2.0
    if not f(k_hat) < 0:  # cannot happen with a converged maximum; never bracket blindly
        return float(lo), np.inf
    hi = brentq(f, k_hat, hi_k, xtol=1e-7 * k_hat + 1e-15)
    return float(lo), float(hi)


def _k_correlation(A: NDArray[np.float64], B: NDArray[np.float64], q: NDArray[np.float64]) -> float:
    """Correlation of the k_L², k_R² estimates from the expected Fisher information of
    e_i ~ N(μ, q_L A_i + q_R B_i): I_jk = ½ Σ_i tr(C_i⁻¹ D_j C_i⁻¹ D_k) with D = (A_i, B_i)
    (Kay, Fundamentals of Statistical Signal Processing I, eq. 3.31). NaN when a basis
    carries no information or C is singular."""
    try:
        Cinv = np.linalg.inv(q[0] * A + q[1] * B)
    except np.linalg.LinAlgError:
        return float("nan")
    X, Y = Cinv @ A, Cinv @ B
    i00 = 0.5 * np.einsum("nij,nji->", X, X)
    i11 = 0.5 * np.einsum("nij,nji->", Y, Y)
    i01 = 0.5 * np.einsum("nij,nji->", X, Y)
    if not (i00 > 0 and i11 > 0 and np.isfinite(i01)):
        return float("nan")
    # (I⁻¹)₀₁/√((I⁻¹)₀₀(I⁻¹)₁₁) for a 2×2 information matrix
    return float(np.clip(-i01 / np.sqrt(i00 * i11), -1.0, 1.0))


def _warnings(rho: float, identified: NDArray[np.bool_], ci: list[tuple[float, float]],
              sigma_theta: float, level: float) -> list[str]:
    notes = []
    names = ("k_left", "k_right")
    for name, known in zip(names, identified, strict=True):
        if not known:
            notes.append(f"the runs carry no information on {name} (that wheel's noise does not "
                         "reach the fitted components: does the wheel move?); its value 0 means unknown")
    if all(identified) and not abs(rho) < CONFOUNDED_CORRELATION:
        # rho is NaN where the information matrix is degenerate: no correlation can be
        # computed, which is the same verdict said without a number.
        how = (f"their estimates correlate at {rho:.4f}" if np.isfinite(rho)
               else "their information matrix is degenerate")
        notes.append(f"the runs cannot tell k_left from k_right: {how}, so only a combination is "
                     "measured and each interval alone means little; drive a path where the two "
                     "wheels' errors show differently (e.g. arcs turning both ways, no spin "
                     "between out and back)")
    for name, (_, hi) in zip(names, ci, strict=True):
        if not np.isfinite(hi):
            notes.append(f"the data do not bound {name} from above at the {100 * level:g} % level "
                         "(open interval)")
    if sigma_theta > FIRST_ORDER_SIGMA_THETA:
        notes.append(f"the fitted end-heading spread is {sigma_theta:.3g} rad, beyond the first-order "
                     f"regime (~{FIRST_ORDER_SIGMA_THETA} rad): the likelihood is wrong there and k "
                     "comes out too large; fit shorter runs, or components y,theta")
    return notes

def fit_wheel_noise_from_runs(runs: Sequence[OdometryLog], robot: DiffDrive, **kwargs: Any) -> WheelNoiseFit:
    """:func:`fit_wheel_noise` on logs with ground truth: each run's end error (truth minus
    odometry, start frame) and its bases along its own odometry path.

    Parameters
    ----------
    runs : sequence of OdometryLog
        Repeated runs of one path (e.g. 10 m forward and back), with ground truth.
    robot : DiffDrive
        Calibrated robot (systematic errors left in the runs bias the mean, not k, when the
        mean is estimated).
    **kwargs : passed to :func:`fit_wheel_noise`.
    """
    from odomkit.kinematics import body_steps
    from odomkit.robot import DiffDrive
    from odomkit.track import dead_reckon_log

    if not isinstance(robot, DiffDrive):
        raise ModelError("k_L, k_R are per-wheel coefficients of a differential-drive robot")
    errors, A, B = [], [], []
    for log in runs:
        if log.ground_truth is None:
            raise InputError("run has no ground truth", source=log.source)
        track = dead_reckon_log(log, robot)
        err = log.ground_truth[-1] - track.poses[-1]
        err[2] = wrap_angle(err[2])
        errors.append(err)
        steps = body_steps(robot, log)
        a, b = wheel_noise_basis(steps.inputs["d_left"], steps.inputs["d_right"],
                                 robot.effective_wheel_base, track.poses[0])
        A.append(a)
        B.append(b)
    return fit_wheel_noise(np.array(errors), np.array(A), np.array(B), **kwargs)
