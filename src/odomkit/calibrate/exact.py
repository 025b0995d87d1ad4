"""Exact-model calibration: wheel scales, wheel base (or a tricycle's or car's scale,
steering offset and wheel base; a unicycle's speed scale, yaw-rate bias and yaw-rate scale;
a gyro robot's metres per tick, gyro bias and gyro scale) by nonlinear least squares on the
exact kinematics.

UMBmark (Borenstein–Feng section IV) linearises the square path (``L sin γ ≈ Lγ``) and
treats turns and straight legs as if they were driven perfectly apart from one error
each. Here the logs are re-integrated with candidate parameters by the same exact-arc
dead reckoning odomkit uses everywhere (:func:`odomkit.integrate.dead_reckon`), and the
parameters are chosen so the integrated poses match the ground truth:

* ``source="endpoints"``: only the final pose of each run is compared (what a UMBmark
  experiment measures);
* ``source="trajectory"``: every logged pose is compared (needs ground truth at every
  row, e.g. a motion-capture system). This also observes the overall scale E_s.

Why the overall scale is unobservable from closed-path endpoints: multiplying both wheel
scales *and* the wheel base by the same factor s leaves every Δθ unchanged and multiplies
every Δd by s, so the whole odometry track is scaled by s about the start pose. The end
of a closed square lies near the start, so the end pose hardly moves. :func:`calibrate_exact`
measures this (how far the compared poses lie from the start relative to the distance
travelled to reach them) and, when it is below ``SCALE_OBSERVABLE_BELOW``, keeps the mean
wheel scale fixed, the constraint UMBmark uses implicitly (Borenstein–Feng eq. 4.28: the
average diameter D_a is unchanged). The wheel base then absorbs any E_s: headings come out
right, distances stay scaled.

Standard errors are ``σ̂² (JᵀJ)⁻¹`` with ``σ̂² = |r|²/(m − p)``, J the (analytic)
Jacobian of the weighted residuals at the solution. This assumes the residuals are
independent with equal variance after weighting. It holds for endpoint residuals
whitened by a noise model (``noise=``); for unweighted endpoints it is approximate
(x, y and θ errors of one run are correlated); for trajectories it is optimistic,
because the errors along one track are a random walk, strongly correlated from row to
row. So a fit of several runs also gives standard errors from the runs' spread
(``std_errors_between_runs``: the runs as independent clusters, see :func:`between_runs`;
:func:`jackknife_runs` refits without each run instead) and warns
where they exceed the fit's by more than :data:`BETWEEN_RUNS_FACTOR`; a single trajectory
is warned about where its residuals exceed the truth's own noise
(:func:`warn_if_drifting`).

The re-integration with sensitivities, the parameter-to-body-step maps of each robot and
the weighted residuals with their Jacobian are in :mod:`odomkit.calibrate.residuals`.
"""

from __future__ import annotations

import warnings
from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from odomkit import validate
from odomkit.calibrate.residuals import (
    CalibratedRobot,
    GyroCalibrationModel,
    ResidualProblem,
    UnicycleCalibrationModel,
    calibration_model,
    endpoint_whitening,
)
from odomkit.errors import InputError, ModelError
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.propagate.plan import NoiseArg
from odomkit.robot import DiffDrive
from odomkit.truth import Truth, scatter_sigma, truth_from_log

__all__ = ["BETWEEN_RUNS_FACTOR", "between_runs", "between_runs_warning", "SCALE_OBSERVABLE_BELOW",
           "calibrate_exact", "ExactCalibration", "held_note", "jackknife_runs", "Source", "truth_noise",
           "warn_if_drifting"]

Source = Literal["endpoints", "trajectory"]

#: Below this relative sensitivity the overall scale counts as unobservable.
SCALE_OBSERVABLE_BELOW = 0.05
#: A parameter whose between-run standard error exceeds the fit's own by more than this
#: factor is warned about. Where the fit's ± are honest, the between-run variance over N
#: runs is unbiased and scatters about like the fit's times χ²_{N−1}/(N−1) (fewer degrees of
#: freedom where runs differ: Bell & McCaffrey 2002), so the ratio of the two standard errors
#: exceeds 3 with probability P(χ²₁ > 9) = 0.27 % for 2 runs, e^−9 for 3, less for more.
#: Measured on simulated runs of one robot with white truth noise (where the fit's own ± came
#: out 1.1–1.5× small all the same): a warning in at most 3 % of experiments of 2 or 3 runs,
#: none of 5 or 8 (:func:`between_runs`). And ± that are 3× too small are no longer ±: an
#: interval of ±1 of them holds the value about a quarter of the time, not two thirds.
BETWEEN_RUNS_FACTOR = 3.0
#: A column-scaled Jacobian conditioned worse than this is singular: JᵀJ's condition number
#: is its square, 1e16, beyond double precision. Real single runs reach 2e3 (OptiOdom's
#: shortest diff runs, whose wheel base alone comes out anywhere); an arc of constant
#: curvature, which cannot tell the wheels' scale from the wheel base, 1e15–1e16.
_UNDETERMINED = 1e8


@dataclass(frozen=True)
class ExactCalibration:
    """Result of :func:`calibrate_exact`.

    Parameters
    ----------
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        The input robot with the fitted corrections in place.
    names : tuple of str
        Parameter names: ``c_left, c_right, c_wheel_base`` (diff),
        ``c_scale, steering_offset, wheel_to_axle`` (tricycle; m for ``wheel_to_axle``, rad for
        the offset), ``c_scale, steering_offset, wheel_base`` (car),
        ``c_scale, yaw_rate_bias, yaw_rate_scale`` (unicycle; rad/s for the bias) or
        ``m_per_tick, gyro_bias, gyro_scale`` (gyro; m, rad/s).
    values, std_errors : ndarray, shape (3,)
        Estimates and standard errors ``sqrt(diag(cov))``.
    cov, corr : ndarray, shape (3, 3)
        Parameter covariance ``σ̂²(JᵀJ)⁻¹`` and correlation matrix. With a fixed scale,
        c_left and c_right are perfectly anti-correlated (corr −1) and their sum has zero
        variance.
    residual_variance : float
        σ̂² of the weighted residuals (m² unless whitened, then dimensionless).
    n_residuals, n_runs : int
    source : {"endpoints", "trajectory", "positions"}
        ``positions``: :func:`odomkit.calibrate.positions.calibrate_positions` (truth
        positions on their own clock, start poses fitted).
    scale_fixed : bool
        True when the mean scale (diff) or speed scale (``c_scale``, ``m_per_tick``) was held
        at its input value (unobservable or asked).
    scale_sensitivity : float
        Relative sensitivity of the residuals to the overall scale at the start (0 = none).
    notes : tuple of str
        Human-readable remarks (why the scale was fixed, convergence).
    time_offset, time_offset_std_error, time_offset_std_error_between_runs : float or None
        ``positions`` with ``fit_time_offset``: the truth's clock offset δ [s] (a fix
        stamped t is the pose at log time t − δ), its standard error, and that from the runs'
        (windows') spread as ``std_errors_between_runs`` (None for one run); None otherwise.
    std_errors_between_runs : ndarray, shape like ``values``, or None
        Standard errors from the runs' spread (the runs as independent clusters, see
        :func:`calibrate_exact`): honest where the residuals along a run are correlated
        and ``std_errors`` are not. None for one run, where a parameter rests on one run, or
        where the fit is not ``determined``.
    determined : bool
        False where the runs leave a combination of the parameters undetermined (the
        column-scaled Jacobian's condition number beyond 1e8, with a note):
        the values lie anywhere along it and the standard errors mean nothing (a single arc
        of constant curvature cannot tell the wheels' scale from the wheel base).
    n_windows, windows_left_out, window : int or None, int, str or None
        ``positions`` fitted in windows (:func:`odomkit.calibrate.positions.calibrate_positions`
        ``window=``): how many windows were fitted, each from its own start pose (the clusters of
        ``std_errors_between_runs``), how many were left out (too few fixes, truth that does not
        spread), and their length (``"60 s"``, ``"20 m"``; ``"given"``: (start, end) times given);
        None, 0, None for a fit of whole runs.
    drift_dominated : bool
        ``positions`` of whole runs: a run's residuals are mostly the odometry's own drift,
        not the truth's noise, so the fit is biased (:func:`odomkit.calibrate.positions.drift_bias`
        warned; JSON ``drift_dominated``, given only where True). Fit such runs in windows.
    held : tuple of str
        The parameters the caller held at the robot's values (``fixed``, ``calibrate --fix``):
        their values are the robot's and their standard errors 0 (JSON ``held``, given only
        where some are).
    """

    robot: CalibratedRobot
    names: tuple[str, ...]
    values: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    cov: NDArray[np.float64]
    corr: NDArray[np.float64]
    residual_variance: float
    n_residuals: int
    n_runs: int
    source: str
    scale_fixed: bool
    scale_sensitivity: float
    notes: tuple[str, ...] = ()
    time_offset: float | None = None
    time_offset_std_error: float | None = None
    time_offset_std_error_between_runs: float | None = None
    std_errors_between_runs: NDArray[np.float64] | None = None
    determined: bool = True
    n_windows: int | None = None
    windows_left_out: int = 0
    window: str | None = None
    drift_dominated: bool = False
    held: tuple[str, ...] = ()

    @property
    def E_d(self) -> float:
        """Borenstein–Feng eq. (2.3), D_R/D_L (diff only): ratio of the corrected metres per tick."""
        r = self._diff()
        return r.scale_right / r.scale_left

    @property
    def E_b(self) -> float:
        """Borenstein–Feng eq. (2.4), b_actual/b_nominal (diff only)."""
        return self._diff().c_wheel_base

    @property
    def E_s(self) -> float:
        """Scaling error (Borenstein–Feng section II-B): mean actual over mean nominal wheel
        diameter, (scale_left + scale_right)/(m_per_tick_left + m_per_tick_right)."""
        r = self._diff()
        return (r.scale_left + r.scale_right) / (r.m_per_tick_left + r.m_per_tick_right)

    def _diff(self) -> DiffDrive:
        if not isinstance(self.robot, DiffDrive):
            raise ModelError("E_d, E_b, E_s are defined for differential-drive robots only")
        return self.robot

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for JSON output."""
        out: dict[str, Any] = {
            "source": self.source,
            "parameters": {n: float(v) for n, v in zip(self.names, self.values, strict=True)},
            "std_errors": {n: float(v) for n, v in zip(self.names, self.std_errors, strict=True)},
            "corr": self.corr.tolist(),
            "residual_rms": float(np.sqrt(self.residual_variance)),
            "n_residuals": self.n_residuals,
            "n_runs": self.n_runs,
            "scale_fixed": self.scale_fixed,
            "scale_sensitivity": self.scale_sensitivity,
            "notes": list(self.notes),
        }
        if self.time_offset is not None:
            out["truth_time_offset"] = {"value": self.time_offset, "std_error": self.time_offset_std_error}
            if self.time_offset_std_error_between_runs is not None:
                out["truth_time_offset"]["std_error_between_runs"] = self.time_offset_std_error_between_runs
        if self.drift_dominated:
            out["drift_dominated"] = True
        if self.held:
            out["held"] = list(self.held)
        if self.n_windows is not None:
            out["windows"] = {"length": self.window, "fitted": self.n_windows,
                              "left_out": self.windows_left_out}
        if self.std_errors_between_runs is not None:
            out["std_errors_between_runs"] = {
                n: float(v) for n, v in zip(self.names, self.std_errors_between_runs, strict=True)}
        if isinstance(self.robot, DiffDrive):
            out.update(E_d=self.E_d, E_b=self.E_b, E_s=self.E_s,
                       wheel_base=self.robot.effective_wheel_base)
        return out


def held_note(name: str, value: float) -> str:
    """The note of a parameter the caller held (``fixed``, ``calibrate --fix``) at ``value``."""
    return f"{name} held at the robot file's value {value:.6g} (fixed: not fitted, standard error 0)"


def _hold_fixed(offset: NDArray[np.float64], T: NDArray[np.float64], held: Sequence[int],
                p0: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Restrict the map p = offset + T q, shapes (P,), (P, Q), to p[held] = p0[held].

    The constraint T[held] q = p0[held] − offset[held] has the solutions q = q* + N z with
    q* its least-squares solution and N an orthonormal basis of the null space of T[held];
    the new map is p = (offset + T q*) + (T N) z.
    """
    idx = np.asarray(held, dtype=np.intp)
    A = T[idx]
    q_star = np.linalg.lstsq(A, p0[idx] - offset[idx], rcond=None)[0]
    _, sv, vt = np.linalg.svd(A)
    rank = int(np.count_nonzero(sv > 1e-12 * max(1.0, float(sv.max(initial=0.0)))))
    N = vt[rank:].T
    new_offset = offset + T @ q_star
    new_offset[idx] = p0[idx]  # exactly, not to round-off
    T_new = T @ N
    T_new[idx] = 0.0
    return new_offset, T_new


def _check_runs(runs: Sequence[OdometryLog], source: str) -> None:
    if source not in ("endpoints", "trajectory"):
        raise ModelError(f"source must be 'endpoints' or 'trajectory', got {source!r}")
    if len(runs) < 1:
        raise InputError("calibration needs at least one run with ground truth")
    for log in runs:
        if log.ground_truth is None:
            raise InputError("run has no ground truth; calibration compares against it",
                             source=log.source)
        if len(log) < 2:
            raise InputError("run has fewer than two rows", source=log.source)
    if source == "endpoints":
        if len(runs) < 2:
            raise InputError(f"an endpoint calibration needs at least two runs, got {len(runs)}: one run "
                             "calibrates from its whole trajectory (--from trajectory)")
        turns = [float(log.ground_truth[-1, 2] - log.ground_truth[0, 2]) for log in runs]  # type: ignore[index]
        loops = [t for t in turns if abs(t) > np.pi]
        if len(loops) == len(turns) and (all(t > 0 for t in loops) or all(t < 0 for t in loops)):
            raise InputError(
                "all runs are closed loops turning the same way; their endpoints cannot separate "
                "the wheel-diameter and wheel-base errors (Borenstein–Feng section III-A): "
                "add runs in the other direction"
            )


def truth_noise(truths: Sequence[Truth]) -> tuple[float, str]:
    """The truth's position noise σ [m] per axis that a calibration's residuals are held
    against, and what it is: the stated σ (``--truth-sigma``), else the σ the fixes' own file
    states (a bag's NavSatFix covariance), else the fixes' scatter about a smooth path
    (:func:`odomkit.truth.scatter_sigma`); 0 where none is known."""
    stated = max((t.sigma for t in truths), default=0.0)
    what = "stated σ"
    if stated <= 0:
        # The σ the fixes' own file states (a bag's NavSatFix covariance), not given as
        # --truth-sigma: the ratio is judged against it as check judges (a GPS's scatter about
        # a smooth path misses its error correlated in time: a Husky's 0.1 m against 0.8 m
        # stated made its residuals "15x the truth's").
        stated = max((t.stated_sigma for t in truths), default=0.0)
        what = "σ its fixes state"
    if stated <= 0:
        found = [x for x in (scatter_sigma(t) for t in truths) if x is not None]
        stated = float(np.sqrt(np.mean(np.square(found)))) if found else 0.0
        what = "scatter about a smooth path"
    return stated, what


def warn_if_drifting(var_res: float, n_res: int, truths: Sequence[Truth], *, windowed: bool = False) -> None:
    """Warn when the residuals are more than the truth's own noise: σ̂²(JᵀJ)⁻¹ treats them
    as independent from fix to fix, which the odometry's own drift (a random walk along
    each run) is not. On a simulated car with residuals 1.28× the GPS's σ, the clock
    offset's scatter over seeds was about 5× its standard error. The noise is the stated
    σ, else the fixes' own scatter about a smooth path (:func:`odomkit.truth.scatter_sigma`),
    so that a user who states nothing is warned too.

    Parameters
    ----------
    var_res : float
        The residuals' variance per position axis [m²].
    n_res : int
        How many position residuals (fixes × 2).
    truths : sequence of Truth
        The truth of each run, with its stated ``sigma`` [m] (0: not stated).
    windowed : bool
        The fit is of windows (``calibrate --window``): the message names the standard errors
        between windows, which allow for the drift.
    """
    stated, what = truth_noise(truths)
    if stated <= 0 or var_res < 1e-18:  # residuals under a nanometre are round-off, not drift
        return
    ratio = float(np.sqrt(var_res)) / stated
    # An honest residual RMS is σ within about 1/√n_res (relative): allow five of those.
    if ratio > 1.0 + 5.0 / np.sqrt(n_res):
        where = ("each window, so the fit's own standard errors are optimistic; those between windows "
                 "(JSON std_errors_between_runs) allow for it" if windowed else
                 "each run, so the standard errors are optimistic")
        warnings.warn(f"the calibration's residuals (RMS {np.sqrt(var_res):.3g} m) are {ratio:.2f}x the "
                      f"truth's {what} ({stated:.3g} m): the odometry's own drift is in them, correlated "
                      f"along {where}", UserWarning, stacklevel=3)


def between_runs(J: NDArray[np.float64], r: NDArray[np.float64], sizes: Sequence[int],
                  T: NDArray[np.float64]) -> tuple[NDArray[np.float64] | None, int | None]:
    """Standard errors of the parameters p = offset + T q from the runs' spread: the
    cluster-robust ("sandwich") covariance with the runs as clusters, bias-reduced (CR2).

    J (m, Q) and r (m,) are the weighted Jacobian and residuals at the joint solution q̂,
    the runs' blocks of ``sizes`` rows one after the other. Linearised about q̂, the fit's
    error is q̂ − q ≈ −A⁻¹ Σ_i J_iᵀ e_i (A = JᵀJ, e_i run i's errors), so with the runs
    independent, however correlated the rows of one run are,
    Cov q̂ = A⁻¹ (Σ_i J_iᵀ Cov(e_i) J_i) A⁻¹ (Liang & Zeger 1986, Biometrika 73, 13–22).
    The fitted residuals are smaller than the errors: for independent errors of equal
    variance σ² (what σ̂²A⁻¹ assumes), E[r_i r_iᵀ] = σ²(I − H_ii), H_ii = J_i A⁻¹ J_iᵀ, so
    each run's residuals are scaled by (I − H_ii)^(−1/2) before they stand in for its
    errors; the estimate is then unbiased wherever the joint fit's own ± are right (Bell &
    McCaffrey 2002, Survey Methodology 28, 169–181: "bias-reduced linearization"). H_ii has
    rank ≤ Q: with the thin SVD J_i A^(−1/2) = U S Vᵀ, (I − H_ii)^(−1/2) r_i =
    r_i + U((1 − S²)^(−1/2) − 1)Uᵀ r_i, where S² are the run's shares of the information
    (the eigenvalues of A⁻¹A_i, A_i = J_iᵀJ_i).

    For N runs that pin the parameters equally (A_i = A/N) and a model linear over their
    differences, run i's residuals are J_i(q̂ − θ_i) with θ_i its own fit, the shares are
    1/N, and the variance is Σ_i (θ_i − θ̄)²/(N(N − 1)) = s²/N: the standard error of the
    mean of the runs' own fits. Where runs differ it stays the joint fit's: a run counts as
    much as it pins (a short OptiOdom run fitted alone gave a wheel base of 4e11; the joint
    fit hardly depends on it), and no run need be fitted alone (an endpoint gives 2 numbers
    for 3 parameters). Why not the delete-one-run jackknife (:func:`jackknife_runs`; ≈ CR3,
    the residuals scaled by (I − H_ii)^(−1)): it over-corrects where runs carry much of the
    information. On simulated runs of one robot with the truth's white noise the only error
    (40 experiments each), it came out 1.6–3× the fits' actual scatter for 2 runs and 1.1–1.8×
    for 3, and warned in 50 % and 17 % of the experiments where nothing was wrong; this
    estimate came out 0.76–1.26× for 2 to 8 runs and warned in at most 3 % (2 runs). Without
    the correction (CR1, N/(N − 1)·Σ) it was 0.54–1.1×.

    Returns
    -------
    (std_errors (P,), None), or (None, i) where without run i the others leave a direction
    of q undetermined (a share is 1), or (None, None) where the joint fit does.
    """
    # In units of each parameter's own column norm (the estimate does not depend on the
    # parameters' units; the joint fit's determinacy, which the caller has checked, is judged
    # in these units too): only a direction no residual moves at all is refused here.
    norms = np.linalg.norm(J, axis=0)
    if not norms.size or np.any(norms <= 0):
        return None, None
    J = J / norms
    A = J.T @ J
    eig, vec = np.linalg.eigh(A)
    if eig[0] <= 0:
        return None, None  # the joint fit itself leaves a direction undetermined
    half = (vec / np.sqrt(eig)) @ vec.T  # A^(−1/2)
    scores = []
    start = 0
    for i, size in enumerate(sizes):
        Ji, ri = J[start:start + size], r[start:start + size]
        start += size
        U, S, _ = np.linalg.svd(Ji @ half, full_matrices=False)
        share = np.clip(S**2, 0.0, None)
        if float(share.max(initial=0.0)) > 1.0 - 1e-6:
            return None, i
        adjusted = ri + U @ ((1.0 / np.sqrt(1.0 - share) - 1.0) * (U.T @ ri))
        scores.append(Ji.T @ adjusted)
    # Each run's pull on q̂ (back in q's units), then on p̂ = offset + T q̂: (N, P).
    moved = (np.linalg.solve(A, np.asarray(scores).T).T / norms) @ T.T
    return np.sqrt(np.sum(moved**2, axis=0)), None


def between_runs_warning(names: Sequence[str], values: NDArray[np.float64], own: NDArray[np.float64],
                          between: NDArray[np.float64], n_runs: int, clusters: str = "runs") -> str | None:
    """The warning where a parameter's between-run standard error exceeds the fit's own by
    more than :data:`BETWEEN_RUNS_FACTOR` (and round-off: 1e-9 of the value); ``clusters``
    names the runs (``"windows"`` for a fit in windows)."""
    off = [f"{name} ± {b:.2g} between {clusters} against ± {s:.2g} from the fit ({b / s:.0f}×)" if s > 0 else
           f"{name} ± {b:.2g} between {clusters} against ± {s:.2g} from the fit"
           for name, v, s, b in zip(names, values, own, between, strict=True)
           if b > BETWEEN_RUNS_FACTOR * s and b > 1e-9 * max(1.0, abs(float(v)))]
    if not off:
        return None
    one = clusters[:-1]
    robots = "" if clusters == "windows" else " (or the runs' robots differ)"
    return (f"the {n_runs} {clusters} scatter more than the fit's standard errors allow: " + "; ".join(off)
            + f": the fit takes the residuals along a {one} as independent, but the odometry's drift is "
            f"correlated along each {one}{robots}, so its ± are optimistic; quote the "
            f"between-{one} ones (JSON std_errors_between_runs)")


def calibrate_exact(
    runs: Sequence[OdometryLog],
    robot: CalibratedRobot,
    source: Source = "endpoints",
    *,
    heading_weight: float | None = 0.0,
    fix_scale: bool | None = None,
    noise: NoiseArg | None = None,
    every: int = 1,
    method: Method = "exact",
    steering_cubic: bool = False,
    truth_sigma: float | None = None,
    fixed: Collection[str] = (),
) -> ExactCalibration:
    """Fit a robot's systematic parameters to ground truth on the exact kinematics.

    Parameters
    ----------
    runs : sequence of OdometryLog
        Logs with ``ground_truth`` (N, 3); diff robots need ``ticks_left/right`` (or
        ``dist_*``, ``speed_*``), tricycles and cars ``ticks`` (or ``dist``/``speed``) and ``steer``,
        unicycles ``speed`` (or ``dist``) and ``yaw_rate``, gyro robots ``ticks`` (or
        ``dist``/``speed``) and ``yaw_rate``. Each run is integrated from its first
        ground-truth pose.
    robot : DiffDrive | Tricycle | Car | Unicycle | GyroOdometry
        Nominal parameters; its current corrections are the starting point. Fitted: diff
        (c_left, c_right, c_wheel_base), tricycle (c_scale, steering_offset [rad],
        wheel_to_axle [m]), car (c_scale, steering_offset [rad], wheel_base [m]), unicycle
        (c_scale, yaw_rate_bias [rad/s], yaw_rate_scale), gyro (m_per_tick [m], gyro_bias
        [rad/s], gyro_scale). A parameter the runs' channels do not depend on (a gyro
        robot's m_per_tick without a ``ticks`` channel) is held at its value, with a note.
    source : {"endpoints", "trajectory"}
        Compare only each run's final pose, or every row's pose.
    heading_weight : float or None
        Length [m/rad] that turns a heading residual into a position-like one; None means
        a quarter of the mean path length of the runs (the side of a square: a heading
        error δθ at the end counts like a lateral miss of side·δθ). The default 0 fits
        positions only, like UMBmark and E_max,syst; on the OptiOdom squares adding the
        heading made the calibration worse in and out of sample (docs/results/real-data.md).
    fix_scale : bool, optional
        Hold the mean scale (diff: (c_left + c_right)/2; tricycle, car, unicycle: c_scale;
        gyro: m_per_tick) at its input value. Default: automatically, when the compared
        poses lie closer to the start than ``SCALE_OBSERVABLE_BELOW`` times the distance
        travelled (closed paths, endpoints).
    noise : WheelNoise, optional
        Diff endpoints only: whiten each run's end residual by the end-pose covariance that
        this per-wheel noise predicts (Chong–Kleeman eq. 23), making the fit a generalised
        least-squares fit whose standard errors are valid.
    every : int
        Trajectory source: use every ``every``-th row.
    method : {"exact", "midpoint", "euler"}
        Integration method, as in dead reckoning.
    steering_cubic : bool
        A car's ``steering_cubic`` [rad⁻²] is fitted too, as a fourth parameter.
    truth_sigma : float, optional
        The ground truth's position noise [m per axis] (``--truth-sigma``). A single
        trajectory (no runs to compare) is warned about where its residuals exceed it
        (:func:`warn_if_drifting`; not given: the truth's scatter about a smooth path).
    fixed : collection of str
        Parameter names held at the robot's values (``calibrate --fix``), as
        :func:`odomkit.calibrate.positions.calibrate_positions` holds them: not fitted,
        standard error 0, named in the result's ``held`` and a note. An unknown name is a
        ModelError naming the parameters.

    Returns
    -------
    ExactCalibration
        With several runs also ``std_errors_between_runs`` (from the runs' spread, the
        runs as independent clusters: :func:`between_runs`), and a warning naming the
        parameters whose between-run standard error exceeds the fit's by more than
        :data:`BETWEEN_RUNS_FACTOR`.

    Examples
    --------
    Noise-free straight-line-and-turn runs of a robot whose right wheel is 1 % large:

    >>> from odomkit.log import OdometryLog
    >>> from odomkit.integrate import dead_reckon
    >>> from odomkit.kinematics import diff_body_steps
    >>> nominal = DiffDrive(wheel_base=0.5)
    >>> def run(left, right):
    ...     a, r = np.full(200, left / 200), np.full(200, right / 200)
    ...     gt = dead_reckon(*diff_body_steps(a, 1.01 * r, 0.5))
    ...     ch = {"dist_left": np.r_[0, a], "dist_right": np.r_[0, r]}
    ...     return OdometryLog(np.arange(201.0), ch, gt)
    >>> cal = calibrate_exact([run(2, 2.5), run(2.5, 2)], nominal, "trajectory")
    >>> [round(float(v), 6) for v in cal.values]
    [1.0, 1.01, 1.0]
    """
    _check_runs(runs, source)
    every = validate.positive_int(every, "every")
    if truth_sigma is not None:
        truth_sigma = validate.non_negative(truth_sigma, "truth_sigma", unit="m")
    model = calibration_model(robot, runs, steering_cubic=steering_cubic)
    unknown = sorted(set(fixed) - set(model.names))
    if unknown:
        raise ModelError(f"fixed names {', '.join(unknown)}; the parameters are {', '.join(model.names)}")
    if heading_weight is None:
        lengths = [float(np.sum(np.abs(model.steps(model.p0, i)[0]))) for i in range(len(runs))]
        heading_weight = 0.25 * float(np.mean(lengths))
    heading_weight = validate.non_negative(heading_weight, "heading_weight", unit="m/rad")
    whiten = None
    if noise is not None:
        whiten = endpoint_whitening(model, runs, source, noise, method)
    prob = ResidualProblem(model, runs, source, heading_weight, every, whiten, method)
    p0 = model.p0.copy()
    scale_index = [k for k, positive in enumerate(model.positive) if positive]
    sens = prob.scale_sensitivity(p0)
    notes: list[str] = []
    held = [k for k, name in enumerate(model.names) if name in model.unobservable]
    for k in held:
        notes.append(f"{model.names[k]} held at {p0[k]:.6g}: {model.unobservable[model.names[k]]}")
    asked = tuple(name for k, name in enumerate(model.names) if name in set(fixed) and k not in held)
    for name in asked:
        k = model.names.index(name)
        held.append(k)
        notes.append(held_note(name, float(p0[k])))
    if fix_scale is None:
        fix_scale = sens < SCALE_OBSERVABLE_BELOW
        if fix_scale and 0 not in held:
            unobservable = (f"overall scale unobservable (relative sensitivity {sens:.3g} < "
                            f"{SCALE_OBSERVABLE_BELOW}): ")
            if isinstance(model, UnicycleCalibrationModel | GyroCalibrationModel):
                # Its speed scale stretches the track about the start and leaves every Δθ alone.
                notes.append(unobservable + f"speed scale {model.names[0]} held fixed; the heading "
                             "parameters are unaffected, distances keep any scale error")
            else:
                notes.append(unobservable + "mean wheel scale held fixed as in UMBmark; the wheel "
                             "base absorbs any scale error E_s")
    if fix_scale:
        prob.offset, prob.T = model.fixed_scale_map(p0)
    if held:
        prob.offset, prob.T = _hold_fixed(prob.offset, prob.T, held, p0)
    if fix_scale or held:
        q0 = np.asarray(np.linalg.lstsq(prob.T, p0 - prob.offset, rcond=None)[0], dtype=np.float64)
    else:
        q0 = p0.copy()
    r0 = prob.residuals(q0)
    n_res = r0.size
    if not (np.all(np.isfinite(r0)) and np.all(np.isfinite(prob.jacobian(q0)))):
        raise ModelError("the pose residuals at the robot's starting parameters are not finite: "
                         "the robot file's values overflow the dead reckoning (check their units)")
    if n_res <= q0.size:
        raise InputError(
            f"{n_res} residuals cannot determine {q0.size} parameters: give more runs "
            "(UMBmark endpoints need runs in both directions)"
        )
    sol = least_squares(prob.residuals, q0, jac=prob.jacobian, method="lm", x_scale="jac",
                        xtol=1e-13, ftol=1e-13, gtol=1e-13, max_nfev=200)
    if not sol.success:
        notes.append(f"least_squares: {sol.message}")
    J = sol.jac
    if not (np.all(np.isfinite(sol.x)) and np.all(np.isfinite(J)) and np.isfinite(sol.cost)):
        raise ModelError("the calibration diverged to non-finite parameters or residuals; check the "
                         "channel assignment (left/right) and the units of the robot file")
    # A heading weight of 0 leaves every third residual (the weighted θ) at zero: counted, it
    # would divide the variance by half as many residuals again as carry it (1.5× too small).
    carrying = n_res - n_res // 3 if whiten is None and heading_weight == 0 else n_res
    dof = max(carrying - q0.size, 1)
    var_res = float(2.0 * sol.cost / dof)
    norms = np.linalg.norm(J, axis=0)
    singular = np.linalg.svd(J / np.where(norms > 0, norms, 1.0), compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    determined = bool(np.all(norms > 0) and condition <= _UNDETERMINED)
    if not determined:
        notes.append(f"the runs do not determine every parameter (Jacobian condition number "
                     f"{condition:.2g}): a combination of them moves no residual, so the values lie anywhere "
                     "along it and the standard errors mean nothing; drive turns both ways and straights")
    cov_q = var_res * np.linalg.pinv(J.T @ J)
    cov = prob.T @ cov_q @ prob.T.T
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, np.where(std > 0, 1.0, 0.0))
    p = prob.full(sol.x)
    if np.any(p[scale_index] <= 0):
        channels = ("the left and right channels" if isinstance(robot, DiffDrive)
                    else "the channels read (odomkit check compares them with the truth)")
        raise ModelError(f"calibration diverged to non-positive parameters "
                         f"{dict(zip(model.names, (float(x) for x in p), strict=True))}; check {channels}, "
                         "their units and the robot file")
    between = None
    if len(runs) > 1 and determined:
        # Each run's block: 3 residuals (x, y, weighted θ) per compared row.
        between, alone = between_runs(J, sol.fun, [3 * rows.size for rows, _ in prob.truth], prob.T)
        if between is None:
            needed = (f"the other runs do not determine every parameter without {runs[alone].source}"
                      if alone is not None else "the fit does not determine every parameter")
            notes.append(f"no standard errors between runs: {needed}")
        elif said := between_runs_warning(model.names, p, std, between, len(runs)):
            warnings.warn(said, UserWarning, stacklevel=2)
    if between is None and source == "trajectory" and whiten is None:
        # No runs to compare: the residuals against the truth's own noise, as for truth fixes.
        xy = sol.fun.reshape(-1, 3)[:, :2]
        truths = [t for t in (truth_from_log(log) for log in runs) if t is not None]
        warn_if_drifting(float(np.sum(xy**2)) / max(xy.size - q0.size, 1), xy.size,
                         [replace(t, sigma=truth_sigma or 0.0) for t in truths])
    return ExactCalibration(
        robot=model.make_robot(p), names=model.names, values=p, std_errors=std, cov=cov,
        corr=corr, residual_variance=var_res, n_residuals=n_res, n_runs=len(runs),
        source=source, scale_sensitivity=sens, notes=tuple(notes), std_errors_between_runs=between,
        determined=determined, held=asked,
        scale_fixed=(bool(fix_scale) or (0 in held and model.names[0] not in asked)
                     or bool({"c_scale", "m_per_tick"} & set(asked)) or {"c_left", "c_right"} <= set(asked)),
    )


def jackknife_runs(
    runs: Sequence[OdometryLog], robot: CalibratedRobot, source: Source = "trajectory",
    **kwargs: Any,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Delete-one-run jackknife standard errors of :func:`calibrate_exact`'s parameters.

    Each run's residuals are correlated along the track but runs are independent, so
    leaving out one run at a time gives honest standard errors where σ̂²(JᵀJ)⁻¹ does not
    (trajectories). Needs at least 3 runs.

    Returns
    -------
    values : ndarray, shape (3,)
        The all-runs estimate.
    std_errors : ndarray, shape (3,)
        ``sqrt((n−1)/n · Σ (θ_i − θ̄)²)`` (Efron's jackknife).
    """
    n = len(runs)
    if n < 3:
        raise InputError(f"jackknife needs at least 3 runs, got {n}")
    full = calibrate_exact(runs, robot, source, **kwargs).values
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loo = np.array([calibrate_exact([r for j, r in enumerate(runs) if j != i], robot, source,
                                        **kwargs).values for i in range(n)])
    return full, np.sqrt((n - 1) / n * np.sum((loo - loo.mean(axis=0)) ** 2, axis=0))
