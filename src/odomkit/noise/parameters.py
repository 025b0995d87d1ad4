"""Uncertain robot parameters (wheel base, wheel scales) as a noise model.

A wrong wheel base or wheel diameter is the *same* error at every step of a run: in
``mode="bias"`` it is a constant unknown parameter (an augmented state) whose pose
covariance grows with the square of the distance; ``mode="white"`` draws fresh noise
every step, as the Sun–Gao exercise does (it understates long runs; kept for comparison).

Each robot type has its own sensitivity ∂(Δd, Δθ)/∂β, looked up by the robot's type name.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.noise.base import NoiseKind, NoiseModel, register, require_non_negative, steps_input

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps
    from odomkit.robot import Robot

__all__ = [
    "ParameterUncertainty",
    "diff_parameter_jacobian",
    "tricycle_parameter_jacobian",
    "scale_parameter_jacobian",
    "white_parameter_cov",
]


@register
@dataclass(frozen=True)
class ParameterUncertainty(NoiseModel):
    """Uncertain robot parameters (wheel base, wheel scales).

    A wrong wheel base or wheel diameter is the *same* error at every step of a run. With
    ``mode="bias"`` it is modelled as a constant unknown parameter (an augmented state),
    so its pose covariance grows with the square of the distance. ``mode="white"`` draws
    fresh noise every step, as the Sun–Gao exercise does; that understates long runs and
    is kept only for comparison.

    Parameters
    ----------
    sigma_wheel_base : float
        Standard deviation of the wheel base (diff) or of L (tricycle) [m].
    sigma_scale_left, sigma_scale_right : float
        Relative standard deviation of each wheel's metres-per-tick (dimensionless; a
        wheel-diameter σ divided by the diameter). For single-wheel robots use
        ``sigma_scale_left`` for the traction wheel.
    mode : {"bias", "white"}
    """

    sigma_wheel_base: float = 0.0
    sigma_scale_left: float = 0.0
    sigma_scale_right: float = 0.0
    mode: Literal["bias", "white"] = "bias"

    toml_table: ClassVar[str] = "noise.parameters"

    def __post_init__(self) -> None:
        require_non_negative(self)
        if self.mode not in ("bias", "white"):
            raise ModelError(f"ParameterUncertainty.mode must be 'bias' or 'white', got {self.mode!r}")

    @property
    def kind(self) -> NoiseKind:
        """The ``mode``."""
        return self.mode

    def check_robot(self, robot: Robot) -> None:
        """Which parameters apply depends on the robot (see :meth:`bias_variances`)."""
        self.bias_variances(robot)

    def bias_variances(self, robot: Robot) -> NDArray[np.float64]:
        """diff: (σ_b², σ_εL², σ_εR²); tricycle: (σ_L², σ_ε²); gyro, compass: (σ_ε²)."""
        if robot.type_name == "diff":
            return np.array([self.sigma_wheel_base, self.sigma_scale_left,
                             self.sigma_scale_right]) ** 2
        if robot.type_name == "tricycle":
            if self.sigma_scale_right:
                raise ModelError("ParameterUncertainty.sigma_scale_right: a tricycle has one "
                                 "traction wheel; use sigma_scale_left")
            return np.array([self.sigma_wheel_base, self.sigma_scale_left]) ** 2
        if self.sigma_wheel_base or self.sigma_scale_right:
            raise ModelError(f"ParameterUncertainty for a {type(robot).__name__}: only "
                             "sigma_scale_left (the distance scale) applies")
        return np.array([self.sigma_scale_left**2])

    def bias_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """K = ∂(Δd, Δθ)/∂β of steps a … b−1, (n, 2, p), for the robot's parameters."""
        return _SENSITIVITY.get(steps.robot.type_name, _scale_sensitivity)(self, steps, a, b)

    # In white mode the parameters are fresh every step: the same K and variances.
    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """White mode: the parameter variances at every step, (n, p)."""
        return np.broadcast_to(self.bias_variances(steps.robot), (b - a, self._p(steps)))

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """White mode: K of :meth:`bias_jacobian`."""
        return self.bias_jacobian(steps, a, b)

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`white_parameter_cov` of steps a … b−1."""
        return white_parameter_cov(self.bias_jacobian(steps, a, b), self.bias_variances(steps.robot))

    def _p(self, steps: BodySteps) -> int:
        return int(self.bias_variances(steps.robot).size)


def _diff_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    return diff_parameter_jacobian(steps_input(steps, "d_left", pu)[a:b],
                                   steps_input(steps, "d_right", pu)[a:b],
                                   steps.robot.effective_wheel_base)  # type: ignore[union-attr]


def _tricycle_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    return tricycle_parameter_jacobian(steps_input(steps, "travel", pu)[a:b],
                                       steps_input(steps, "steer", pu)[a:b],
                                       steps.robot.wheel_to_axle)  # type: ignore[union-attr]


def _scale_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    return scale_parameter_jacobian(np.asarray(steps.dd, dtype=float)[a:b])


_SENSITIVITY: dict[str, Callable[[ParameterUncertainty, BodySteps, int, int], NDArray[np.float64]]] = {
    "diff": _diff_sensitivity,
    "tricycle": _tricycle_sensitivity,
}


def diff_parameter_jacobian(
    d_left: ArrayLike, d_right: ArrayLike, wheel_base: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(b, ε_L, ε_R), shape (M, 2, 3), differential drive.

    b is the wheel base [m]; ε_L, ε_R are relative wheel-scale errors (a wheel travels
    d·(1 + ε)). From Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b (Borenstein–Feng 2.2–2.4):
    ``[[0, d_L/2, d_R/2], [−Δθ/b, −d_L/b, d_R/b]]``.
    """
    d_l, d_r = np.broadcast_arrays(np.asarray(d_left, dtype=float), np.asarray(d_right, dtype=float))
    jac = np.zeros(d_l.shape + (2, 3))
    jac[..., 0, 1] = 0.5 * d_l
    jac[..., 0, 2] = 0.5 * d_r
    jac[..., 1, 0] = -(d_r - d_l) / wheel_base**2
    jac[..., 1, 1] = -d_l / wheel_base
    jac[..., 1, 2] = d_r / wheel_base
    return jac


def tricycle_parameter_jacobian(
    travel: ArrayLike, steer: ArrayLike, wheel_to_axle: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(L, ε), shape (M, 2, 2): L [m] and the traction-wheel scale ε.

    Δd = s(1+ε)cos α, Δθ = s(1+ε) sin α / L: ``[[0, Δd], [−Δθ/L, Δθ]]``.
    """
    s, a = np.broadcast_arrays(np.asarray(travel, dtype=float), np.asarray(steer, dtype=float))
    dd = s * np.cos(a)
    dtheta = s * np.sin(a) / wheel_to_axle
    jac = np.zeros(s.shape + (2, 2))
    jac[..., 0, 1] = dd
    jac[..., 1, 0] = -dtheta / wheel_to_axle
    jac[..., 1, 1] = dtheta
    return jac


def scale_parameter_jacobian(dd: ArrayLike) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂ε, shape (M, 2, 1), for a single distance scale ε (gyro/compass)."""
    dd = np.asarray(dd, dtype=float)
    jac = np.zeros(dd.shape + (2, 1))
    jac[..., 0, 0] = dd
    return jac


def white_parameter_cov(jac: ArrayLike, var_params: ArrayLike) -> NDArray[np.float64]:
    """Parameter uncertainty treated as fresh white noise at every step (the Sun–Gao
    exercise's treatment): Q = K diag(var) Kᵀ, shape (M, 2, 2).

    This understates long runs: a wrong wheel base is the same error at every step.
    Use the bias mode (:func:`odomkit.propagate.transition.parameter_sensitivity`)
    for a physical prediction.
    """
    jac = np.asarray(jac, dtype=float)
    return np.einsum("...ik,k,...jk->...ij", jac, np.asarray(var_params, dtype=float), jac)
