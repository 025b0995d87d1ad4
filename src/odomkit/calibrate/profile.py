"""Profile likelihoods of fitted variance parameters: the curves behind the intervals.

A profile-likelihood interval (:func:`odomkit.calibrate.fit_noise.fit_noise`,
:func:`odomkit.calibrate.amcl.fit_amcl`) is where the profile ℓ_p(v_j) = max over the
other free parameters (all ≥ 0) of log L stays within χ²₁(level)/2 of the maximum ℓ̂.
The fits find only the two crossings; this module computes the whole curve on a grid, to
draw it (``fit-noise --plot``, ``fit-amcl --plot``) and to check the crossings
independently. It calls only the public likelihoods: the window likelihood
(:class:`~odomkit.calibrate.window_likelihood.WindowLikelihood`) and AMCL's
(:func:`~odomkit.calibrate.amcl.log_likelihood`), each with its analytic gradient, and
maximises with scipy's L-BFGS-B (bounds v ≥ 0), warm-started from the estimate and from
the neighbouring grid point, whichever ends higher.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError

if TYPE_CHECKING:
    from odomkit.calibrate.amcl import AmclData, AmclFit
    from odomkit.calibrate.fit_noise import NoiseFit
    from odomkit.noise import NoiseModel
    from odomkit.robot import Robot
    from odomkit.window_errors import WindowBasis

__all__ = ["LogLikelihood", "Profile", "amcl_profiles", "noise_profiles", "profile_grid",
           "profile_log_likelihood"]

#: log L, its gradient (None where log L is −∞) and, optionally, a positive semi-definite
#: curvature (the expected or average information, ≈ −∇²log L) or None.
LogLikelihood = Callable[[NDArray[np.float64]],
                         tuple[float, NDArray[np.float64] | None, NDArray[np.float64] | None]]


@dataclass(frozen=True)
class Profile:
    """One parameter's profile likelihood.

    Attributes
    ----------
    name : str
        The parameter (``k_left``, ``alpha3``, ...).
    values : ndarray, shape (K,)
        Grid of the parameter in its own unit (σ and k fields: the square root of the
        variance parameter), increasing.
    log_likelihood : ndarray, shape (K,)
        ℓ_p at each value.
    estimate : float
        The fit's value.
    maximum : float
        ℓ̂, log L at the fit.
    interval : (float, float)
        The fit's profile-likelihood interval (upper end ``inf`` when open).
    level : float
        Its confidence level.
    """

    name: str
    values: NDArray[np.float64]
    log_likelihood: NDArray[np.float64]
    estimate: float
    maximum: float
    interval: tuple[float, float]
    level: float


def profile_log_likelihood(loglik: LogLikelihood, estimate: ArrayLike, index: int, grid: ArrayLike, *,
                           free: Collection[int] | None = None) -> NDArray[np.float64]:
    """ℓ_p(x) = max over v[free \\ {index}] ≥ 0 of ``loglik(v)`` with v[index] = x, on a grid.

    Parameters
    ----------
    loglik : callable
        v (P,) -> (log L, ∂log L/∂v or None, curvature (P, P) or None). With a curvature
        the maximisation takes Newton steps projected on v ≥ 0 (a handful of evaluations);
        without, scipy's L-BFGS-B.
    estimate : array_like, shape (P,)
        The maximum-likelihood estimate: the start, and the value of the entries that are
        not free.
    index : int
        The profiled entry.
    grid : array_like, shape (K,)
        Its values.
    free : collection of int, optional
        Entries maximised over (default: all); ``index`` is left out of them.

    Returns
    -------
    ndarray, shape (K,)

    Examples
    --------
    A Gaussian log-likelihood in two correlated parameters: the profile of the first is
    the 1-D Gaussian with its marginal variance (A⁻¹)₀₀ = 2.

    >>> A = np.array([[1.0, -0.5], [-0.5, 0.5]])
    >>> mu = np.array([3.0, 4.0])
    >>> f = lambda v: (-0.5 * (v - mu) @ A @ (v - mu), -A @ (v - mu), A)
    >>> np.round(profile_log_likelihood(f, mu, 0, [1.0, 3.0, 5.0]), 6).tolist()
    [-1.0, 0.0, -1.0]
    """
    v_hat = np.asarray(estimate, dtype=float)
    x = np.asarray(grid, dtype=float)
    if not 0 <= index < v_hat.size:
        raise ModelError(f"index {index} is not one of the {v_hat.size} parameters")
    others = np.array(sorted(set(range(v_hat.size) if free is None else free) - {index}), dtype=np.intp)
    typical = float(np.max(np.abs(v_hat))) if v_hat.size else 1.0
    scale = np.maximum(np.abs(v_hat[others]), 1e-3 * typical)
    scale[scale == 0] = 1.0

    def solve(value: float, start: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        base = v_hat.copy()
        base[index] = value
        if others.size == 0:
            return float(loglik(base)[0]), start
        base[others] = np.maximum(start, 0.0)
        if loglik(base)[2] is not None:
            return _newton(loglik, base, others, scale)
        return _lbfgsb(loglik, base, others, scale)

    out = np.full(x.size, -np.inf)
    order = np.argsort(x)
    centre = int(np.searchsorted(x[order], v_hat[index]))
    # Outward from the estimate in both directions: each point starts where its neighbour's
    # optimum is (the first one of a sweep from the estimate too; the higher end wins).
    for sweep in (order[centre:], order[:centre][::-1]):
        previous = None
        for k in sweep:
            candidates = [solve(float(x[k]), previous if previous is not None else v_hat[others])]
            if previous is not None and k == sweep[1 if len(sweep) > 1 else 0]:
                candidates.append(solve(float(x[k]), v_hat[others]))
            value, previous = max(candidates, key=lambda c: c[0])
            out[k] = value
    return out


def _newton(loglik: LogLikelihood, v: NDArray[np.float64], idx: NDArray[np.intp],
            scale: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
    """Maximise over v[idx] ≥ 0 by Newton steps on the given curvature, projected on the
    bound (an entry at zero whose gradient points below it stays), with step halving."""
    ll, grad, curv = loglik(v)
    for _ in range(100):
        if grad is None or curv is None or not np.isfinite(ll):
            break
        u = v[idx] / scale
        g = grad[idx] * scale
        move = ~((u <= 0.0) & (g <= 0.0))
        step = np.zeros_like(u)
        if move.any():
            H = (curv[np.ix_(idx, idx)] * scale[:, None] * scale[None, :])[np.ix_(move, move)]
            step[move] = np.linalg.pinv(H, rcond=1e-12, hermitian=True) @ g[move]
        t, gain = 1.0, -np.inf
        while t > 1e-10:
            trial = v.copy()
            trial[idx] = np.maximum(u + t * step, 0.0) * scale
            value = loglik(trial)
            gain = value[0] - ll
            if gain >= 0.0:
                break
            t *= 0.5
        if not gain >= 0.0:
            break
        change = float(np.max(np.abs(trial[idx] - v[idx]) / scale / (1.0 + u)))
        v, (ll, grad, curv) = trial, value
        if gain < 1e-10 and change < 1e-8:
            break
    return float(ll), v[idx]


def _lbfgsb(loglik: LogLikelihood, v: NDArray[np.float64], idx: NDArray[np.intp],
            scale: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
    """Maximise over v[idx] ≥ 0 with scipy's L-BFGS-B (gradient only)."""
    from scipy.optimize import minimize

    def objective(beta: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        trial = v.copy()
        trial[idx] = np.maximum(beta, 0.0) * scale
        ll, grad, _ = loglik(trial)
        if grad is None or not np.isfinite(ll):
            return 1e300, np.zeros_like(beta)
        return -float(ll), -np.asarray(grad)[idx] * scale

    found = minimize(objective, v[idx] / scale, jac=True, method="L-BFGS-B", bounds=[(0.0, None)] * idx.size,
                     options={"maxiter": 1000, "ftol": 1e-15, "gtol": 1e-10})
    return -float(found.fun), np.maximum(found.x, 0.0) * scale


def profile_grid(estimate: float, interval: tuple[float, float], points: int = 25) -> NDArray[np.float64]:
    """A grid (model units, ≥ 0) that spans an interval with a margin of 40 % of its width
    on each side, holding the estimate and both finite interval ends; an open interval
    runs to three times its largest finite number.

    >>> np.round(profile_grid(2.0, (1.0, 3.0), 5), 12).tolist()
    [0.2, 1.0, 1.1, 2.0, 2.9, 3.0, 3.8]
    """
    lo, hi = float(interval[0]), float(interval[1])
    if np.isfinite(hi):
        width = max(hi - lo, 1e-12 * max(abs(hi), 1.0))
        a, b = max(0.0, lo - 0.4 * width), hi + 0.4 * width
    else:
        b = 3.0 * max(estimate, lo, 0.0) or 1.0
        a = max(0.0, lo - 0.2 * (b - lo))
    marks = np.array([v for v in (estimate, lo, hi) if np.isfinite(v) and a <= v <= b])
    even = np.linspace(a, b, points)
    # The marks themselves, not grid points a rounding error away from them.
    near = np.isclose(even[:, None], marks[None, :], rtol=0.0, atol=1e-9 * (b - a)).any(axis=1)
    return np.unique(np.concatenate([even[~near], marks]))


def noise_profiles(bases: Sequence[WindowBasis], models: Sequence[NoiseModel], robot: Robot, fit: NoiseFit,
                   *, kinds: Collection[str] = ("white",), fixed: Collection[str] = (),
                   points: int = 25) -> list[Profile]:
    """The profile likelihood of every free parameter of a :func:`fit_noise` result.

    Parameters
    ----------
    bases, models, robot, kinds, fixed
        Exactly as given to :func:`odomkit.calibrate.fit_noise.fit_noise`.
    fit : NoiseFit
        Its result.
    points : int
        Grid points per parameter (:func:`profile_grid`).

    Returns
    -------
    list of Profile
        In the order of ``fit.parameters``; values in the models' own units.
    """
    from odomkit.calibrate.fit_noise import fit_parameters
    from odomkit.calibrate.window_likelihood import WindowLikelihood

    params = fit_parameters(bases, models, robot, kinds, set(fixed) | set(fit.truth_held))
    if {p.key for p in params if p.free} != set(fit.parameters):
        raise ModelError("the fit's parameters are not those of these models, kinds and fixed names")
    used = [b for b in bases if len(b.windows)]
    lik = WindowLikelihood(used)
    v_hat = np.array([fit.variances[p.key] for p in params])
    trim = fit.trim
    if trim is not None and fit.trimmed:
        # A trimmed fit's likelihood holds the windows inside its ``trim`` ellipse at the
        # fit (the fixed point of its trimming).
        keep = np.split(lik.inside(v_hat, trim), lik.starts[1:])
        lik = WindowLikelihood([b.select(k) for b, k in zip(used, keep, strict=True) if k.any()])
    free = [j for j, p in enumerate(params) if p.free]

    def loglik(v: NDArray[np.float64]) -> tuple[float, NDArray[np.float64] | None,
                                                NDArray[np.float64] | None]:
        # The average information: positive semi-definite, Newton-fast (Gilmour et al. 1995).
        value = lik(v, information=True)
        return value.loglik, value.gradient, value.average

    out = []
    for j in free:
        p = params[j]
        power = p.power
        grid = profile_grid(fit.parameters[p.key], fit.interval[p.key], points)
        ll = profile_log_likelihood(loglik, v_hat, j, grid**power, free=free)
        out.append(Profile(p.key, grid, ll, fit.parameters[p.key], fit.log_likelihood,
                           fit.interval[p.key], fit.level))
    return out


def amcl_profiles(data: AmclData | Sequence[AmclData], fit: AmclFit, points: int = 25) -> list[Profile]:
    """The profile likelihood of each α of a :func:`odomkit.calibrate.amcl.fit_amcl`
    result, on the same (pooled) data."""
    from odomkit.calibrate.amcl import AmclData, log_likelihood

    pooled = data if isinstance(data, AmclData) else AmclData.concatenate(list(data))

    def loglik(alpha: NDArray[np.float64]) -> tuple[float, NDArray[np.float64] | None, None]:
        value, grad = log_likelihood(alpha, pooled)
        return value, grad if np.isfinite(value) else None, None

    out = []
    for k, name in enumerate(fit.names):
        interval = (float(fit.interval[k, 0]), float(fit.interval[k, 1]))
        grid = profile_grid(float(fit.alpha[k]), interval, points)
        ll = profile_log_likelihood(loglik, fit.alpha, k, grid)
        out.append(Profile(name, grid, ll, float(fit.alpha[k]), fit.log_likelihood, interval, fit.level))
    return out
