"""A log's noise models -> what the propagation engines need (:func:`plan_noise`).

:mod:`odomkit.propagate.inputs` maps one noise model onto the per-step input covariance
Q_k of given steps. This module decides, for the :class:`~odomkit.kinematics.BodySteps`
of a whole log and a noise model or tuple of models, which of those mappings apply: it
checks each model against the robot, picks the step map, sums the independent white
sources, separates bias-mode parameters and direct-heading (compass) odometry, and hands
the engines a :class:`NoisePlan` whose functions take a step range, so nothing of size
M×2×2 is built for the whole log. It is kept apart from ``inputs`` because it is
bookkeeping over models and robots, not mathematics of one model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import ModelError
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    NoiseModel,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.propagate.inputs import (
    ENGINE_METHODS,
    _sym2,
    classical_input_cov,
    diff_parameter_jacobian,
    direct_heading_variances,
    scale_parameter_jacobian,
    speed_gyro_input_cov,
    tricycle_input_cov,
    tricycle_parameter_jacobian,
    wheel_cov_coefficients,
    white_parameter_cov,
)
from odomkit.robot import CompassOdometry, DiffDrive, Tricycle

# --- a log's noise models -> per-chunk inputs of the engines --------------------------

InputFn = Callable[[int, int], NDArray[np.float64]]


@dataclass(frozen=True)
class WheelInputs:
    """Per-wheel noise of a whole log in the form a compiled engine consumes: the wheel
    travels d_left, d_right (M,) [m] and
    :func:`~odomkit.propagate.inputs.wheel_cov_coefficients` (5,).

    >>> from odomkit.propagate.inputs import wheel_input_cov
    >>> w = WheelInputs(np.array([1.0]), np.array([1.0]),
    ...                 wheel_cov_coefficients(0.5, WheelNoise(0.1, 0.1)))
    >>> np.array_equal(w.cov_input(0, 1), wheel_input_cov([1.0], [1.0], 0.5, WheelNoise(0.1, 0.1)))
    True
    """

    d_left: NDArray[np.float64]
    d_right: NDArray[np.float64]
    coefficients: NDArray[np.float64]

    def cov_input(self, a: int, b: int) -> NDArray[np.float64]:
        """:func:`~odomkit.propagate.inputs.wheel_input_cov` of steps a … b−1, (b − a, 2, 2)."""
        k_l2, k_r2, j00_sq, j01_j11, j11_sq = self.coefficients
        var_l = np.abs(self.d_left[a:b]) * k_l2
        var_r = np.abs(self.d_right[a:b]) * k_r2
        var_sum = var_l + var_r
        return _sym2(j00_sq * var_sum, j01_j11 * (var_r - var_l), j11_sq * var_sum)


@dataclass(frozen=True)
class NoisePlan:
    """What the engines need from a set of noise models for one log (built by
    :func:`plan_noise`). Functions take a step range [a, b) so nothing of size M×2×2
    is ever built for the whole log.

    Attributes
    ----------
    method : str
        Step map of the engines ("classical" for ClassicalNoise).
    direct : bool
        Direct-heading (compass) odometry: heading measured, not integrated.
    var_heading : ndarray, shape (M + 1,), or None
        Direct heading: variance of each heading sample [rad²].
    var_params : ndarray, shape (p,), or None
        Bias-mode parameter variances; None when there is no bias term.
    wheel : WheelInputs or None
        Set when per-wheel noise is the only white source, so that the numba recursion
        can form Q_k itself; ``white`` then holds the same model as a function.
    """

    method: str
    direct: bool
    white: tuple[InputFn, ...]
    var_heading: NDArray[np.float64] | None = None
    var_params: NDArray[np.float64] | None = None
    param_jac: InputFn | None = None
    wheel: WheelInputs | None = None

    def cov_input(self, a: int, b: int) -> NDArray[np.float64]:
        """Summed white input covariance of steps a … b−1, (b − a, 2, 2)."""
        if len(self.white) == 1:
            return self.white[0](a, b)
        q = np.zeros((b - a, 2, 2))
        for fn in self.white:
            q += fn(a, b)
        return q

    def var_dd(self, a: int, b: int) -> NDArray[np.float64]:
        """Variance of Δd of steps a … b−1 [m²] (direct heading)."""
        return self.cov_input(a, b)[:, 0, 0]

    def param_jacobian(self, a: int, b: int) -> NDArray[np.float64]:
        """K = ∂(Δd, Δθ)/∂β of steps a … b−1, (b − a, 2, p)."""
        assert self.param_jac is not None
        return self.param_jac(a, b)


def _input(steps: Any, key: str) -> NDArray[np.float64]:
    try:
        return np.asarray(steps.inputs[key], dtype=float)
    except KeyError:
        raise ModelError(f"this noise model needs the per-step input {key!r}, which the "
                         f"steps of a {type(steps.robot).__name__} do not have") from None


def _require_robot(model: object, robot: object, cls: type) -> None:
    if not isinstance(robot, cls):
        raise ModelError(f"{type(model).__name__} applies to a {cls.__name__} robot, "
                         f"not a {type(robot).__name__}")


def _parameters(steps: Any, pu: ParameterUncertainty):
    """(K(a, b), variances) of the robot's uncertain parameters."""
    robot = steps.robot
    if isinstance(robot, DiffDrive):
        d_l, d_r = _input(steps, "d_left"), _input(steps, "d_right")
        b = robot.effective_wheel_base
        var = np.array([pu.sigma_wheel_base, pu.sigma_scale_left, pu.sigma_scale_right]) ** 2
        return (lambda i, j: diff_parameter_jacobian(d_l[i:j], d_r[i:j], b)), var
    if isinstance(robot, Tricycle):
        s, a = _input(steps, "travel"), _input(steps, "steer")
        if pu.sigma_scale_right:
            raise ModelError("ParameterUncertainty.sigma_scale_right: a tricycle has one "
                             "traction wheel; use sigma_scale_left")
        var = np.array([pu.sigma_wheel_base, pu.sigma_scale_left]) ** 2
        length = robot.wheel_to_axle
        return (lambda i, j: tricycle_parameter_jacobian(s[i:j], a[i:j], length)), var
    if pu.sigma_wheel_base or pu.sigma_scale_right:
        raise ModelError(f"ParameterUncertainty for a {type(robot).__name__}: only "
                         "sigma_scale_left (the distance scale) applies")
    dd = np.asarray(steps.dd, dtype=float)
    return (lambda i, j: scale_parameter_jacobian(dd[i:j])), np.array([pu.sigma_scale_left**2])


def plan_noise(steps: Any, noise: Any, method: str = "exact") -> NoisePlan:
    """Check a noise model (or tuple of them) against a log's robot and plan the engines.

    Combinations (each model at most once):

    - DiffDrive: WheelNoise, ParameterUncertainty (wheel base, both wheel scales)
    - Tricycle: TricycleNoise, ParameterUncertainty (L = wheel_base, traction scale)
    - GyroOdometry: SpeedNoise, GyroNoise, ParameterUncertainty (distance scale)
    - CompassOdometry: SpeedNoise, CompassNoise, ParameterUncertainty (distance scale),
      propagated as direct-heading odometry
    - any robot: ClassicalNoise alone (with its own step map), SpeedNoise

    Independent white sources add their input covariances; bias-mode parameters add
    S diag(σ²) S^T on top.
    """
    if method not in ENGINE_METHODS[:3]:
        raise ModelError(f"unknown method {method!r}; expected exact, midpoint or euler")
    models = noise if isinstance(noise, tuple | list) else (noise,)
    by_type: dict[type, Any] = {}
    for model in models:
        if not isinstance(model, NoiseModel.__args__):  # type: ignore[attr-defined]
            raise ModelError(f"not an odomkit noise model: {type(model).__name__}")
        if type(model) in by_type:
            raise ModelError(f"{type(model).__name__} given twice")
        by_type[type(model)] = model
    robot = steps.robot
    dd = np.asarray(steps.dd, dtype=float)
    dt = np.asarray(steps.dt, dtype=float)
    direct = isinstance(robot, CompassOdometry)
    white: list[InputFn] = []
    wheel: WheelInputs | None = None
    if ClassicalNoise in by_type:
        if len(by_type) > 1:
            raise ModelError("ClassicalNoise has its own step map and cannot be combined")
        cl = by_type[ClassicalNoise]
        return NoisePlan("classical", direct, (lambda a, b: classical_input_cov(b - a, cl),))
    if WheelNoise in by_type:
        _require_robot(by_type[WheelNoise], robot, DiffDrive)
        wn, d_l, d_r = by_type[WheelNoise], _input(steps, "d_left"), _input(steps, "d_right")
        base = robot.effective_wheel_base
        wheel = WheelInputs(d_l, d_r, wheel_cov_coefficients(base, wn))
        white.append(wheel.cov_input)
    if TricycleNoise in by_type:
        _require_robot(by_type[TricycleNoise], robot, Tricycle)
        tn, s, st = by_type[TricycleNoise], _input(steps, "travel"), _input(steps, "steer")
        length = robot.wheel_to_axle
        white.append(lambda a, b: tricycle_input_cov(s[a:b], st[a:b], dt[a:b], length, tn))
    if GyroNoise in by_type and direct:
        raise ModelError("GyroNoise: a CompassOdometry robot measures heading; use CompassNoise")
    if SpeedNoise in by_type or GyroNoise in by_type:
        sp, gy = by_type.get(SpeedNoise), by_type.get(GyroNoise)
        white.append(lambda a, b: speed_gyro_input_cov(dd[a:b], dt[a:b], sp, gy))
    var_heading = None
    if direct:
        var_heading = (direct_heading_variances(dt, by_type[CompassNoise])
                       if CompassNoise in by_type else np.zeros(dd.size + 1))
    elif CompassNoise in by_type:
        raise ModelError("CompassNoise applies to a CompassOdometry robot "
                         f"(direct heading), not a {type(robot).__name__}")
    var_params, param_jac = None, None
    if ParameterUncertainty in by_type:
        pu = by_type[ParameterUncertainty]
        jac, var = _parameters(steps, pu)
        if pu.mode == "white":
            white.append(lambda a, b: white_parameter_cov(jac(a, b), var))
        else:
            var_params, param_jac = var, jac
    only_wheel = wheel if len(white) == 1 and wheel is not None and not direct else None
    return NoisePlan(method, direct, tuple(white), var_heading, var_params, param_jac,
                     only_wheel)
