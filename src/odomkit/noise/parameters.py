"""Uncertain robot parameters (the bias noise of every vehicle) as a noise model.

A wrong wheel base, wheel diameter, steering offset or gyro offset is the *same* error at
every step of a run: in ``mode="bias"`` it is a constant unknown parameter (an augmented
state) whose pose covariance grows with the square of the distance; ``mode="white"``
draws fresh noise every step, as the Sun–Gao exercise does (it understates long runs;
kept for comparison).

Which parameters a vehicle has, and their order in the parameter vector β, is
:data:`PARAMETERS` (keyed by the robot's type name); each vehicle's sensitivity
∂(Δd, Δθ)/∂β is looked up the same way (:data:`_SENSITIVITY`):

==========  ===================================  ===========================================
vehicle     β                                    fields (σ of each, in this order)
==========  ===================================  ===========================================
diff        wheel base b [m]; left, right        sigma_wheel_base, sigma_scale_left,
            wheel scale ε_L, ε_R [1]             sigma_scale_right
tricycle,   wheel base L [m]; measuring-wheel    sigma_wheel_base, sigma_scale_left,
car         scale ε [1]; steering offset δα      sigma_steering_offset
            [rad]
gyro,       speed scale ε [1]; yaw-rate offset   sigma_scale_left, sigma_yaw_rate_offset,
unicycle    δω [rad/s]; yaw-rate scale ε_ω [1]   sigma_yaw_rate_scale
compass     speed scale ε [1]; heading offset    sigma_scale_left, sigma_heading_offset
            δh [rad]
==========  ===================================  ===========================================

A heading offset does not change any step (Δθ is a difference of two measured headings);
it moves every measured heading, θ_k = θ_meas,k + δh, which the direct-heading engine
carries as :meth:`ParameterUncertainty.bias_heading`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError
from odomkit.kinematics import car_body_jacobian, unicycle_moving
from odomkit.noise.base import NoiseKind, NoiseModel, register, require_non_negative, steps_input

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps
    from odomkit.robot import Robot

__all__ = [
    "PARAMETERS",
    "ParameterUncertainty",
    "car_parameter_jacobian",
    "diff_parameter_jacobian",
    "rate_parameter_jacobian",
    "tricycle_parameter_jacobian",
    "scale_parameter_jacobian",
    "white_parameter_cov",
]

_STEERED = ("sigma_wheel_base", "sigma_scale_left", "sigma_steering_offset")
_RATE = ("sigma_scale_left", "sigma_yaw_rate_offset", "sigma_yaw_rate_scale")
PARAMETERS: dict[str, tuple[str, ...]] = {
    "diff": ("sigma_wheel_base", "sigma_scale_left", "sigma_scale_right"),
    "tricycle": _STEERED,
    "car": _STEERED,
    "gyro": _RATE,
    "unicycle": _RATE,
    "compass": ("sigma_scale_left", "sigma_heading_offset"),
}
"""The bias parameters of each vehicle (robot type name), in the order of β."""


@register
@dataclass(frozen=True)
class ParameterUncertainty(NoiseModel):
    """Uncertain robot parameters: the bias (constant over a run) of every vehicle.

    A wrong wheel base or wheel diameter is the *same* error at every step of a run. With
    ``mode="bias"`` it is modelled as a constant unknown parameter (an augmented state),
    so its pose covariance grows with the square of the distance. ``mode="white"`` draws
    fresh noise every step, as the Sun–Gao exercise does; that understates long runs and
    is kept only for comparison. Each vehicle has the parameters of :data:`PARAMETERS`; a
    non-zero σ of a parameter the vehicle does not have is refused, not ignored.

    Parameters
    ----------
    sigma_wheel_base : float
        Standard deviation of the wheel base: b (diff), L (tricycle ``wheel_to_axle``,
        car ``wheel_base``) [m].
    sigma_scale_left, sigma_scale_right : float
        Relative standard deviation of each wheel's metres-per-tick (dimensionless; a
        wheel-diameter σ divided by the diameter). For single-wheel robots
        ``sigma_scale_left`` is the scale of the measured distance or speed (the traction
        or measuring wheel, the speed of a unicycle, gyro or compass robot).
    mode : {"bias", "white"}
    sigma_steering_offset : float
        Standard deviation of a constant steering-angle error (tricycle, car) [rad].
    sigma_yaw_rate_offset : float
        Standard deviation of a constant error added to the yaw rate (gyro, unicycle)
        [rad/s].
    sigma_yaw_rate_scale : float
        Relative standard deviation of the yaw-rate scale (gyro, unicycle) [1].
    sigma_heading_offset : float
        Standard deviation of a constant error of every measured heading (compass) [rad];
        bias mode only (a fresh heading error at every sample is
        :class:`~odomkit.noise.CompassNoise`).
    """

    sigma_wheel_base: float = 0.0
    sigma_scale_left: float = 0.0
    sigma_scale_right: float = 0.0
    mode: Literal["bias", "white"] = "bias"
    sigma_steering_offset: float = 0.0
    sigma_yaw_rate_offset: float = 0.0
    sigma_yaw_rate_scale: float = 0.0
    sigma_heading_offset: float = 0.0

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

    def parameters(self, robot: Robot) -> tuple[str, ...]:
        """The field names of ``robot``'s bias parameters, in the order of β."""
        try:
            return PARAMETERS[robot.type_name]
        except (KeyError, AttributeError):
            raise ModelError(f"ParameterUncertainty knows no parameters of a "
                             f"{type(robot).__name__}") from None

    def bias_variances(self, robot: Robot) -> NDArray[np.float64]:
        """σ² of each of ``robot``'s parameters (:data:`PARAMETERS`), (p,); a ModelError
        names a non-zero σ the robot has no parameter for."""
        names = self.parameters(robot)
        for name in PARAMETERS["diff"] + _STEERED + _RATE + ("sigma_heading_offset",):
            if name not in names and getattr(self, name):
                hint = ("; a tricycle has one traction wheel: use sigma_scale_left"
                        if name == "sigma_scale_right" and robot.type_name == "tricycle" else
                        "; its one measured wheel or speed is sigma_scale_left"
                        if name == "sigma_scale_right" else "")
                raise ModelError(f"ParameterUncertainty.{name} does not apply to a {type(robot).__name__}, "
                                 f"whose parameters are {', '.join(names)}{hint}")
        if self.mode == "white" and self.sigma_heading_offset:
            raise ModelError("ParameterUncertainty.sigma_heading_offset is a bias only: a fresh "
                             "heading error at every sample is CompassNoise")
        return np.array([getattr(self, name) for name in names], dtype=float) ** 2

    def bias_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """K = ∂(Δd, Δθ)/∂β of steps a … b−1, (n, 2, p), for the robot's parameters."""
        try:
            sensitivity = _SENSITIVITY[steps.robot.type_name]
        except KeyError:
            raise ModelError(f"ParameterUncertainty has no sensitivity for a "
                             f"{type(steps.robot).__name__}") from None
        return sensitivity(self, steps, a, b)

    def bias_heading(self, robot: Robot) -> NDArray[np.float64]:
        """∂θ_k/∂β of every measured heading, (p,): 1 for the compass heading offset, 0
        otherwise (and for every integrated-heading vehicle)."""
        names = self.parameters(robot)
        out = np.zeros(len(names))
        if robot.measures_heading:
            out[[i for i, n in enumerate(names) if n == "sigma_heading_offset"]] = 1.0
        return out

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
    travel, steer = steps_input(steps, "travel", pu)[a:b], steps_input(steps, "steer", pu)[a:b]
    jac = np.empty((b - a, 2, 3))
    jac[..., :2] = tricycle_parameter_jacobian(travel, steer, steps.robot.wheel_to_axle)  # type: ignore[union-attr]
    # δα: ∂(s cos α, s sin α / L)/∂α (kinematics.tricycle_body_jacobian)
    jac[..., 0, 2] = -travel * np.sin(steer)
    jac[..., 1, 2] = travel * np.cos(steer) / steps.robot.wheel_to_axle  # type: ignore[union-attr]
    return jac


def _car_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    robot = steps.robot
    return car_parameter_jacobian(steps_input(steps, "travel", pu)[a:b],
                                  steps_input(steps, "steer", pu)[a:b], robot.wheel_base,  # type: ignore[union-attr]
                                  robot.encoder_offset, robot.encoder_at)  # type: ignore[union-attr]


def _rate_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    return rate_parameter_jacobian(steps.dd[a:b], steps.dtheta[a:b], steps.dt[a:b])


def _unicycle_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    # A standing base (no travel, no yaw rate) is not turned by a yaw-rate offset.
    moving = unicycle_moving(steps.dd[a:b], steps.inputs["yaw_rate"][a:b])
    return rate_parameter_jacobian(steps.dd[a:b], steps.dtheta[a:b], np.where(moving, steps.dt[a:b], 0.0))


def _compass_sensitivity(pu: ParameterUncertainty, steps: BodySteps, a: int, b: int):
    # The heading offset moves no step (Δθ = h_{k+1} − h_k): its column is zero, and it
    # enters through bias_heading.
    jac = np.zeros((b - a, 2, 2))
    jac[..., :1] = scale_parameter_jacobian(np.asarray(steps.dd, dtype=float)[a:b])
    return jac


_SENSITIVITY: dict[str, Callable[[ParameterUncertainty, BodySteps, int, int], NDArray[np.float64]]] = {
    "diff": _diff_sensitivity,
    "tricycle": _tricycle_sensitivity,
    "car": _car_sensitivity,
    "gyro": _rate_sensitivity,
    "unicycle": _unicycle_sensitivity,
    "compass": _compass_sensitivity,
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


def car_parameter_jacobian(
    travel: ArrayLike, steer: ArrayLike, wheel_base: float, encoder_offset: float = 0.0,
    encoder_at: str = "rear",
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(L, ε, δα), shape (M, 2, 3), of a car
    (:func:`odomkit.kinematics.car_body_steps`): the wheel base L [m], the measuring
    wheel's scale ε (it travels s(1 + ε), so the column is (Δd, Δθ)) and a steering
    offset δα [rad] (α + δα): the L and α columns of
    :func:`odomkit.kinematics.car_body_jacobian`, and s times its s column.
    """
    s = np.asarray(travel, dtype=float)
    body = car_body_jacobian(s, steer, wheel_base, encoder_offset, encoder_at)
    jac = np.empty(body.shape)
    jac[..., 0] = body[..., 2]
    jac[..., 1] = body[..., 0] * s[..., None]
    jac[..., 2] = body[..., 1]
    return jac


def rate_parameter_jacobian(dd: ArrayLike, dtheta: ArrayLike, dt: ArrayLike) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(ε, δω, ε_ω), shape (M, 2, 3), of speed and yaw-rate odometry (gyro,
    unicycle): Δd = v·Δt·(1 + ε), Δθ = (ω·(1 + ε_ω) + δω)·Δt, so
    ``[[Δd, 0, 0], [0, Δt, Δθ]]``.
    """
    dd, dtheta, dt = np.broadcast_arrays(np.asarray(dd, dtype=float), np.asarray(dtheta, dtype=float),
                                         np.asarray(dt, dtype=float))
    jac = np.zeros(dd.shape + (2, 3))
    jac[..., 0, 0] = dd
    jac[..., 1, 1] = dt
    jac[..., 1, 2] = dtheta
    return jac


def scale_parameter_jacobian(dd: ArrayLike) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂ε, shape (M, 2, 1), for a single distance scale ε."""
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
