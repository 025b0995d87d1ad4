"""Maximum-likelihood noise variances from window-end errors (``odomkit fit-noise``).

Each log with ground truth is cut into windows that restart from the truth
(:mod:`odomkit.windows`; their ends' errors and covariances: :mod:`odomkit.window_errors`).
To first order a window end's covariance is linear in the noise models' variance
parameters v (:meth:`odomkit.noise.NoiseModel.variance_parameters`: σ and k fields
squared, var/psd/alpha fields as they are), so the bases are computed once per window and
the likelihood of every window end (:class:`WindowLikelihood`: white noise independent
between windows, one bias draw per log) is cheap to evaluate at any v.
It is maximised over v ≥ 0 by L-BFGS-B on log v with its analytic gradient.

Intervals are **profile-likelihood** intervals {v_j : 2(ℓ̂ − ℓ_p(v_j)) ≤ χ²₁(level)}: they
respect the boundary v ≥ 0 (an interval may be closed at 0) and are reported in the
model's own units (σ, k: the square root of the variance bounds). A likelihood that stays
within the threshold however large v_j grows gives an open upper bound (infinity): the
data cannot identify that parameter.

Warnings (the result's ``warnings``) say when a result could be silently wrong: a
parameter the data cannot identify (flat profile, correlation near ±1, too little
turning, too few windows or logs), a first-order model stretched too far (σθ large at
window ends), logs that disagree with the fit (each log's eᵀΣ⁻¹e against its χ²
distribution, Bonferroni-corrected), and a fitted value no real robot or truth has (a
period jitter over half the sample period, a run-to-run scale over 10 %, a truth stamped
seconds off: :mod:`odomkit.calibrate.noise_plausible`), where the fit has put error the
model does not explain.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq
from scipy.stats import chi2

from odomkit.calibrate.noise_plausible import implausible_values
from odomkit.calibrate.window_likelihood import WindowLikelihood
from odomkit.errors import InputError, ModelError
from odomkit.evaluate import coverage, coverage_range, coverage_verdicts, nees, overall_verdict
from odomkit.noise import NOISE_MODELS, NoiseModel, NoiseSet
from odomkit.noise.base import variance_power
from odomkit.window_errors import TRUTH_NOISE

if TYPE_CHECKING:
    from odomkit.robot import Robot
    from odomkit.window_errors import WindowBasis

__all__ = [
    "CONFOUNDED_CORRELATION",
    "DEFAULT_FIXED",
    "DEFAULT_TRIM",
    "DEFAULT_WHITE",
    "defaults_left_out",
    "first_order_horizon",
    "first_order_note",
    "first_order_track_note",
    "FIRST_ORDER_SIGMA_THETA",
    "FITTED_ABOVE_SCATTER",
    "GIVEN_ABOVE_SCATTER",
    "TRIM_SHARE",
    "NoiseFit",
    "NoiseParameter",
    "fit_noise",
    "fit_parameters",
    "noise_parameters",
    "models_to_fit",
]

#: The white models fitted when a robot file names none, by robot type: the vehicle's own
#: input noise, and slip across the track (:class:`~odomkit.noise.LateralSlipNoise`) for
#: every vehicle; a differential drive also gets common-mode slip along the track
#: (:class:`~odomkit.noise.SpeedNoise`), which its per-wheel k cannot express (a steered
#: vehicle's speed noise already is). On held-out OptiOdom runs the per-wheel k alone
#: cannot hold at both 10 s and 30 s windows; with slip it does (benchmarks/honesty.py).
#: A unicycle also gets noise that grows with turning (:class:`~odomkit.noise.TurnNoise`),
#: which its distance and time noise cannot express: fitted on MRCLAM robots 1-2 it lifted
#: the held-out robots' 95 % coverage of 30 s windows from 0.874 to 0.908 (dataset 6) and
#: 0.878 to 0.927 (dataset 7). A gyro robot does not by default: its |Δθ| is the measured
#: turn, which the gyro's own noise makes grow with the sample rate while it stands or drives
#: straight (0.12 rad over 60 s standing at 10 Hz, 0.19 at 400 Hz), and no gyro log backs it.
DEFAULT_WHITE: dict[str, tuple[str, ...]] = {
    "diff": ("WheelNoise", "SpeedNoise", "LateralSlipNoise"),
    "tricycle": ("TricycleNoise", "LateralSlipNoise"),
    "gyro": ("SpeedNoise", "GyroNoise", "LateralSlipNoise"),
    "compass": ("SpeedNoise", "CompassNoise", "LateralSlipNoise"),
    "unicycle": ("SpeedNoise", "GyroNoise", "TurnNoise", "LateralSlipNoise"),
    "car": ("TricycleNoise", "LateralSlipNoise"),
}
#: Parameters of those defaults held at zero: with a constant sample period a period
#: error moves a tricycle exactly as a speed error does (∂/∂T = (v/T)·∂/∂v), so the data
#: cannot tell them apart.
DEFAULT_FIXED = frozenset({"sigma_dt"})
#: ``odomkit fit-noise``'s default ``--trim``: window ends outside the fit's 99.9 % ellipse
#: are left out of it. On OptiOdom (both platforms, fitted on half the experiments, scored
#: on the other half and the other way round) every untrimmed fit over-covers 30 s windows
#: (95 % coverage 1.00, NEES 0.1-0.6) because a few heavy-tailed windows inflate it; trimmed,
#: the 30 s targets are met in two of the four cases and missed by one or two window ends
#: in the others, at a cost of a few points of 95 % coverage at 10 s
#: (benchmarks/honesty.py). On very few runs with heavy tails (the demo's ten) trimming
#: costs more; ``--trim 1`` keeps every window.
DEFAULT_TRIM: float | None = 0.999
#: σθ at a window end [rad] above which the first-order model is doubtful: the along-track
#: second-order error (≈ D σθ²/2) reaches a tenth of the cross-track error (D σθ). Also
#: calibrate-noise's limit at a run's end (:mod:`odomkit.calibrate.noise_fit`): the same
#: model judged the same way (it had 0.3 rad there, with no reason recorded).
FIRST_ORDER_SIGMA_THETA = 0.2
#: |correlation| of two fitted variances' estimates (expected Fisher information) beyond
#: which they are not told apart: each standard error is 1/√(1 − ρ²) > 3.2 times that of a
#: fit of either alone. Every pair of fit-noise's parameters is judged by it, and
#: calibrate-noise's k_L², k_R² (:mod:`odomkit.calibrate.noise_fit`): one quantity, one
#: threshold (calibrate-noise had 0.99, with no reason recorded, and passed a CW+CCW square's
#: −0.964 without a word).
CONFOUNDED_CORRELATION = 0.95


def first_order_note(var_theta: ArrayLike, start_var_theta: ArrayLike | None = None) -> str | None:
    """The warning that the first-order covariance may not hold at window ends whose
    heading variance ``var_theta`` (W,) [rad²] exceeds :data:`FIRST_ORDER_SIGMA_THETA`²
    (fit-noise's fitted model, evaluate's scored one), or None.

    ``start_var_theta`` (W,) [rad²], where given, is the share of it that each window's start
    heading brings (fitted to position-only truth): where that is most of it at those ends,
    shorter windows do not help (a Husky bag's 0.85 rad came from fixes of 0.8 m), and the
    advice says what does."""
    var = np.clip(np.asarray(var_theta, dtype=float), 0.0, None)
    sigma_theta = np.sqrt(var)
    big = sigma_theta > FIRST_ORDER_SIGMA_THETA
    if not big.any():
        return None
    said = (f"the first-order model may not hold: σθ reaches {sigma_theta.max():.3g} rad at "
            f"{int(big.sum())} of {big.size} window ends (> {FIRST_ORDER_SIGMA_THETA} rad)")
    if start_var_theta is not None:
        start = np.clip(np.asarray(start_var_theta, dtype=float), 0.0, None)
        if np.median(start[big] / var[big]) > 0.5:
            return (f"{said}, most of it each window's start heading, fitted to position-only truth (σθ "
                    f"up to {np.sqrt(start[big].max()):.3g} rad at the start): shorter windows do not shrink "
                    "that; denser or less noisy fixes, or a truth with heading, do")
    return f"{said}; use shorter windows"


def first_order_horizon(t: ArrayLike, var_theta: ArrayLike) -> float | None:
    """How long [s from ``t[0]``] a track's first-order covariance holds: when its σθ first
    passes :data:`FIRST_ORDER_SIGMA_THETA`, from the poses' times ``t`` (N,) [s] and heading
    variances ``var_theta`` (N,) [rad²]; None where it never does.

    Examples
    --------
    >>> first_order_horizon([0.0, 1.0, 2.0], [0.0, 0.01, 0.09]), first_order_horizon([0.0, 1.0], [0.0, 0.01])
    (2.0, None)
    """
    times = np.asarray(t, dtype=float)
    big = np.sqrt(np.clip(np.asarray(var_theta, dtype=float), 0.0, None)) > FIRST_ORDER_SIGMA_THETA
    return float(times[int(np.argmax(big))] - times[0]) if big.any() else None


def first_order_track_note(t: ArrayLike, var_theta: ArrayLike, what: str = "the track's covariance",
                           test: str = "odomkit evaluate --window 10s") -> str | None:
    """The warning that a whole track's first-order covariance has passed
    :data:`FIRST_ORDER_SIGMA_THETA`, or None where its σθ stays within it.

    ``t`` (N,) [s] are the poses' times and ``var_theta`` (N,) [rad²] their heading
    variances; the note says from when on σθ passes the limit (the horizon over which the
    covariance still holds), its largest value and the final one. ``what`` names the
    covariance and ``test`` the windowed honesty test to use instead.

    Examples
    --------
    >>> first_order_track_note([0.0, 1.0, 2.0], [0.0, 0.01, 0.04]) is None
    True
    >>> first_order_track_note([0.0, 1.0, 2.0], [0.0, 0.01, 0.09])[:93]
    "the track's covariance passes the first-order limit: its σθ exceeds 0.2 rad from 2 s into the"
    """
    horizon = first_order_horizon(t, var_theta)
    if horizon is None:
        return None
    times = np.asarray(t, dtype=float)
    sigma = np.sqrt(np.clip(np.asarray(var_theta, dtype=float), 0.0, None))
    top = int(np.argmax(sigma))
    where = (" at the end" if top == sigma.size - 1 else
             f" ({float(times[top] - times[0]):.4g} s into the log; {sigma[-1]:.3g} rad at the end)")
    at_start = sigma[0] > FIRST_ORDER_SIGMA_THETA  # the start pose's own σθ is past it
    since, shorter = (("from the start (the start pose's own)", "shorter horizons") if at_start else
                      (f"from {horizon:.4g} s into the log on",
                       f"shorter horizons (here under {horizon:.3g} s)"))
    return (f"{what} passes the first-order limit: its σθ exceeds {FIRST_ORDER_SIGMA_THETA} rad {since} "
            f"and reaches {sigma[top]:.3g} rad{where}, so it is no longer a Gaussian claim about the pose: "
            "the linearised ellipse no longer describes where the robot is (the true spread bends along the "
            "arc the heading error sweeps, and the position ellipse is too small along the arc); judge the "
            f"noise with the windowed test ({test}) and trust the covariance over {shorter}")


_U_MAX = 1e14  # upper bound of a variance in units of its starting scale
_MAX_STEPS = 200
_TOL_LL = 1e-9  # log L gain that ends the iteration (intervals need ~1e-3)
_FLAT = 1e12  # an upper profile bound beyond this many times the scale is open
_TRIM_ROUNDS = 10  # trimming settles in 2-4 rounds on real data


@dataclass(frozen=True)
class NoiseParameter:
    """One variance parameter: ``models[model]``'s field ``name``.

    ``key`` names it in the output (the field name, or ``Class.field`` when two models
    share a field name); ``kind`` is its model's (white or bias); ``free`` whether it is
    fitted (else held at its model's value).
    """

    key: str
    model: int
    name: str
    kind: str
    free: bool

    @property
    def power(self) -> int:
        """2 when the value is a standard deviation (the variance its square), else 1."""
        return 2 if self.kind == "truth" else variance_power(self.name)

    def to_value(self, variance: float) -> float:
        """The model-unit value (σ, k or the variance itself) of a variance."""
        return float(np.sqrt(variance)) if self.power == 2 else float(variance)


def _zero_model(cls: type[NoiseModel]) -> NoiseModel | None:
    """The model with every numeric field zero (text fields at their default), or None."""
    kwargs = {}
    for f in fields(cls):  # type: ignore[arg-type]
        if not isinstance(f.default, str):
            kwargs[f.name] = 0.0
    try:
        return cls(**kwargs)
    except (TypeError, ModelError):
        return None


def _applies(model: NoiseModel, robot: Robot) -> bool:
    try:
        model.check_robot(robot)
    except ModelError:
        return False
    return True


def models_to_fit(robot: Robot, models: Sequence[NoiseModel], kinds: Collection[str]
                  ) -> tuple[tuple[NoiseModel, ...], frozenset[str]]:
    """The models a fit uses, and the fields held fixed by default.

    The given models (a robot file's ``[noise]``), plus, for each asked kind they lack, a
    default: white from :data:`DEFAULT_WHITE` (else every registered white model made for
    exactly this robot type); bias from the registered models whose all-zero instance is a
    bias model that applies to the robot, those made for this robot type preferred to
    those for any robot. A new model class plugs in by registering; nothing here changes.
    """
    out = list(models)
    fixed: set[str] = set()
    kind_name = robot.type_name
    if "white" in kinds and not any(m.kind == "white" for m in out):
        names = DEFAULT_WHITE.get(kind_name)
        if names is None:
            names = tuple(n for n, c in NOISE_MODELS.items() if c.robot_types == (kind_name,))
        made = [m for m in (_zero_model(NOISE_MODELS[n]) for n in names) if m is not None]
        made = [m for m in made if m.kind == "white" and _applies(m, robot)]
        if not made:
            raise ModelError(f"fit-noise has no default white noise for a {type(robot).__name__}; "
                             "name the models to fit in the robot file's [noise] table")
        out += made
        fixed |= DEFAULT_FIXED & {n for m in made for n in m.variance_parameters()}
    if "bias" in kinds and not any(m.kind == "bias" for m in out):
        made = [m for m in (_zero_model(c) for c in NOISE_MODELS.values()) if m is not None]
        made = [m for m in made if m.kind == "bias" and _applies(m, robot)]
        specific = [m for m in made if kind_name in m.robot_types]
        out += specific or made
    if not out:
        raise ModelError("no noise models to fit")
    NoiseSet.of(out).check_robot(robot)
    return tuple(out), frozenset(fixed)


def defaults_left_out(robot: Robot, models: Sequence[NoiseModel]) -> dict[str, tuple[str, ...]]:
    """The default white models (:data:`DEFAULT_WHITE`) a fit leaves out because the given
    models (a robot file's ``[noise]``) name white models of their own: class name -> its
    variance fields (what a robot file adds, at 0, to fit it). Empty where the given models
    name no white model (the defaults are then used) or all of the defaults."""
    if not any(m.kind == "white" for m in models):
        return {}
    have = {type(m).__name__ for m in models}
    out = {}
    for name in DEFAULT_WHITE.get(robot.type_name, ()):
        made = _zero_model(NOISE_MODELS[name]) if name in NOISE_MODELS else None
        if name not in have and made is not None and _applies(made, robot):
            out[name] = tuple(made.variance_parameters())
    return out


def noise_parameters(models: Sequence[NoiseModel], robot: Robot, kinds: Collection[str],
                     fixed: Collection[str] = ()) -> tuple[NoiseParameter, ...]:
    """Every variance parameter of ``models`` that applies to ``robot``: white ones first,
    then bias (the order of :func:`odomkit.window_errors.window_covariance_basis`); free when
    the model's kind is in ``kinds`` and the key or field is not in ``fixed``."""
    entries = []
    for kind in ("white", "bias"):
        for i, model in enumerate(models):
            if model.kind == kind:
                entries += [(i, name, kind) for name in model.variance_parameters(robot)]
    counts: dict[str, int] = {}
    for _, name, _ in entries:
        counts[name] = counts.get(name, 0) + 1
    out = []
    for i, name, kind in entries:
        key = name if counts[name] == 1 else f"{type(models[i]).__name__}.{name}"
        out.append(NoiseParameter(key, i, name, kind, kind in kinds and key not in fixed
                                  and name not in fixed))
    return tuple(out)


def _has_truth_columns(basis: WindowBasis) -> bool:
    """Whether ``basis`` carries the truth's own noise as its last white columns."""
    return basis.white_names[-len(TRUTH_NOISE):] == TRUTH_NOISE


def fit_parameters(bases: Sequence[WindowBasis], models: Sequence[NoiseModel], robot: Robot,
                   kinds: Collection[str], fixed: Collection[str] = ()) -> tuple[NoiseParameter, ...]:
    """The parameters of a fit on ``bases``: :func:`noise_parameters`, and, where the bases
    carry the truth's own noise (:data:`odomkit.window_errors.TRUTH_NOISE`, ``truth_columns``),
    ``truth_sigma`` [m], ``truth_heading_sigma`` [rad] and ``truth_time_sigma`` [s]
    between the white and the bias ones (the bases' column order), kind ``"truth"``: free
    unless named in ``fixed`` or their columns are zero in every window (no truth heading
    anywhere; a robot that never moves at a window's ends)."""
    params = noise_parameters(models, robot, kinds, fixed)
    used = [b for b in bases if len(b.windows)]
    if not used or not _has_truth_columns(used[0]):
        return params
    q = len(used[0].white_names)
    truth = []
    for k, (_, name) in enumerate(TRUTH_NOISE):
        column = q - len(TRUTH_NOISE) + k
        seen = any(np.any(b.white[:, column]) for b in used)
        truth.append(NoiseParameter(name, -1, name, "truth", seen and name not in fixed))
    n_white = sum(p.kind == "white" for p in params)
    return params[:n_white] + tuple(truth) + params[n_white:]


@dataclass(frozen=True)
class NoiseFit:
    """Result of :func:`fit_noise` (values in each model's own units).

    ``parameters`` and ``interval`` hold the free parameters by key (interval upper bound
    ``inf`` when the data cannot bound it); ``variances`` every parameter's variance;
    ``models`` the fitted noise models; ``per_log`` each log's windows, eᵀΣ⁻¹e, its
    degrees of freedom and two-sided p-value; ``truth_noise`` the truth's own noise
    {``truth_sigma`` [m], ``truth_heading_sigma`` [rad], ``truth_time_sigma`` [s]}, fitted
    or held, where the fit
    had it (None otherwise): the honesty test adds it to every window end
    (``odomkit evaluate``), the robot's own covariance does not.
    """

    parameters: dict[str, float]
    interval: dict[str, tuple[float, float]]
    variances: dict[str, float]
    kinds: dict[str, str]
    models: tuple[NoiseModel, ...]
    level: float
    log_likelihood: float
    windows: int
    logs: int
    coverage_in_sample: dict[str, float | None]
    correlation: dict[str, dict[str, float]]
    per_log: list[dict[str, float | int | str]]
    warnings: list[str] = field(default_factory=list)
    cross_validation: dict[str, object] | None = None
    trimmed: int = 0
    trim: float | None = None
    truth_noise: dict[str, float] | None = None
    truth_held: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {
            "parameters": self.parameters,
            "interval95" if self.level == 0.95 else f"interval{100 * self.level:g}":
                {k: list(v) for k, v in self.interval.items()},
            "variances": self.variances, "kinds": self.kinds, "level": self.level,
            "windows": self.windows, "logs": self.logs, "log_likelihood": self.log_likelihood,
            "coverage_in_sample": self.coverage_in_sample, "correlation": self.correlation,
            "warnings": self.warnings, "per_log": self.per_log,
            "trim": self.trim, "windows_trimmed": self.trimmed, "truth_noise": self.truth_noise,
        }
        if self.cross_validation is not None:
            out["cross_validation"] = self.cross_validation
        return out


class _Problem:
    """log L over the free parameters, maximised by Newton steps projected on v ≥ 0.

    Each step solves J Δ = g over the parameters not held at zero by the bound, clips at
    zero and halves until log L does not decrease. J is the observed information where
    it is positive definite, else the average information (Gilmour, Thompson and Cullis
    1995), always positive semi-definite; both and g are in closed form
    (:class:`WindowLikelihood`), so a fit takes a handful of evaluations. (Fisher
    scoring, with the expected information, converged linearly here, 15–20 steps; scipy's
    L-BFGS-B was ten times slower on a busy machine, its BLAS threads contending with the
    likelihood's numpy calls.)
    """

    def __init__(self, lik: WindowLikelihood, v0: NDArray[np.float64], free: NDArray[np.intp],
                 scale: NDArray[np.float64]):
        self.lik, self.v0, self.free, self.scale = lik, v0, free, scale

    def maximise(self, base: NDArray[np.float64], idx: NDArray[np.intp],
                 start: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
        """Maximise over v[idx] from v[idx] = ``start``, the other entries as in ``base``."""
        v = base.copy()
        v[idx] = np.maximum(start, 0.0)
        val = self.lik(v, information=idx.size > 0)
        if idx.size == 0 or val.gradient is None:
            # No gradient: the window covariances are not positive definite at this start
            # (log L = -inf, e.g. a starting variance that overflowed); the caller decides.
            return v, val.loglik
        s = self.scale[idx]
        for _ in range(_MAX_STEPS):
            assert val.gradient is not None and val.average is not None
            assert val.information is not None
            g = val.gradient[idx] * s
            both = np.ix_(idx, idx)
            outer = s[:, None] * s[None, :]
            u = v[idx] / s
            move = ~((u <= 0.0) & (g <= 0.0))  # a variance at zero that would go negative stays
            step = np.zeros_like(u)
            if move.any():
                mm = np.ix_(move, move)
                # The observed information 2A − I where it is positive definite (Newton:
                # quadratic convergence), else the average information A.
                observed = ((2.0 * val.average - val.information)[both] * outer)[mm]
                eig = np.linalg.eigvalsh(observed)
                if eig[0] > 1e-10 * max(eig[-1], 1e-300):
                    step[move] = np.linalg.solve(observed, g[move])
                else:
                    step[move] = np.linalg.pinv((val.average[both] * outer)[mm], rcond=1e-12) @ g[move]
            t, accepted, gain = 1.0, None, 0.0
            while t > 1e-12:
                trial = v.copy()
                trial[idx] = s * np.minimum(np.maximum(u + t * step, 0.0), _U_MAX)
                gain = self.lik(trial, gradient=False).loglik - val.loglik
                if gain >= 0.0:
                    accepted = trial
                    break
                t *= 0.5
            if accepted is None:
                break
            change = np.max(np.abs(accepted[idx] - v[idx]) / s / (1.0 + u))
            v = accepted
            val = self.lik(v, information=True)
            if gain <= _TOL_LL and change < 1e-6:
                break
        return v, val.loglik


def _scales(lik: WindowLikelihood, free: NDArray[np.intp]) -> NDArray[np.float64]:
    """A starting variance per parameter: the one that alone would explain the errors,
    shared among the free parameters (geometric mean over the observed components)."""
    e2 = np.sum(lik.error**2, axis=0)
    fixed, white, sens = lik.raw
    diag = np.concatenate([np.einsum("wjaa->ja", white),
                           lik.weights @ np.einsum("wac,wac->ca", sens, sens)])
    obs = lik.observed.any(axis=0)
    scale = np.ones(lik.n_params)
    for j in range(lik.n_params):
        ok = obs & (diag[j] > 0) & (e2 > 0)
        if ok.any():
            scale[j] = float(np.exp(np.mean(np.log(e2[ok] / diag[j, ok])))) / max(free.size, 1)
    return scale


class _Irregular(Exception):
    """The profile likelihood of a parameter does not behave: it does not reach the fit's own
    value near the fit, or its bracket does not cross the interval's level."""


def _crossing(gap: Callable[[float], float], lo_x: float, hi_x: float) -> float:
    """Where ``gap`` changes sign between lo_x and hi_x, by bisection on log v."""
    try:
        return float(np.exp(brentq(lambda y: gap(float(np.exp(y))), np.log(lo_x), np.log(hi_x), xtol=1e-4)))
    except ValueError:  # no sign change: the profile is not what the fit assumed
        raise _Irregular from None


def _profile_interval(prob: _Problem, v_hat: NDArray[np.float64], ll_hat: float, j: int,
                      crit: float) -> tuple[float, float]:
    """Profile-likelihood interval of v_j (variances); :class:`_Irregular` where the
    profile does not reach the fit's own log-likelihood at the fit (the fit sits on a
    spike of the likelihood that the profile's own maximisation does not find again)."""
    others = np.array([i for i in prob.free if i != j], dtype=np.intp)
    target = ll_hat - 0.5 * crit

    def gap(x: float) -> float:
        base = v_hat.copy()
        base[j] = x
        _, ll = prob.maximise(base, others, v_hat[others])
        return ll - target  # ≥ 0 inside the interval

    s = prob.scale[j]
    start = v_hat[j] if v_hat[j] > 0 else s * 1e-6
    if not gap(start) >= 0:
        raise _Irregular
    # Upper bound: grow by ×10 until outside, then bisect on log v.
    lo_x, hi_x, upper = start, start, float("inf")
    while hi_x < s * _FLAT:
        lo_x, hi_x = hi_x, hi_x * 10.0
        if gap(hi_x) < 0:
            upper = _crossing(gap, lo_x, hi_x)
            break
    if v_hat[j] == 0 or gap(0.0) >= 0:
        return 0.0, upper
    hi_x = v_hat[j]
    while True:
        lo_x = hi_x / 10.0
        if gap(lo_x) < 0:
            break
        hi_x = lo_x
        if hi_x < v_hat[j] * 1e-12:
            return 0.0, upper
    return _crossing(gap, lo_x, hi_x), upper


def _correlation(prob: _Problem, v_hat: NDArray[np.float64], idx: NDArray[np.intp]
                 ) -> NDArray[np.float64]:
    """Correlation of the estimates of v[idx] from the expected (Fisher) information at
    the fit (pseudo-inverse: a direction the data do not inform gives ±1, not an error).
    It is a property of the design (which directions the windows inform), so parameters
    fitted to zero take part too."""
    info = prob.lik(v_hat, information=True).information
    assert info is not None
    sub = info[np.ix_(idx, idx)]
    d = np.sqrt(np.clip(np.diag(sub), 1e-300, None))
    cov = np.linalg.pinv(sub / d[:, None] / d[None, :], rcond=1e-12, hermitian=True)
    e = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    return np.clip(cov / e[:, None] / e[None, :], -1.0, 1.0)


def fit_noise(
    bases: Sequence[WindowBasis],
    models: Sequence[NoiseModel],
    robot: Robot,
    *,
    kinds: Collection[str] = ("white",),
    fixed: Collection[str] = (),
    level: float = 0.95,
    log_names: Sequence[str] | None = None,
    cross_validate: bool = False,
    trim: float | None = None,
    truth_held: Mapping[str, float] | None = None,
    window_labels: Sequence[Sequence[str]] | None = None,
    truth_scatter: float | None = None,
    window_lengths: Sequence[Sequence[str]] | None = None,
) -> NoiseFit:
    """Maximum-likelihood variances of ``models`` from the window bases of several logs.

    A building block, with a building block's defaults: no trimming (``trim=None``), white
    noise alone (``kinds=("white",)``), and the truth's noise fitted only where the bases
    carry it as columns (:func:`odomkit.window_errors.log_window_basis`'s ``truth_columns``,
    False by default). ``odomkit fit-noise``'s defaults differ (trim :data:`DEFAULT_TRIM`,
    white and bias, the truth's noise fitted, :data:`DEFAULT_FIXED` held): for logs in memory
    they are :func:`odomkit.workflows.fit_noise.fit_noise_in_memory`, which gives the
    command's result; chained by hand with these defaults the fit is another, far more
    cautious model.

    Parameters
    ----------
    bases : sequence of WindowBasis
        One per log, from :func:`odomkit.window_errors.window_covariance_basis` with ``models``.
    models : sequence of NoiseModel
        The models (:func:`models_to_fit`); parameters not fitted keep their value.
    robot : Robot
    kinds : collection of {"white", "bias"}
        Which models' parameters are fitted.
    fixed : collection of str
        Parameter keys (or field names) held at their model's value.
    level : float
        Confidence level of the profile-likelihood intervals.
    log_names : sequence of str, optional
        Names of the logs for ``per_log`` and warnings.
    cross_validate : bool
        Also refit without each log in turn and score that log (leave-one-log-out
        coverage).
    trim : float in (0.5, 1), optional
        Fit the bulk of the windows, not their tails: window ends outside the ``trim``
        ellipse of the current fit (eᵀΣ⁻¹e above the χ² quantile ``trim`` of its observed
        components, marginal over the bias) are left out and the fit repeated until the
        set stops changing (a trimmed likelihood; Neykov et al. 2007). Real odometry
        errors have heavy tails (a bump, a slip, a truth glitch): a few such windows
        inflate a Gaussian fit until most windows over-cover. The left-out windows are
        counted (``trimmed``), named in a warning, and still scored in
        ``coverage_in_sample``. None: every window (``odomkit fit-noise`` uses :data:`DEFAULT_TRIM`).
    truth_held : mapping, optional
        Where the bases carry the truth's own noise (``truth_columns``): those of
        ``truth_sigma`` [m], ``truth_heading_sigma`` [rad] and ``truth_time_sigma`` [s]
        held at the given value (the user knows them, e.g. a GPS's σ); the others are
        fitted. Without truth columns the truth's noise is the bases' fixed part and this
        must be empty.
    window_labels : one sequence per basis of one label per window, optional
        How warnings name a window (``"a.csv 1266.7-1276.8 s"``); default the log's name and
        the window's number.
    window_lengths : one sequence per basis of each window's length, optional
        The ``--window`` length each window was cut at (``"10 s"``): the leave-one-out
        coverage is also given per length (``cross_validation["by_length"]``), where the
        pooled figure can hide a length that fails (a user study's tricycle: 0.886 pooled,
        its 2 m windows 0.758 held out).
    truth_scatter : float, optional
        How the truth's fixes scatter about a smooth path [m per axis]
        (:func:`odomkit.truth.scatter_sigma`), for two warnings: where every noise parameter
        of the robot's own models is fitted to zero, a held ``truth_sigma`` more than
        :data:`GIVEN_ABOVE_SCATTER` times it may be too large; and a fitted ``truth_sigma``
        more than :data:`FITTED_ABOVE_SCATTER` times it is not the truth's white noise.

    Returns
    -------
    NoiseFit
    """
    if not 0 < level < 1:
        raise ModelError(f"level must be in (0, 1), got {level}")
    if trim is not None and not 0.5 < trim < 1:
        raise ModelError(f"trim must be in (0.5, 1), got {trim}")
    held = dict(truth_held or {})
    names_of_truth = [name for _, name in TRUTH_NOISE]
    if set(held) - set(names_of_truth):
        raise ModelError(f"truth_held names {sorted(set(held) - set(names_of_truth))}; expected some of "
                         f"{names_of_truth}")
    with_windows = [b for b in bases if len(b.windows)]
    if held and with_windows and not any(_has_truth_columns(b) for b in with_windows):
        raise ModelError("truth_held needs bases with the truth's noise as columns (truth_columns=True)")
    params = fit_parameters(bases, models, robot, kinds, set(fixed) | set(held))
    names = list(log_names) if log_names is not None else [f"log {i}" for i in range(len(bases))]
    used = [i for i, b in enumerate(bases) if len(b.windows)]
    everything = WindowLikelihood([bases[i] for i in used])
    if everything.n_params != len(params):
        raise ModelError("the bases do not belong to these noise models")
    free = np.array([k for k, p in enumerate(params) if p.free], dtype=np.intp)
    if free.size == 0:
        raise ModelError("nothing to fit: no free noise parameter of the asked kinds")
    observed = int(np.sum(everything.nobs))
    if observed <= free.size:
        # Each window end gives 2 numbers (3 with a truth heading): no more numbers than
        # variances leaves the likelihood flat in some direction, whatever it prints.
        # Fewer kinds only where both were asked for: a user study was told "or fit fewer kinds
        # (--kinds white)" after giving --kinds white.
        fewer = ", or fit fewer kinds (--kinds white)" if {"white", "bias"} <= set(kinds) else ""
        raise InputError(f"{everything.n_windows} window(s) give {observed} numbers for {free.size} free "
                         "noise parameter(s): the fit is undetermined; use shorter windows or more "
                         f"logs{fewer}")
    v0 = np.array([held.get(p.name, 0.0) ** 2 if p.kind == "truth"
                   else models[p.model].variance_parameters()[p.name] for p in params])
    lik = everything
    prob, v_hat, ll_hat = _solve(lik, v0, free, None)
    all_used = list(used)
    kept_bases: dict[int, WindowBasis] = {i: bases[i] for i in used}
    trimmed: dict[int, int] = {}
    if trim is not None and np.isfinite(ll_hat):
        kept = np.ones(everything.n_windows, dtype=bool)
        for _ in range(_TRIM_ROUNDS):
            inside = everything.inside(v_hat, trim)
            if np.array_equal(inside, kept):
                break
            kept = inside
            pieces = np.split(kept, everything.starts[1:])
            kept_bases = {i: bases[i].select(k) for i, k in zip(all_used, pieces, strict=True)}
            trimmed = {i: int((~k).sum()) for i, k in zip(all_used, pieces, strict=True) if not k.all()}
            used = [i for i in all_used if len(kept_bases[i].windows)]
            if not used:
                raise ModelError("trimming left no windows: the errors are far larger than any "
                                 "noise model can explain; check the units of the log and the truth")
            lik = WindowLikelihood([kept_bases[i] for i in used])
            prob, v_hat, ll_hat = _solve(lik, v0, free, v_hat)
    if not np.isfinite(ll_hat):
        # Errors against the truth of 1e195 m square to inf: the starting variances overflow
        # and no start gives positive definite window covariances.
        raise ModelError("the noise fit: the window covariances are not positive definite at any "
                         "starting variance (errors against the truth up to "
                         f"{float(np.max(np.abs(lik.error))):.3g}); check the units of the log and "
                         "the truth")
    crit = float(chi2.ppf(level, 1))
    intervals: dict[int, tuple[float, float]] = {}
    irregular = []
    for j in free:
        try:
            intervals[int(j)] = _profile_interval(prob, v_hat, ll_hat, int(j), crit)
        except _Irregular:
            intervals[int(j)] = (0.0, float("inf"))
            irregular.append(params[int(j)].key)
    warnings: list[str] = []
    if irregular:
        warnings.append(f"no profile-likelihood interval for {', '.join(irregular)}: the likelihood is not "
                        "regular there (a spike or ridge; too few windows per log for the bias and truth "
                        "terms?), shown as 0 .. inf; fit more logs, longer ones, or hold some terms (--fix, "
                        "--truth-sigma)")
    flat = [j for j in free if not np.isfinite(intervals[int(j)][1]) and params[int(j)].key not in irregular]
    for j in flat:
        v_hat[j] = v0[j]  # the data say nothing: keep the robot file's value
    cov = lik.window_covariance(v_hat)
    val = lik(v_hat, gradient=False)
    n_trimmed = sum(trimmed.values())
    # Every window end (trimmed ones too) under the fit: its position eᵀΣ⁻¹e and its label.
    every_cov = everything.window_covariance(v_hat)[:, :2, :2]
    in_sample = coverage(everything.error[:, :2], every_cov)
    end_nees = nees(everything.error[:, :2], every_cov)
    labels = [label for i in all_used for label in (
        window_labels[i] if window_labels is not None
        else [f"{names[i]} window {k + 1}" for k in range(len(bases[i].windows))])]
    if n_trimmed:
        worst = sorted(trimmed.items(), key=lambda item: -item[1])[:3]
        warnings.append(
            f"{n_trimmed} of {everything.n_windows} window ends lie outside the {100 * (trim or 1.0):g} % "
            f"ellipse of the fit and were left out of it (heavy tails; most in "
            + ", ".join(f"{names[i]} ({n})" for i, n in worst)
            + "): expect coverage at 99 % below 0.99 on new runs"
            + _trim_share_note(n_trimmed, everything.n_windows, trim or 1.0, end_nees, labels))
    # Every robot parameter at zero: the truth's noise explains every window end, and the
    # file written predicts no growth of the odometry's error (a user study's RAV4, GPS truth).
    at_zero = _robot_at_zero(params, free, v_hat, everything)
    truth_now = _truth_text(params, v_hat, held)
    given = _truth_text(params, v_hat, held, given_only=True) if at_zero else ""
    misfit = _in_sample_note(in_sample, end_nees, labels, models, trimmed=n_trimmed, given_truth=given)
    if misfit:
        warnings.append(misfit)
    if at_zero:
        warnings.append(_no_growth_note(params, v_hat, held, everything, every_cov, truth_now, truth_scatter))
    fitted_sigma = [params[j].to_value(float(v_hat[j])) for j in free
                    if params[j].kind == "truth" and params[j].name == "truth_sigma" and j not in flat]
    if fitted_sigma and (above := _fitted_above_scatter(fitted_sigma[0], truth_scatter)):
        warnings.append(above)
    informed = np.array([j for j in free if j not in flat], dtype=np.intp)
    corr = _correlation(prob, v_hat, informed) if informed.size > 1 else np.eye(informed.size)
    keys = [p.key for p in params]
    # Only what the data fitted is judged: a value held or kept at the robot file's is the user's.
    warnings += implausible_values([(params[j].key, params[j].name, params[j].kind,
                                     params[j].to_value(float(v_hat[j]))) for j in free if j not in flat],
                                   robot, [w for i in used for w in kept_bases[i].windows])
    _warn(warnings, lik, params, free, intervals, flat, informed, corr, cov, val.quad,
          [names[i] for i in used], bases=[kept_bases[i] for i in used])
    floor = _floor_note([kept_bases[i] for i in used], v_hat, params, free)
    if floor:
        warnings.append(floor)
    fitted = []
    for i, model in enumerate(models):
        mine = {p.name: float(v_hat[k]) for k, p in enumerate(params) if p.model == i}
        fitted.append(model.from_variances(mine) if mine else model)
    per_log: list[dict[str, float | int | str]] = []
    for k, i in enumerate(used):
        dof = int(lik.nobs[k])
        per_log.append({"log": names[i], "windows": len(kept_bases[i].windows), "quad": float(val.quad[k]),
                        "dof": dof, "p_value": _two_sided(float(val.quad[k]), dof)})
    cv = (_cross_validate(prob, v_hat, kept_bases, bases, used, params, window_lengths) if cross_validate
          else None)
    if cross_validate and cv is None:
        warnings.append("cross-validation needs at least two logs with windows")
    return NoiseFit(
        parameters={keys[j]: params[j].to_value(v_hat[j]) for j in free},
        interval={keys[j]: (params[j].to_value(intervals[int(j)][0]),
                            params[j].to_value(intervals[int(j)][1])) for j in free},
        variances={keys[k]: float(v_hat[k]) for k in range(len(params))},
        kinds={p.key: p.kind for p in params},
        models=tuple(fitted), level=level, log_likelihood=float(val.loglik),
        windows=lik.n_windows, logs=lik.n_logs,
        coverage_in_sample=in_sample,
        trimmed=n_trimmed, trim=trim,
        truth_noise={p.key: p.to_value(v_hat[k]) for k, p in enumerate(params) if p.kind == "truth"} or None,
        truth_held=tuple(held),
        correlation={keys[a]: {keys[b]: float(corr[x, y]) for y, b in enumerate(informed)}
                     for x, a in enumerate(informed)},
        per_log=per_log, warnings=warnings, cross_validation=cv,
    )


#: Trimming more than this share of the window ends is no rare tail (an honest model leaves
#: out 1 − trim of them: 0.1 % at the default 0.999): a user study's fits trimmed 12 to 27 %.
TRIM_SHARE = 0.05
#: How many of the largest window ends a misfit warning names.
_WORST_SHOWN = 3


def _largest(end_nees: NDArray[np.float64], labels: Sequence[str]) -> str:
    """The window ends of largest position eᵀΣ⁻¹e, named (``"a.csv 10-20 s (38.2)"``)."""
    finite = np.where(np.isfinite(end_nees), end_nees, -np.inf)
    order = np.argsort(-finite, kind="stable")[:_WORST_SHOWN]
    return ", ".join(f"{labels[k]} ({end_nees[k]:.3g})" for k in order if np.isfinite(end_nees[k]))


def _trim_share_note(n_trimmed: int, n: int, trim: float, end_nees: NDArray[np.float64],
                     labels: Sequence[str]) -> str:
    """What trimming more than :data:`TRIM_SHARE` of the ends means (appended to the trim
    warning; empty otherwise): no rare tail, where an honest model leaves out 1 − ``trim``
    of them and, in 97.5 % of fits, no more than its binomial point."""
    if n_trimmed <= TRIM_SHARE * n:
        return ""
    _, most = coverage_range(n, 1.0 - trim)
    return (f"; trimming {100 * n_trimmed / n:.3g} % of the ends is no rare tail (an honest model leaves out "
            f"{100 * (1 - trim):.2g} %, at most {round(most * n)} of {n} in 97.5 % of fits): the model "
            "family does not describe these logs, and the trimmed fit describes their bulk only; the "
            f"largest eᵀΣ⁻¹e (2 on average for an honest model): {_largest(end_nees, labels)}")


def _in_sample_note(in_sample: dict[str, float | None], end_nees: NDArray[np.float64], labels: Sequence[str],
                    models: Sequence[NoiseModel], trimmed: int, given_truth: str = "") -> str | None:
    """The warning where the fit's own in-sample coverage lies outside the range an honest
    model's falls in over this many window ends (:func:`odomkit.evaluate.coverage_range`):
    a fit that misses on the very windows it was fitted to has a model family that does not
    describe these logs. Names the window ends of largest eᵀΣ⁻¹e. (The range assumes
    independent ends; windows of several lengths overlap, so it is a little narrow there.)

    ``given_truth`` (:func:`_truth_text` of the truth noise held), where every robot
    parameter is fitted to zero: a pessimistic fit is then the truth's noise as given, too
    large for these ends, and the warning names that instead of the model family."""
    n = int(np.count_nonzero(np.isfinite(end_nees)))
    verdicts = coverage_verdicts(in_sample, n)
    overall = overall_verdict(verdicts)
    if overall in (None, "consistent"):
        return None
    off = [k for k, v in verdicts.items() if v not in (None, "consistent")]
    ranges = ", ".join(f"{100 * float(k):g} % {in_sample[k]:.3f} against {lo:.3f}..{hi:.3f}"
                       for k in off for lo, hi in [coverage_range(n, float(k))])
    family = ", ".join(dict.fromkeys(type(m).__name__ for m in models))
    what = {"optimistic": "too small", "pessimistic": "too large",
            "mixed": "too large in the core and too small in the tails"}[overall]
    kept = " (trimmed ends included)" if trimmed else ""
    if overall == "pessimistic" and given_truth:
        return (f"in-sample coverage misses the range an honest model's falls in over {n} window ends"
                f"{kept}: {ranges}; the fitted covariance is too large (pessimistic) on the very windows it "
                "was fitted to, with every noise parameter of the robot's own models at zero: what is left "
                f"is the truth's noise as given ({given_truth}), too large for these window ends' errors, so "
                "the σ given is likely too large (give a smaller one, or leave it out and fit-noise fits it)")
    return (f"in-sample coverage misses the range an honest model's falls in over {n} window ends{kept}: "
            f"{ranges}; the fitted covariance is {what} ({overall}) on the very windows it was fitted to, so "
            f"the model family ({family}) does not describe these logs; the largest eᵀΣ⁻¹e (2 on average "
            f"for an honest model): {_largest(end_nees, labels)}: look at those windows (a turn the odometry "
            "misses, a wheel slipping, a jump in the truth)")


#: A held ``truth_sigma`` more than this many times the fixes' own scatter about a smooth path
#: (:func:`odomkit.truth.scatter_sigma`) is called possibly too large where the robot's noise is
#: fitted to zero: that scatter comes back within 5 % of white noise's σ and a bending path only
#: adds to it, so twice it is no estimate's error (a RAV4's u-blox fixes scatter 0.088 m: its
#: --truth-sigma 0.09 is not called too large, 0.5 is).
GIVEN_ABOVE_SCATTER = 2.0
#: A fitted ``truth_sigma`` more than this many times the fixes' own scatter about a smooth path
#: (:func:`odomkit.truth.scatter_sigma`) is called no white noise of the truth's. That scatter
#: comes back within 5 % of white noise's σ (:data:`GIVEN_ABOVE_SCATTER`); a fitted σ has its own
#: estimate error too, a few tens of per cent from tens of window ends, so the factor is larger
#: than a given σ's: five times is neither estimate's error (a user study's F1TENTH car fitted 8.2
#: mm against its motion capture's 0.32 mm, 26 times).
FITTED_ABOVE_SCATTER = 5.0
#: The robot's noise is "at zero" where its share of the predicted position variance at the
#: window ends is below this: no growth a track's covariance would show.
_AT_ZERO = 1e-9
#: What each truth-noise parameter is given by, and its unit.
_TRUTH_FLAGS = {"truth_sigma": ("--truth-sigma", "m"),
                "truth_heading_sigma": ("--truth-heading-sigma", "rad"),
                "truth_time_sigma": ("--truth-time-sigma", "s")}


def _robot_at_zero(params: Sequence[NoiseParameter], free: NDArray[np.intp], v_hat: NDArray[np.float64],
                   lik: WindowLikelihood) -> bool:
    """Whether every variance of the robot's own models (white and bias; the truth's aside,
    held ones included) is zero at the fit, some of them fitted: their share of the predicted
    position variance at ``lik``'s window ends is under :data:`_AT_ZERO`."""
    robot = np.array([k for k, p in enumerate(params) if p.kind != "truth"], dtype=np.intp)
    if not robot.size or not any(params[int(j)].kind != "truth" for j in free):
        return False
    without = v_hat.copy()
    without[robot] = 0.0
    total = float(np.trace(lik.window_covariance(v_hat)[:, :2, :2], axis1=1, axis2=2).sum())
    truth = float(np.trace(lik.window_covariance(without)[:, :2, :2], axis1=1, axis2=2).sum())
    return not total - truth > _AT_ZERO * total


def _truth_text(params: Sequence[NoiseParameter], v_hat: NDArray[np.float64], held: Mapping[str, float],
                given_only: bool = False) -> str:
    """The truth's noise at the fit, each nonzero term with its unit and whether it was given
    or fitted (``"truth_sigma 0.5 m, given"``); ``given_only``: the given ones alone. Empty
    where there is none."""
    said = []
    for k, p in enumerate(params):
        if p.kind != "truth" or not v_hat[k] > 0 or (given_only and p.name not in held):
            continue
        unit = _TRUTH_FLAGS.get(p.name, ("", ""))[1]
        how = "given" if p.name in held else "fitted"
        said.append(f"{p.key} {p.to_value(float(v_hat[k])):.3g} {unit}, {how}")
    return "; ".join(said)


def _no_growth_note(params: Sequence[NoiseParameter], v_hat: NDArray[np.float64], held: Mapping[str, float],
                    lik: WindowLikelihood, cov: NDArray[np.float64], truth: str,
                    scatter: float | None) -> str:
    """The warning where every noise parameter of the robot's own models is fitted to zero
    (:func:`_robot_at_zero`): the window ends' errors (``lik``'s, RMS per axis) lie within
    the truth's own noise (``truth``: :func:`_truth_text`), which alone predicts the position
    covariances ``cov`` (W, 2, 2) [m²] there, so the file written predicts no growth of the
    odometry's error; what to do, and, where a held ``truth_sigma`` is more than
    :data:`GIVEN_ABOVE_SCATTER` times the fixes' ``scatter`` [m], that it may be too large."""
    keys = ", ".join(p.key for p in params if p.kind != "truth" and p.free)
    rms = float(np.sqrt(np.mean(np.square(lik.error[:, :2]))))
    predicted = float(np.sqrt(np.mean(np.trace(cov, axis1=1, axis2=2)) / 2.0))
    # Position-only truth: each window's start heading is fitted to the fixes, and their noise
    # reaches the end through it too (a car's 10 s on a highway: 0.09 m fixes predict 1.5 m).
    through = ("" if lik.observed[:, 2].any() else
               " (at each window's two ends, and through its start heading, fitted to the fixes)")
    flags = [_TRUTH_FLAGS[name][0] for name, value in held.items() if value > 0 and name in _TRUTH_FLAGS]
    smaller = (f", or give a smaller {' / '.join(flags)} (or none: fit-noise then fits the truth's noise)"
               if flags else "")
    note = (f"every noise parameter of the robot's own models is fitted to zero ({keys}): the window ends' "
            f"errors (RMS {rms:.3g} m per axis over {lik.n_windows} ends) lie within the truth's own noise "
            f"({truth or 'the fixed part of each window end'}), which alone predicts {predicted:.3g} m "
            f"per axis there{through}, so the file written predicts no growth of the odometry's error: a "
            "track's covariance is then its start pose's alone, however far it drives; fit longer windows "
            f"(--window 30s) or more logs, so that the odometry's error outgrows the truth's noise{smaller}")
    sigma = held.get("truth_sigma")
    if sigma is not None and scatter is not None and scatter > 0 and sigma > GIVEN_ABOVE_SCATTER * scatter:
        note += (f"; the truth_sigma given ({sigma:.3g} m) is {sigma / scatter:.2g} times the scatter of "
                 f"the truth's fixes about a smooth path ({scatter:.3g} m per axis, "
                 "odomkit.truth.scatter_sigma): the stated σ may be too large")
    return note


def _fitted_above_scatter(sigma: float, scatter: float | None) -> str | None:
    """The warning where the fitted ``truth_sigma`` [m] is more than
    :data:`FITTED_ABOVE_SCATTER` times the fixes' ``scatter`` [m per axis] about a smooth path,
    else None: the scatter measures their white noise, so the truth-noise parameter has taken
    up something else that does not grow with a window's length."""
    if scatter is None or not scatter > 0 or not sigma > FITTED_ABOVE_SCATTER * scatter:
        return None
    return (f"the fitted truth_sigma ({sigma:.3g} m) is {sigma / scatter:.2g} times the scatter of the "
            f"truth's own fixes about a smooth path ({scatter:.3g} m per axis, odomkit.truth.scatter_sigma), "
            "which measures their white noise within a few per cent: it is not the truth's white noise but "
            "something at each window end that does not grow with the window and that the fit could put "
            "nowhere else: an error of the truth's that is correlated in time (a GPS's multipath, a motion "
            "capture's calibration), which that scatter misses; the odometry's own short-term error; or a "
            "clock's jitter between the truth and the log. It goes to the written file's [truth] sigma, "
            "which evaluate and report add to every window end they score but track, predict and the ROS "
            "parameters leave out: where it is the odometry's own error, their covariance lacks it. To "
            f"tell, hold the truth's σ at the fixes' scatter (--truth-sigma {scatter:.3g}) and fit again: "
            "what then moves into the robot's noise is the odometry's")


def _solve(lik: WindowLikelihood, v0: NDArray[np.float64], free: NDArray[np.intp],
           warm: NDArray[np.float64] | None) -> tuple[_Problem, NDArray[np.float64], float]:
    """Maximise ``lik`` over v[free] from two scaled starts (and ``warm``, a previous fit)."""
    prob = _Problem(lik, v0, free, _scales(lik, free))
    starts = [prob.scale[free], 0.1 * prob.scale[free]]
    if warm is not None:
        starts.append(warm[free])
    best = None
    for start in starts:
        cand = prob.maximise(v0, free, start)
        if best is None or cand[1] > best[1]:
            best = cand
    assert best is not None
    return prob, best[0], best[1]


def _two_sided(quad: float, dof: int) -> float:
    return float(min(1.0, 2.0 * min(chi2.cdf(quad, dof), chi2.sf(quad, dof))))


def _warn(out: list[str], lik: WindowLikelihood, params: Sequence[NoiseParameter],
          free: NDArray[np.intp], intervals: dict[int, tuple[float, float]], flat: list[int],
          informed: NDArray[np.intp], corr: NDArray[np.float64], cov: NDArray[np.float64],
          quad: NDArray[np.float64], names: Sequence[str], bases: Sequence[WindowBasis]) -> None:
    turning = np.concatenate([b.turning for b in bases])
    mean_turn = float(np.mean(turning)) if turning.size else 0.0
    hint = (f" (too little turning: the windows turn {mean_turn:.2g} rad each on average)"
            if mean_turn < 0.5 else "")
    n_free = int(free.size)
    if lik.n_windows < max(10, 5 * n_free):
        out.append(f"too few windows ({lik.n_windows}) for {n_free} free parameter(s): the "
                   "intervals rest on large-sample theory; use more logs or shorter windows")
    if any(params[j].kind == "bias" for j in free) and lik.n_logs < 5:
        out.append(f"bias variances rest on {lik.n_logs} log(s) or robot(s) (--group): each draws its "
                   "bias once, so they are weakly determined; fit more logs, from more robots")
    for j in flat:
        out.append(f"{params[j].key} is not identifiable from these data (the likelihood does "
                   f"not bound it){hint}; kept at its robot-file value")
    for x in range(informed.size):
        for y in range(x + 1, informed.size):
            if abs(corr[x, y]) > CONFOUNDED_CORRELATION:
                a, b = params[informed[x]].key, params[informed[y]].key
                out.append(f"{a} and {b} are not separately identifiable (correlation "
                           f"{corr[x, y]:+.3f}){hint}")
    note = first_order_note(cov[:, 2, 2], lik.raw[0][:, 2, 2])  # raw[0]: the start's share and the truth's
    if note:
        out.append(note)
    p = np.array([_two_sided(float(q), int(n)) for q, n in zip(quad, lik.nobs, strict=True)])
    bad = np.flatnonzero(p < 0.01 / max(len(p), 1))
    if len(p) > 1 and bad.size:
        # Which way each one errs: above 1 its errors are larger than the fit says (the fit is
        # optimistic for it), below 1 smaller (pessimistic); a user study read "disagree" as
        # "worse" where three of four named logs were too good.
        shown = ", ".join(f"{names[i]} (eᵀΣ⁻¹e/dof = {quad[i] / lik.nobs[i]:.3g}: errors "
                          f"{'larger' if quad[i] > lik.nobs[i] else 'smaller'} than the fit says)"
                          for i in bad[np.argsort(p[bad])][:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        out.append(f"{bad.size} of {len(p)} logs disagree with the fit (per-log χ² test at 1 %, "
                   f"Bonferroni; eᵀΣ⁻¹e/dof is 1 for a log the fit describes): {shown}{more}")


#: The truth's fitted floor is warned about above this share of the predicted position
#: variance at the window ends, when the windows are of about one size (FLOOR_SPREAD).
FLOOR_SHARE = 0.5
#: Windows whose longest is under this multiple of their shortest, in time or in travel, are
#: "of one size": a floor and a growing noise are then told apart only by the scatter of sizes.
FLOOR_SPREAD = 2.0


def _floor_note(bases: Sequence[WindowBasis], v_hat: NDArray[np.float64],
                params: Sequence[NoiseParameter], free: NDArray[np.intp]) -> str | None:
    """A warning where the truth's own noise, fitted, is most of the predicted position
    variance at window ends that are all of about one size.

    A floor (the truth's σ at a window's two ends) does not grow with the window; robot
    noise does. Windows of one length tell the two apart only through the scatter of their
    travel and turning, so a floor fitted there can absorb what is really model misfit (a
    robot's systematic error that grows with the window: on simulated commanded-velocity
    robots a motion capture's "floor" came out at 0.14 m and 0.86 s) and the model then
    over-covers shorter windows and under-covers longer ones.
    """
    truth = [int(j) for j in free if params[int(j)].kind == "truth"]
    if not truth or not bases:
        return None
    durations = np.array([w.duration for b in bases for w in b.windows])
    travels = np.array([w.travel for b in bases for w in b.windows])
    one_size = any(x.size and float(np.min(x)) > 0 and float(np.max(x)) < FLOOR_SPREAD * float(np.min(x))
                   for x in (durations, travels))
    if not one_size:
        return None
    q = len(bases[0].white_names)
    only_floor = np.zeros_like(v_hat)
    only_floor[truth] = v_hat[truth]
    floor = sum(float(np.einsum("j,wjaa->", only_floor[:q], b.white[:, :, :2, :2])) for b in bases)
    total = sum(float(np.trace(b.covariance(v_hat)[:, :2, :2], axis1=1, axis2=2).sum()) for b in bases)
    share = floor / total if total > 0 else 0.0
    if share <= FLOOR_SHARE:
        return None
    shown = ", ".join(f"{params[j].key} {params[j].to_value(v_hat[j]):.3g}" for j in truth if v_hat[j] > 0)
    return (f"the truth's own noise, fitted ({shown}), is {100 * share:.0f} % of the predicted position "
            "variance at these window ends, all of about one length: there a floor that does not grow "
            "with the window is hard to tell from robot noise that does, so the model may not hold at "
            "other lengths; fit two lengths (--window 10s --window 30s) or give the truth's noise "
            "(--truth-sigma, --truth-heading-sigma, --truth-time-sigma)")


def _cross_validate(prob: _Problem, v_hat: NDArray[np.float64], fitted: dict[int, WindowBasis],
                    scored: Sequence[WindowBasis], used: Sequence[int],
                    params: Sequence[NoiseParameter],
                    lengths: Sequence[Sequence[str]] | None = None) -> dict[str, object] | None:
    """Leave-one-log-out: refit without each log (from the full fit, on the windows it
    kept: ``fitted``) and score every window of that log (``scored``, trimmed ones too);
    with ``lengths`` (each scored window's length) the coverage of each length apart too."""
    if len(used) < 2:
        return None
    errors: list[NDArray[np.float64]] = []
    covs: list[NDArray[np.float64]] = []
    tags: list[str] = []
    spread: dict[str, list[float]] = {params[j].key: [] for j in prob.free}
    for k in range(len(used)):
        rest = WindowLikelihood([fitted[i] for m, i in enumerate(used) if m != k])
        sub = _Problem(rest, prob.v0, prob.free, prob.scale)
        v, _ = sub.maximise(v_hat, prob.free, v_hat[prob.free])
        held = WindowLikelihood([scored[used[k]]])
        errors.append(held.error[:, :2])
        covs.append(held.window_covariance(v)[:, :2, :2])
        own = tuple(lengths[used[k]]) if lengths is not None else ()
        tags.extend(own if len(own) == held.error.shape[0] else ("",) * held.error.shape[0])
        for j in prob.free:
            spread[params[j].key].append(params[j].to_value(v[j]))
    error, cov, tag = np.concatenate(errors), np.concatenate(covs), np.array(tags)
    out: dict[str, object] = {"coverage": coverage(error, cov), "folds": len(used),
                              "windows": int(error.shape[0]),
                              "parameter_range": {k: [min(x), max(x)] for k, x in spread.items()}}
    named = [x for x in dict.fromkeys(tags) if x]
    if len(named) > 1:  # windows of several lengths: the pooled figure can hide one that fails
        out["by_length"] = {x: {"coverage": coverage(error[tag == x], cov[tag == x]),
                                "windows": int(np.count_nonzero(tag == x))} for x in named}
    return out
