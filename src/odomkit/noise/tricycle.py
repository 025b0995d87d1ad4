"""Steered-vehicle noise (tricycle and car): white noise on each sample's speed, steering
angle and period (Sun–Gao, Snowhite part; the car's kinematics instead of the tricycle's
for a car)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.kinematics import car_body_jacobian
from odomkit.noise.base import NoiseModel, register, require_non_negative, steps_input

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps

__all__ = ["TricycleNoise", "car_input_jacobian", "tricycle_input_jacobian", "tricycle_input_cov",
           "tricycle_input_variances"]


@register
@dataclass(frozen=True)
class TricycleNoise(NoiseModel):
    """The exercise's tricycle noise: independent white noise on each sample's speed,
    steering angle and sample period (Sun–Gao, Snowhite part). It is also a car's white
    speed and steering noise: the same raw inputs through the car's kinematics
    (:func:`car_input_jacobian`).

    Parameters
    ----------
    sigma_speed : float
        Standard deviation of the measured wheel speed [m/s] (the tricycle's front wheel,
        the car's measuring wheel; for a ticks channel, of the per-step travelled
        distance divided by the step duration).
    sigma_steer : float
        Standard deviation of the steering angle [rad].
    sigma_dt : float
        Standard deviation of the sample period [s].
    """

    sigma_speed: float
    sigma_steer: float
    sigma_dt: float = 0.0

    robot_types: ClassVar[tuple[str, ...]] = ("tricycle", "car")
    # σ per sample: D/T samples of a stretch of D seconds give var Δs = σ_v²·T·D, so a
    # planned path needs the sample period T (NoiseModel.per_sample).
    per_sample: ClassVar[bool] = True

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(σ_v², σ_α², σ_T²) of every step, (n, 3); σ_v² is 0 where the wheel did not turn
        (:func:`tricycle_input_variances`)."""
        return tricycle_input_variances(steps_input(steps, "travel", self)[a:b], self)

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`tricycle_input_jacobian` (a car: :func:`car_input_jacobian`) of steps
        a … b−1, (n, 2, 3)."""
        travel, steer = steps_input(steps, "travel", self)[a:b], steps_input(steps, "steer", self)[a:b]
        robot = steps.robot
        if robot.type_name == "car":
            return car_input_jacobian(travel, steer, steps.dt[a:b], robot.wheel_base,  # type: ignore[union-attr]
                                      robot.encoder_offset, robot.encoder_at)  # type: ignore[union-attr]
        return tricycle_input_jacobian(travel, steer, steps.dt[a:b],
                                       robot.wheel_to_axle)  # type: ignore[union-attr]

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`tricycle_input_cov` of steps a … b−1 (a car: J diag(σ²) Jᵀ of
        :meth:`input_jacobian`)."""
        if steps.robot.type_name == "car":
            return super().input_cov(steps, a, b)
        return tricycle_input_cov(steps_input(steps, "travel", self)[a:b],
                                  steps_input(steps, "steer", self)[a:b], steps.dt[a:b],
                                  steps.robot.wheel_to_axle, self)  # type: ignore[union-attr]


def tricycle_input_jacobian(
    travel: ArrayLike, steer: ArrayLike, dt: ArrayLike, wheel_to_axle: float
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(v, α, T) of the tricycle step, shape (M, 2, 3).

    With v = s/T the front-wheel speed, Δd = vT·cos α, Δθ = vT·sin α / L (Sun–Gao,
    Snowhite model):

    ``[[T cos α, −vT sin α, v cos α], [T sin α / L, vT cos α / L, v sin α / L]]``.

    Derived again rather than copied: the exercise does not print this J, and its
    printed heading update (vT sin α/(2L) in section 2.2, vT sin α/2 in 3.2) has a
    spurious ½ and a missing L; the heading change is vT sin α / L. Checked against
    finite differences in the tests.
    For a zero-length step (T = 0) the speed is taken as 0.
    """
    s, a, t = np.broadcast_arrays(np.asarray(travel, dtype=float), np.asarray(steer, dtype=float),
                                  np.asarray(dt, dtype=float))
    v = np.divide(s, t, out=np.zeros_like(s), where=t != 0)
    jac = np.empty(s.shape + (2, 3))
    ca, sa = np.cos(a), np.sin(a)
    jac[..., 0, 0] = t * ca
    jac[..., 0, 1] = -s * sa
    jac[..., 0, 2] = v * ca
    jac[..., 1, 0] = t * sa / wheel_to_axle
    jac[..., 1, 1] = s * ca / wheel_to_axle
    jac[..., 1, 2] = v * sa / wheel_to_axle
    return jac


def car_input_jacobian(
    travel: ArrayLike, steer: ArrayLike, dt: ArrayLike, wheel_base: float,
    encoder_offset: float = 0.0, encoder_at: str = "rear",
) -> NDArray[np.float64]:
    """∂(Δd, Δθ)/∂(v, α, T) of a car step (:func:`odomkit.kinematics.car_body_steps`),
    shape (M, 2, 3), with v = s/T the measuring wheel's speed: the body motion depends on
    v and T through s = vT only, so ∂/∂v = T·∂/∂s, ∂/∂T = v·∂/∂s, and ∂/∂α is the car's
    (:func:`odomkit.kinematics.car_body_jacobian`). For T = 0 the speed is taken as 0.
    """
    s, t = np.broadcast_arrays(np.asarray(travel, dtype=float), np.asarray(dt, dtype=float))
    v = np.divide(s, t, out=np.zeros_like(s), where=t != 0)
    body = car_body_jacobian(s, steer, wheel_base, encoder_offset, encoder_at)
    jac = np.empty(body.shape)
    jac[..., 0] = body[..., 0] * t[..., None]
    jac[..., 1] = body[..., 1]
    jac[..., 2] = body[..., 0] * v[..., None]
    return jac


def tricycle_input_cov(
    travel: ArrayLike, steer: ArrayLike, dt: ArrayLike, wheel_to_axle: float, noise: TricycleNoise
) -> NDArray[np.float64]:
    """Tricycle speed, steering and sample-period noise -> Cov(Δd, Δθ) per step.

    Q = J diag(σ_v², σ_α², σ_T²) Jᵀ with J from :func:`tricycle_input_jacobian`
    (Sun–Gao, Snowhite part, Σ_vαT; independent white noise on each sample).

    Parameters
    ----------
    travel : array_like, shape (M,)
        Front-wheel travel s = v·T [m].
    steer : array_like, shape (M,)
        Steering angle [rad].
    dt : array_like, shape (M,)
        Sample period T [s].
    wheel_to_axle : float
        L [m].
    noise : TricycleNoise
        sigma_speed [m/s], sigma_steer [rad], sigma_dt [s].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)

    Examples
    --------
    >>> q = tricycle_input_cov([0.1], [0.0], [0.1], 1.0, TricycleNoise(0.01, 0.02))
    >>> np.allclose(q[0], [[1e-6, 0.0], [0.0, 4e-6]])
    True
    """
    jac = tricycle_input_jacobian(travel, steer, dt, wheel_to_axle)
    var = tricycle_input_variances(travel, noise)
    return np.einsum("...ik,...k,...jk->...ij", jac, var, jac)


def tricycle_input_variances(travel: ArrayLike, noise: TricycleNoise) -> NDArray[np.float64]:
    """(σ_v², σ_α², σ_T²) of each step, shape (M, 3), with σ_v² = 0 where the measured
    travel is exactly 0.

    A wheel encoder that reads no travel over a step says the vehicle stood still: its
    speed error (quantisation, slip) is zero then, not σ_v. Without this a vehicle that
    stands still (OptiOdom's tricycle squares stand 35–40 % of the time at the corners)
    gathers position variance T²σ_v² per step while it stands, which the truth does not
    show (issue 11). The steering and period terms vanish there anyway (∂/∂α, ∂/∂T ∝ s).

    Examples
    --------
    >>> tricycle_input_variances([0.0, 0.1], TricycleNoise(0.1, 0.2))[:, 0]
    array([0.  , 0.01])
    """
    s = np.asarray(travel, dtype=float)
    var = np.empty(s.shape + (3,))
    var[..., 0] = np.where(s != 0.0, noise.sigma_speed**2, 0.0)
    var[..., 1] = noise.sigma_steer**2
    var[..., 2] = noise.sigma_dt**2
    return var
