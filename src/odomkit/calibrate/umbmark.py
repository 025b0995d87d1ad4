"""UMBmark: Borenstein–Feng's bidirectional-square calibration of E_d and E_b.

The robot drives an L×L square by odometry n times clockwise (CW) and n times
counter-clockwise (CCW), starting at (0, 0) heading +x and making four on-the-spot 90°
turns. The return position errors ε = absolute − calculated (Borenstein–Feng eq. 3.1) of
each run are the input here.

Conventions (Borenstein–Feng section IV-A, re-derived; see docs/reference/commands/umbmark.md):

- α [rad] is the Type A error of each nominal 90° turn, positive when the robot turns
  *less* than 90° in both directions (actual wheel base larger than believed, E_b > 1).
- β [rad] is the Type B heading change accumulated on each nominally straight leg,
  positive when the robot curves to the *left* (CCW) in both directions (right wheel
  larger, E_d > 1).

To first order in α and β the centres of gravity are (eq. 4.4, 4.8, 4.12, 4.16)::

    x_cw  = −2L(α + β)      y_cw  = −2L(α + β)
    x_ccw = −2L(α − β)      y_ccw = +2L(α − β)

whence the four estimators of eq. (4.20a/b) and (4.24a/b).

Wheel-base correction: a believed 90° turn is ended when (d_R − d_L)/b_believed = π/2;
the robot really turns (d_R − d_L)/b_actual = (π/2)·b_believed/b_actual = π/2 − α, so
E_b = b_actual/b_believed = (π/2)/(π/2 − α) *exactly* — Borenstein–Feng eq. (4.27),
90°/(90° − α). Chong–Kleeman's eq. (10), c_b = π/(π − α), is the same proportion
written for a 180° turn: it applies only half of the needed correction (c_b − 1 ≈ α/π
instead of 2α/π) and leaves a Type A error of about α/2 per turn. It is offered only for
comparison (:func:`umbmark_chong_kleeman`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import InputError, ModelError
from odomkit.robot import DiffDrive

Variant = Literal["borenstein-feng", "chong-kleeman"]

__all__ = [
    "UmbmarkResult",
    "umbmark",
    "umbmark_chong_kleeman",
    "apply_corrections",
    "e_max_syst",
    "umbmark_summary",
]


@dataclass(frozen=True)
class UmbmarkResult:
    """Everything UMBmark derives from two clusters of return position errors.

    Lengths in metres, angles in radians; tuples are (x, y).

    Attributes
    ----------
    variant : {"borenstein-feng", "chong-kleeman"}
        Which wheel-base formula produced ``E_b`` (see module docstring).
    side, wheel_base_nominal : float
        L and the wheel base b the odometry used during the runs [m].
    n_cw, n_ccw : int
        Number of runs in each direction.
    cg_cw, cg_ccw : tuple of float
        Centres of gravity of the return position errors, eq. (3.2) [m].
    r_cg_cw, r_cg_ccw : float
        Their distances from the origin, eq. (3.3) [m].
    e_max_syst : float
        max(r_cg_cw, r_cg_ccw), eq. (3.4) [m].
    alpha_x, alpha_y, alpha : float
        Type A error per turn from eq. (4.24a), (4.24b) and their mean [rad].
    beta_x, beta_y, beta : float
        Type B heading change per leg from eq. (4.20a), (4.20b) and their mean [rad].
    radius : float
        Signed radius of the curved legs, eq. (4.21) [m]; ``inf`` when β = 0,
        positive = curving left.
    E_d : float
        D_R/D_L relative to the believed wheels, eq. (4.22).
    E_b : float
        b_actual/b_believed, eq. (4.27) (Chong–Kleeman variant: their c_b, eq. 10).
    c_left, c_right : float
        Wheel-scale correction factors, eq. (4.31)–(4.32); their mean is 1.
    wheel_base : float
        Corrected wheel base E_b·b [m], eq. (4.26).
    sigma_cw, sigma_ccw : tuple of float
        Sample standard deviations (ddof = 1) of ε_x and ε_y in each cluster [m];
        NaN with a single run.
    sem_cw, sem_ccw : float
        Standard error of each centre of gravity, √((σ_x² + σ_y²)/n) [m] (the expected
        distance of the c.g. from the cluster's true centre); NaN with a single run.
    second_compensation_advised : bool or None
        Borenstein–Feng's rule of thumb (section V): a second compensation can help when a
        cluster's c.g. lies more than 3·SEM from the origin. ``None`` when a direction has
        fewer than two runs (no SEM).
    """

    variant: Variant
    side: float
    wheel_base_nominal: float
    n_cw: int
    n_ccw: int
    cg_cw: tuple[float, float]
    cg_ccw: tuple[float, float]
    r_cg_cw: float
    r_cg_ccw: float
    e_max_syst: float
    alpha_x: float
    alpha_y: float
    alpha: float
    beta_x: float
    beta_y: float
    beta: float
    radius: float
    E_d: float
    E_b: float
    c_left: float
    c_right: float
    wheel_base: float
    sigma_cw: tuple[float, float]
    sigma_ccw: tuple[float, float]
    sem_cw: float
    sem_ccw: float
    second_compensation_advised: bool | None

    @property
    def alpha_disagreement(self) -> float:
        """α_x − α_y [rad]. Not a noise measure alone: the neglected second-order terms
        make it ≈ −4β² for a pure Type B error even without noise (α_x ≈ α − 1.5β²,
        α_y ≈ α + 2.5β²; their mean carries only β²/2)."""
        return self.alpha_x - self.alpha_y

    @property
    def beta_disagreement(self) -> float:
        """β_x − β_y [rad]."""
        return self.beta_x - self.beta_y

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python summary with the CLI's JSON keys (``radius`` is None when infinite)."""
        return {
            "cg": {"cw": list(self.cg_cw), "ccw": list(self.cg_ccw)},
            "e_max_syst": self.e_max_syst,
            "alpha": self.alpha,
            "beta": self.beta,
            "radius": self.radius if math.isfinite(self.radius) else None,
            "E_d": self.E_d,
            "E_b": self.E_b,
            "c_left": self.c_left,
            "c_right": self.c_right,
            "wheel_base": self.wheel_base,
            "second_compensation_advised": self.second_compensation_advised,
            "variant": self.variant,
            "wheel_base_nominal": self.wheel_base_nominal,
            "side": self.side,
            "runs": {"cw": self.n_cw, "ccw": self.n_ccw},
            "r_cg": {"cw": self.r_cg_cw, "ccw": self.r_cg_ccw},
            "alpha_x": self.alpha_x,
            "alpha_y": self.alpha_y,
            "alpha_disagreement": self.alpha_disagreement,
            "beta_x": self.beta_x,
            "beta_y": self.beta_y,
            "beta_disagreement": self.beta_disagreement,
            "alpha_deg": math.degrees(self.alpha),
            "beta_deg": math.degrees(self.beta),
            "sigma": {"cw": list(self.sigma_cw), "ccw": list(self.sigma_ccw)},
            "sem": {"cw": self.sem_cw, "ccw": self.sem_ccw},
        }


def _errors_array(errors: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = validate.finite_array(errors, name, ("n", 2), error=InputError)
    if arr.shape[0] < 1:
        raise InputError(f"{name} must hold at least one run (one row x, y), got none")
    return arr


def e_max_syst(errors_cw: ArrayLike, errors_ccw: ArrayLike) -> float:
    """E_max,syst, Borenstein–Feng eq. (3.2)–(3.4) [m].

    Examples
    --------
    >>> e_max_syst([[0.3, 0.4], [0.3, 0.4]], [[0.0, 0.1]])
    0.5
    """
    cw = _errors_array(errors_cw, "errors_cw").mean(axis=0)
    ccw = _errors_array(errors_ccw, "errors_ccw").mean(axis=0)
    return float(max(math.hypot(*cw), math.hypot(*ccw)))


def _spread(arr: NDArray[np.float64]) -> tuple[tuple[float, float], float]:
    n = arr.shape[0]
    if n < 2:
        return (math.nan, math.nan), math.nan
    sigma = arr.std(axis=0, ddof=1)
    # The c.g. error has variance (σx² + σy²)/n in distance: the SEM the 3·SEM rule needs.
    return (float(sigma[0]), float(sigma[1])), float(math.sqrt((sigma**2).sum() / n))


def umbmark(
    errors_cw: ArrayLike,
    errors_ccw: ArrayLike,
    side: float,
    wheel_base: float,
    *,
    variant: Variant = "borenstein-feng",
) -> UmbmarkResult:
    """Calibrate E_d and E_b from UMBmark return position errors (Borenstein–Feng 1996).

    Parameters
    ----------
    errors_cw, errors_ccw : array_like, shape (n, 2) and (m, 2)
        Return position errors (ε_x, ε_y) = absolute − calculated, eq. (3.1), of each CW
        and CCW run [m], in the frame where the run starts at (0, 0) heading +x (CW runs
        turn right after the first leg, i.e. towards −y).
    side : float
        Side L of the square [m].
    wheel_base : float
        Wheel base b the odometry used during the runs [m].
    variant : {"borenstein-feng", "chong-kleeman"}
        Wheel-base formula: eq. (4.27) (correct) or Chong–Kleeman eq. (10) (half the
        correction; for comparison only).

    Returns
    -------
    UmbmarkResult

    Raises
    ------
    InputError
        Errors not of shape (n, 2) or not finite.
    ModelError
        ``side``/``wheel_base`` not positive, or errors so large that the model breaks
        (a curve tighter than half the wheel base, or |α| ≥ 90°).

    Examples
    --------
    A robot whose only error is a turn 1° short (α = 0.01745 rad) on a 4 m square ends at
    (−2Lα, ∓2Lα) to first order (eq. 4.4, 4.8):

    >>> a = np.radians(1.0)
    >>> r = umbmark([[-8 * a, -8 * a]], [[-8 * a, 8 * a]], side=4.0, wheel_base=0.34)
    >>> round(math.degrees(r.alpha), 12), r.beta, r.E_d, r.radius
    (1.0, 0.0, 1.0, inf)
    >>> round(r.E_b, 6), round(r.wheel_base, 6)   # 90/(90 − 1), eq. (4.27)
    (1.011236, 0.34382)
    """
    if variant not in ("borenstein-feng", "chong-kleeman"):
        raise ModelError(f"variant must be 'borenstein-feng' or 'chong-kleeman', got {variant!r}")
    cw = _errors_array(errors_cw, "errors_cw")
    ccw = _errors_array(errors_ccw, "errors_ccw")
    L = validate.positive(side, "side", unit="m")
    b = validate.positive(wheel_base, "wheel_base", unit="m")

    with np.errstate(all="ignore"):  # an overflow is reported below, not warned about
        x_cw, y_cw = cw.mean(axis=0)  # Borenstein–Feng eq. (3.2)
        x_ccw, y_ccw = ccw.mean(axis=0)
    r_cw, r_ccw = math.hypot(x_cw, y_cw), math.hypot(x_ccw, y_ccw)  # eq. (3.3)
    if not math.isfinite(max(r_cw, r_ccw)):
        raise ModelError("the centres of gravity of the return errors overflow: the errors are "
                         "too large for UMBmark (check units: metres)")

    # Borenstein–Feng eq. (4.20a/b) and (4.24a/b), in radians. (The printed eq. 4.19
    # drops the β: it must read −4Lβ = x_cw − x_ccw.)
    with np.errstate(all="ignore"):
        beta_x = (x_cw - x_ccw) / (-4.0 * L)
        beta_y = (y_cw + y_ccw) / (-4.0 * L)
        alpha_x = (x_cw + x_ccw) / (-4.0 * L)
        alpha_y = (y_cw - y_ccw) / (-4.0 * L)
    # Averaging α and β (Chong–Kleeman eq. 7–8). Borenstein–Feng's footnote 2 averages
    # E_d,x/E_d,y and E_b,x/E_b,y instead; the two differ by O((β_x − β_y)²), far below
    # the noise that makes β_x ≠ β_y, and averaging α, β keeps R, E_d and E_b consistent.
    alpha = 0.5 * (alpha_x + alpha_y)
    beta = 0.5 * (beta_x + beta_y) + 0.0  # + 0.0 turns −0.0 into 0.0
    if not all(math.isfinite(v) for v in (alpha_x, alpha_y, beta_x, beta_y, alpha, beta)):
        raise ModelError(f"α and β overflow (return errors over a {L:g} m side): the errors are too "
                         "large for UMBmark (check units: metres, and the side L)")

    s = math.sin(0.5 * beta)
    # Borenstein–Feng eq. (4.21); R is infinite on straight legs (β = 0).
    radius = math.inf if s == 0.0 else 0.5 * L / s
    # Eq. (4.22) (R + b/2)/(R − b/2) with R from (4.21), multiplied through by sin(β/2)
    # (= Chong–Kleeman eq. 9): exact at β = 0, no division by R.
    if abs(beta) >= math.pi or L - b * abs(s) <= 0.0:
        raise ModelError(
            f"β = {beta:.4g} rad per {L:g} m leg means a half-turn or a curve radius below b/2; "
            "the errors are too large for UMBmark (check units: metres, and the CW/CCW labels)"
        )
    E_d = (L + b * s) / (L - b * s)

    if variant == "borenstein-feng":
        if alpha >= 0.5 * math.pi:
            raise ModelError(f"α = {alpha:.4g} rad is not below 90°: the errors are not UMBmark's")
        E_b = (0.5 * math.pi) / (0.5 * math.pi - alpha)  # eq. (4.27): 90°/(90° − α)
    else:
        if alpha >= math.pi:
            raise ModelError(f"α = {alpha:.4g} rad is not below 180°")
        # Chong–Kleeman eq. (10) as printed; wrong by a factor 2 in (c_b − 1), see module doc.
        E_b = math.pi / (math.pi - alpha)
    # Each estimator alone must describe a turn error below the model's limit (α: 90°, or
    # 180° for Chong–Kleeman's c_b; β: a half-turn per leg): errors whose x and y estimates
    # are far out of range but happen to average to a small α or β (±6e198 rad -> 0) would
    # otherwise give a silently wrong E_d, E_b.
    alpha_limit = 0.5 * math.pi if variant == "borenstein-feng" else math.pi
    for name, value, limit in (("α_x", alpha_x, alpha_limit), ("α_y", alpha_y, alpha_limit),
                               ("β_x", beta_x, math.pi), ("β_y", beta_y, math.pi)):
        if not abs(value) < limit:
            raise ModelError(
                f"{name} = {value:.4g} rad (eq. 4.20/4.24 with L = {L:g} m) is not below "
                f"{math.degrees(limit):.0f}°: the errors are too large for UMBmark (check units: "
                "metres, the side L, and the CW/CCW labels)")

    c_left = 2.0 / (E_d + 1.0)  # eq. (4.31)
    c_right = 2.0 / (1.0 / E_d + 1.0)  # eq. (4.32) = E_d·c_L (Chong–Kleeman eq. 12)

    sigma_cw, sem_cw = _spread(cw)
    sigma_ccw, sem_ccw = _spread(ccw)
    advised: bool | None
    if cw.shape[0] < 2 or ccw.shape[0] < 2:
        advised = None
    else:
        # Borenstein–Feng section V: E_max,syst < 3·SEM -> a second pass is unlikely to help.
        # Applied per cluster, each against its own SEM.
        advised = bool(r_cw > 3.0 * sem_cw or r_ccw > 3.0 * sem_ccw)

    return UmbmarkResult(
        variant=variant,
        side=L,
        wheel_base_nominal=b,
        n_cw=int(cw.shape[0]),
        n_ccw=int(ccw.shape[0]),
        cg_cw=(float(x_cw), float(y_cw)),
        cg_ccw=(float(x_ccw), float(y_ccw)),
        r_cg_cw=r_cw,
        r_cg_ccw=r_ccw,
        e_max_syst=max(r_cw, r_ccw),  # eq. (3.4)
        alpha_x=float(alpha_x),
        alpha_y=float(alpha_y),
        alpha=float(alpha),
        beta_x=float(beta_x),
        beta_y=float(beta_y),
        beta=float(beta),
        radius=float(radius),
        E_d=float(E_d),
        E_b=float(E_b),
        c_left=float(c_left),
        c_right=float(c_right),
        wheel_base=float(E_b * b),  # eq. (4.26)
        sigma_cw=sigma_cw,
        sigma_ccw=sigma_ccw,
        sem_cw=sem_cw,
        sem_ccw=sem_ccw,
        second_compensation_advised=advised,
    )


def umbmark_chong_kleeman(
    errors_cw: ArrayLike, errors_ccw: ArrayLike, side: float, wheel_base: float
) -> UmbmarkResult:
    """UMBmark as Chong–Kleeman wrote it (their eq. 5–13), for comparison.

    Their α, β (eq. 7–8), E_d (eq. 9), c_l, c_r (eq. 11–12) and E_max,syst (eq. 13) equal
    Borenstein–Feng's; only the wheel-base factor differs: c_b = π/(π − α) (eq. 10),
    which corrects half of the Type A error (see the module docstring). ``E_b`` and
    ``wheel_base`` of the result hold c_b and c_b·b.

    Examples
    --------
    >>> a = np.radians(1.0)
    >>> r = umbmark_chong_kleeman([[-8 * a, -8 * a]], [[-8 * a, 8 * a]], 4.0, 0.34)
    >>> round(r.E_b, 6)   # 180/(180 − 1)
    1.005587
    """
    return umbmark(errors_cw, errors_ccw, side, wheel_base, variant="chong-kleeman")


def apply_corrections(robot: DiffDrive, result: UmbmarkResult) -> DiffDrive:
    """The robot with a UMBmark result applied on top of its current corrections.

    UMBmark measures E_d and E_b *relative to the parameters the odometry used*, so a
    second compensation composes with the first (Borenstein–Feng section V: a compensated
    robot is a "new" uncompensated one): the wheel-scale ratio c_R/c_L is multiplied by
    E_d while the mean (c_L + c_R)/2 is kept (eq. 4.28: do not change the average
    diameter), and c_wheel_base is multiplied by E_b (eq. 4.26).

    Examples
    --------
    >>> r = umbmark([[0.0, 0.0]], [[0.0, 0.0]], 4.0, 0.34)
    >>> apply_corrections(DiffDrive(0.34), r) == DiffDrive(0.34)
    True
    """
    ratio = result.E_d * robot.c_right / robot.c_left
    mean = 0.5 * (robot.c_left + robot.c_right)
    return replace(
        robot,
        c_left=mean * 2.0 / (ratio + 1.0),  # eq. (4.31) scaled to keep the mean
        c_right=mean * 2.0 * ratio / (ratio + 1.0),  # eq. (4.32)
        c_wheel_base=robot.c_wheel_base * result.E_b,
    )


def umbmark_summary(
    errors_cw: ArrayLike, errors_ccw: ArrayLike, side: float, wheel_base: float
) -> dict[str, Any]:
    """Borenstein–Feng's result as a dict, with Chong–Kleeman's variant under
    ``"chong_kleeman"`` (what ``odomkit umbmark --json`` prints).

    Examples
    --------
    >>> s = umbmark_summary([[-0.1, -0.1], [-0.1, -0.1]], [[-0.1, 0.1], [-0.1, 0.1]], 4, 0.34)
    >>> round(s["E_b"] - 1, 6), round(s["chong_kleeman"]["c_b"] - 1, 6)  # 2α/π vs α/π
    (0.008022, 0.003995)
    """
    bf = umbmark(errors_cw, errors_ccw, side, wheel_base)
    ck = umbmark_chong_kleeman(errors_cw, errors_ccw, side, wheel_base)
    out = bf.to_dict()
    out["chong_kleeman"] = {
        "alpha": ck.alpha,
        "beta": ck.beta,
        "E_d": ck.E_d,
        "c_b": ck.E_b,
        "c_left": ck.c_left,
        "c_right": ck.c_right,
        "wheel_base": ck.wheel_base,
        "note": "c_b = pi/(pi - alpha) (Chong-Kleeman eq. 10) applies half the wheel-base "
                "correction a 90-degree turn needs; E_b = 90/(90 - alpha) (Borenstein-Feng "
                "eq. 4.27) is the one that follows from the geometry",
    }
    return out
