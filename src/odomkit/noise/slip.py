"""Lateral slip: white position noise across the track, for every vehicle.

Per-wheel, speed and heading noise move the position only along the track or through the
heading. Real logs (the OptiOdom runs) also show a sideways error that grows as
√distance with no heading error behind it: the contact points slide sideways (tyre
scrub, a skidding castor). :class:`LateralSlipNoise` models it as an independent
sideways displacement ε_k ~ N(0, α_lat·|Δd_k|) at every step k, along the unit normal of
the step's displacement, u_k = (−sin θ̄_k, cos θ̄_k) (θ̄_k: the chord direction of the
step map, :func:`odomkit.propagate.lateral.lateral_headings`). It is the sideways twin of
Kelly's speed noise, var Δd = α_ss·|Δd| (:class:`odomkit.noise.kelly.SpeedNoise`).

It enters no body input (Δd, Δθ) and no heading: the engines add its contribution to the
position block apart from the recursion (:mod:`odomkit.propagate.lateral` says why that
is exact), and the Monte Carlo draws a third normal per step for it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray

from odomkit.noise.base import NoiseModel, register, require_non_negative

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps

__all__ = ["LateralSlipNoise"]


@register
@dataclass(frozen=True)
class LateralSlipNoise(NoiseModel):
    """White sideways slip: each step's position moves across the track by
    ε ~ N(0, alpha_lateral·|Δd|) (any robot; integrated or measured heading alike).

    Parameters
    ----------
    alpha_lateral : float
        Variance of the sideways displacement per metre travelled [m²/m = m].

    Examples
    --------
    >>> from odomkit.kinematics import BodySteps
    >>> from odomkit.robot import DiffDrive
    >>> steps = BodySteps(np.array([0.5, -0.2]), np.zeros(2), np.full(2, 0.1),
    ...                   {"d_left": np.zeros(2), "d_right": np.zeros(2)}, DiffDrive(0.4))
    >>> LateralSlipNoise(1e-4).lateral_variances(steps, 0, 2).tolist()
    [5e-05, 2e-05]
    """

    alpha_lateral: float

    position_only: ClassVar[bool] = True

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """No raw input to (Δd, Δθ): the slip moves the position only, (n, 0)."""
        return np.zeros((b - a, 0))

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(n, 2, 0): see :meth:`input_variances`."""
        return np.zeros((b - a, 2, 0))

    def lateral_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """α_lat·|Δd| of steps a … b−1 [m²], (b − a,)."""
        return self.alpha_lateral * np.abs(np.asarray(steps.dd[a:b], dtype=float))
