"""Differential-drive noise: per-wheel white noise (Chong–Kleeman) and the classical model.

=====================  ========================================================
model                  Q_k of (Δd, Δθ)
=====================  ========================================================
:class:`WheelNoise`    :func:`wheel_input_cov` (Chong–Kleeman eq. 4)
:class:`ClassicalNoise`  :func:`classical_input_cov` with the rotate-then-translate
                       step map (Chong–Kleeman eq. 1–3; ``step_map = "classical"``)
=====================  ========================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.kinematics import diff_body_jacobian
from odomkit.noise.base import NoiseModel, register, require_non_negative, steps_input, sym2

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps

__all__ = [
    "WheelNoise",
    "ClassicalNoise",
    "WheelInputs",
    "wheel_cov_coefficients",
    "wheel_input_cov",
    "classical_input_cov",
]


@register
@dataclass(frozen=True)
class WheelNoise(NoiseModel):
    """Per-wheel white noise, Chong–Kleeman eq. (4), (18).

    The distance a wheel travels over a step has variance ``k² · |d|``.

    Parameters
    ----------
    k_left, k_right : float
        Noise coefficients [m^½]; e.g. 0.001 m^½ gives σ = 1 mm after 1 m of wheel travel.
    """

    k_left: float
    k_right: float

    robot_types: ClassVar[tuple[str, ...]] = ("diff",)
    family: ClassVar[str | None] = "wheel"

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(k_L²|d_L|, k_R²|d_R|) of each step [m²], (n, 2)."""
        d_l = steps_input(steps, "d_left", self)[a:b]
        d_r = steps_input(steps, "d_right", self)[a:b]
        return np.stack([self.k_left**2 * np.abs(d_l), self.k_right**2 * np.abs(d_r)], axis=-1)

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """The constant ∂(Δd, Δθ)/∂(d_L, d_R) = [[½, ½], [−1/b, 1/b]], (n, 2, 2)."""
        jac = diff_body_jacobian(steps.robot.effective_wheel_base)  # type: ignore[union-attr]
        return np.broadcast_to(jac, (b - a, 2, 2))

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`wheel_input_cov` of steps a … b−1."""
        d_l = steps_input(steps, "d_left", self)
        d_r = steps_input(steps, "d_right", self)
        return wheel_input_cov(d_l[a:b], d_r[a:b], steps.robot.effective_wheel_base,  # type: ignore[union-attr]
                               self)

    def input_factor(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """J diag(σ_L, σ_R) with σ = k·√|d|: [[σ_L/2, σ_R/2], [−σ_L/b, σ_R/b]], (n, 2, 2)."""
        sigma_l = self.k_left * np.sqrt(np.abs(steps_input(steps, "d_left", self)[a:b]))
        sigma_r = self.k_right * np.sqrt(np.abs(steps_input(steps, "d_right", self)[a:b]))
        base = steps.robot.effective_wheel_base  # type: ignore[union-attr]
        # Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b, Borenstein–Feng (2.2)–(2.4)
        return np.stack([np.stack([0.5 * sigma_l, 0.5 * sigma_r], axis=-1),
                         np.stack([-sigma_l / base, sigma_r / base], axis=-1)], axis=-2)

    def compiled_inputs(self, steps: BodySteps) -> WheelInputs:
        """The wheel travels and :func:`wheel_cov_coefficients`: the numba recursion forms
        each Q_k itself from these (no (M, 2, 2) array)."""
        return WheelInputs(steps_input(steps, "d_left", self), steps_input(steps, "d_right", self),
                           wheel_cov_coefficients(steps.robot.effective_wheel_base,  # type: ignore[union-attr]
                                                  self))


@register
@dataclass(frozen=True)
class ClassicalNoise(NoiseModel):
    """The classical model, Chong–Kleeman eq. (1)–(3): independent translation and
    rotation errors per *step*, whatever the step's length.

    Kept so users can see its inconsistency: its covariance depends on how a path is cut
    into steps (Chong–Kleeman section 1, the 2D vs D+D example).

    Parameters
    ----------
    sigma_distance : float
        Standard deviation of each step's translation D_k [m].
    sigma_angle : float
        Standard deviation of each step's rotation α_k [rad].
    """

    sigma_distance: float
    sigma_angle: float

    family: ClassVar[str | None] = "classical"
    step_map: ClassVar[str | None] = "classical"

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(σ_D², σ_α²) of every step, (n, 2)."""
        return np.broadcast_to(np.array([self.sigma_distance**2, self.sigma_angle**2]), (b - a, 2))

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """The identity: the raw inputs are (D, α) themselves, (n, 2, 2)."""
        return np.broadcast_to(np.eye(2), (b - a, 2, 2))

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`classical_input_cov` of steps a … b−1."""
        return classical_input_cov(b - a, self)


@dataclass(frozen=True)
class WheelInputs:
    """Per-wheel noise of a whole log in the form a compiled engine consumes: the wheel
    travels d_left, d_right (M,) [m] and :func:`wheel_cov_coefficients` (5,).

    Examples
    --------
    >>> w = WheelInputs(np.array([1.0]), np.array([1.0]),
    ...                 wheel_cov_coefficients(0.5, WheelNoise(0.1, 0.1)))
    >>> np.array_equal(w.cov_input(0, 1), wheel_input_cov([1.0], [1.0], 0.5, WheelNoise(0.1, 0.1)))
    True
    """

    d_left: NDArray[np.float64]
    d_right: NDArray[np.float64]
    coefficients: NDArray[np.float64]

    def cov_input(self, a: int, b: int) -> NDArray[np.float64]:
        """:func:`wheel_input_cov` of steps a … b−1, (b − a, 2, 2)."""
        k_l2, k_r2, j00_sq, j01_j11, j11_sq = self.coefficients
        var_l = np.abs(self.d_left[a:b]) * k_l2
        var_r = np.abs(self.d_right[a:b]) * k_r2
        var_sum = var_l + var_r
        return sym2(j00_sq * var_sum, j01_j11 * (var_r - var_l), j11_sq * var_sum)


def wheel_cov_coefficients(wheel_base: float, noise: WheelNoise) -> NDArray[np.float64]:
    """(k_L², k_R², J00², J01·J11, J11²), J = ∂(Δd, Δθ)/∂(d_L, d_R): the constants of
    :func:`wheel_input_cov`, shared with the numba kernel so both give the same bits.

    Examples
    --------
    >>> wheel_cov_coefficients(0.5, WheelNoise(0.1, 0.2)).round(6).tolist()
    [0.01, 0.04, 0.25, 1.0, 4.0]
    """
    jac = diff_body_jacobian(wheel_base)
    return np.array([noise.k_left**2, noise.k_right**2, jac[0, 0] ** 2,
                     jac[0, 1] * jac[1, 1], jac[1, 1] ** 2])


def wheel_input_cov(
    d_left: ArrayLike, d_right: ArrayLike, wheel_base: float, noise: WheelNoise
) -> NDArray[np.float64]:
    """Per-wheel white noise -> Cov(Δd, Δθ) of each step.

    Cov(d_L, d_R) = diag(k_L²|d_L|, k_R²|d_R|) (Chong–Kleeman eq. 4), mapped by the
    constant Jacobian J = ∂(Δd, Δθ)/∂(d_L, d_R) = [[½, ½], [−1/b, 1/b]]
    (Borenstein–Feng eq. 2.2–2.4): Q = J diag Jᵀ.

    Parameters
    ----------
    d_left, d_right : array_like, shape (M,)
        Wheel travel of each step [m].
    wheel_base : float
        Effective wheel base b [m].
    noise : WheelNoise
        k_left, k_right [m^½].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)
        [m², m·rad; m·rad, rad²].

    Examples
    --------
    >>> q = wheel_input_cov([1.0], [1.0], 0.5, WheelNoise(0.1, 0.1))
    >>> np.allclose(q[0], [[0.005, 0.0], [0.0, 0.08]])
    True
    """
    k_l2, k_r2, j00_sq, j01_j11, j11_sq = wheel_cov_coefficients(wheel_base, noise)
    var_l = np.abs(np.asarray(d_left, dtype=float))
    var_l *= k_l2
    var_r = np.abs(np.asarray(d_right, dtype=float))
    var_r *= k_r2
    # The Sun–Gao exercise prints Σ_ΔdΔθ = diag((σr²+σl²)/4, (σr²−σl²)/L²): wrong. The
    # θθ entry is (σr²+σl²)/b² (variances add), and the off-diagonal is (σr²−σl²)/(2b),
    # not 0. Its J_x also swaps sin and cos in the θ column; the engines use
    # [−Δy, Δx] (kinematics.step_jacobians), checked by finite differences.
    # J diag(var_l, var_r) Jᵀ written out with J = [[½, ½], [−1/b, 1/b]]: no (M, 2, 2)
    # temporaries, few passes. The numba kernel (propagate/_numba.py, QMODE_WHEEL)
    # repeats these operations in this order; keep the two in step.
    var_sum = var_l + var_r
    var_diff = var_r
    var_diff -= var_l
    return sym2(j00_sq * var_sum, j01_j11 * var_diff, j11_sq * var_sum)


def classical_input_cov(m: int, noise: ClassicalNoise) -> NDArray[np.float64]:
    """The classical model's Cov(D_k, α_k) = diag(σ_D², σ_α²), the same for every step.

    Chong–Kleeman eq. (3). It must be propagated with the classical step map, rotation
    α then translation D (eq. 1), i.e. ``method="classical"`` in the engines. Its
    covariance depends on how a path is cut into steps (Chong–Kleeman section 1: one
    step of 2D and two of D differ); odomkit keeps it only to show that.

    Returns
    -------
    cov_input : ndarray, shape (m, 2, 2)
        [m², m·rad; m·rad, rad²].

    Examples
    --------
    >>> classical_input_cov(2, ClassicalNoise(0.1, 0.01))[1].tolist()
    [[0.010000000000000002, 0.0], [0.0, 0.0001]]
    """
    return sym2(np.full(m, noise.sigma_distance**2), np.zeros(m),
                np.full(m, noise.sigma_angle**2))
