"""Turn noise: white noise that grows with how far the vehicle turns (unicycle, gyro).

odomkit's other white noise of a speed and yaw-rate vehicle grows with distance
(:class:`~odomkit.noise.SpeedNoise`, var Δd = α_ss·|Δd|) or with time
(:class:`~odomkit.noise.GyroNoise`, var Δθ = σ_gg·Δt). A base driven by commanded
velocities (``cmd_vel``) also executes its *turns* imperfectly: on the UTIAS MRCLAM
robots (iRobot Create bases, Vicon truth) the truth turns 0.84–0.99 times the commanded
turn over 1 s stretches, varying from turn to turn, and travels only 0.6–0.8 times the
commanded distance while turning hard (1.02–1.06 on straights). :class:`TurnNoise` models
both as white noise whose variance grows with the heading change of each step:

======================  ===============================  =================================
term                    error of step k                  variance
======================  ===============================  =================================
``alpha_turn``          heading, δθ_k (enters Δθ)        α_turn·|Δθ_k|        [rad²]
``alpha_turn_travel``   travel, δd_k (enters Δd)         α_turn_travel·|Δθ_k| [m²]
======================  ===============================  =================================

independent of each other, of every other step and of every other model.

**Why linear in |Δθ|: partition invariance.** A turn of Θ cut into n steps of Θ/n gathers
Σ α·|Θ/n| = α·|Θ| whatever n, so the covariance of a turn does not depend on the log's
sample rate (as long as a step does not turn both ways), exactly as α_ss·|Δd| does for
distance. That holds for a commanded or reported turn (a unicycle's ω is a body velocity,
zero where the base stands). A gyro robot's Δθ is its *measured* turn: the gyro's own noise
(and a bias left over) adds |Δθ| while it stands or drives straight, more the faster it is
sampled (over 60 s standing, 0.12 rad at 10 Hz, 0.19 rad at 400 Hz), so ``fit-noise`` fits
this model by default for a unicycle only (:data:`odomkit.calibrate.fit_noise.DEFAULT_WHITE`).

These are the analogues of nav2 AMCL's α1 (rotation error from rotation) and α4
(translation error from rotation) (:mod:`odomkit.calibrate.amcl`), but AMCL's variances
are α·rot² per filter update: quadratic in the increment, so cutting the same turn into
twice as many updates halves its variance, and the α's hold only for the update
thresholds they were tuned at. α_turn and α_turn_travel do not.

On a constant-curvature segment (speed V, yaw rate ω, duration T) the model is the same
as a :class:`~odomkit.noise.GyroNoise` of density α_turn·|ω| plus a
:class:`~odomkit.noise.SpeedNoise` of α_ss = α_turn_travel·|κ| (κ = ω/V), which is how the
closed form of a planned path takes it (:func:`odomkit.propagate.closed_kelly.gyro_arc_cov`);
on a spin in place (V = 0) the travel error moves the robot along its turning heading.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import ModelError
from odomkit.noise.base import NoiseModel, register, require_non_negative, sym2

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps
    from odomkit.robot import Robot

__all__ = ["TurnNoise"]

# ∂(Δd, Δθ)/∂(δθ, δd): the heading error enters Δθ, the travel error Δd.
_JACOBIAN = np.array([[0.0, 1.0], [1.0, 0.0]])


@register
@dataclass(frozen=True)
class TurnNoise(NoiseModel):
    """White noise proportional to the heading change: var δθ = α_turn·|Δθ| and
    var δd = α_turn_travel·|Δθ| over each step (a unicycle or a gyro robot; see the
    module docstring for why, and for the AMCL α1/α4 it stands for).

    Both are *variances* per radian turned (σ² is linear in |Δθ|, σ grows as √|Δθ|);
    either may be zero. A straight step (Δθ = 0), and a unicycle standing still, gathers
    nothing from it.

    Parameters
    ----------
    alpha_turn : float
        Heading variance per radian turned [rad²/rad = rad] (AMCL's α1, rotation from
        rotation, made linear).
    alpha_turn_travel : float
        Travel variance per radian turned [m²/rad] (AMCL's α4, translation from
        rotation, made linear).

    Examples
    --------
    >>> from odomkit.kinematics import BodySteps
    >>> from odomkit.robot import Unicycle
    >>> steps = BodySteps(np.array([0.1, 0.1, 0.0]), np.array([0.0, -0.2, 0.5]),
    ...                   np.full(3, 0.1), {"yaw_rate": np.array([0.0, -2.0, 5.0])}, Unicycle())
    >>> q = TurnNoise(alpha_turn=0.01, alpha_turn_travel=0.002).input_cov(steps, 0, 3)
    >>> q[:, 1, 1].round(12).tolist(), q[:, 0, 0].round(12).tolist()
    ([0.0, 0.002, 0.005], [0.0, 0.0004, 0.001])
    """

    alpha_turn: float = 0.0
    alpha_turn_travel: float = 0.0

    robot_types: ClassVar[tuple[str, ...]] = ("gyro", "unicycle")
    family: ClassVar[str | None] = "gyro"

    def __post_init__(self) -> None:
        require_non_negative(self)

    def check_robot(self, robot: Robot) -> None:
        """A unicycle or gyro robot only: a differential drive's per-wheel noise
        (``k_left``, ``k_right``) already grows with turning, a tricycle's or car's
        steering noise with its steering, and a compass robot measures its heading."""
        try:
            super().check_robot(robot)
        except ModelError as exc:
            why = {"diff": "; a diff robot's per-wheel noise (k_left, k_right) already grows with turning",
                   "tricycle": "; its steering noise (sigma_steer) already grows with turning",
                   "car": "; its steering noise (sigma_steer) already grows with turning",
                   "compass": "; a compass robot measures its heading instead of integrating turns"}
            raise ModelError(f"{exc}{why.get(robot.type_name, '')}") from None

    def _turned(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        return np.abs(np.asarray(steps.dtheta[a:b], dtype=float))

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(α_turn·|Δθ| [rad²], α_turn_travel·|Δθ| [m²]) of each step, (n, 2)."""
        turned = self._turned(steps, a, b)
        return np.stack([self.alpha_turn * turned, self.alpha_turn_travel * turned], axis=-1)

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """The heading error enters Δθ, the travel error Δd: [[0, 1], [1, 0]], (n, 2, 2)."""
        return np.broadcast_to(_JACOBIAN, (b - a, 2, 2))

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """diag(α_turn_travel·|Δθ|, α_turn·|Δθ|) of (Δd, Δθ), (n, 2, 2)."""
        turned = self._turned(steps, a, b)
        return sym2(self.alpha_turn_travel * turned, np.zeros_like(turned), self.alpha_turn * turned)
