"""A log's noise models -> what the propagation engines need (:func:`plan_noise`).

Everything a noise model means is answered by the model itself
(:class:`odomkit.noise.NoiseModel`); this module only asks, once per log, and hands the
engines a :class:`NoisePlan` whose functions take a step range [a, b), so nothing of size
M×2×2 is ever built for the whole log.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps
from odomkit.noise import NoiseModel, NoiseSet
from odomkit.noise.wheel import WheelInputs
from odomkit.propagate.inputs import ENGINE_METHODS

__all__ = ["NoisePlan", "NoiseArg", "plan_noise"]

NoiseArg = NoiseModel | NoiseSet | Sequence[NoiseModel]
"""What a ``noise`` argument may be: one model, a sequence of them, or a NoiseSet."""


@dataclass(frozen=True)
class NoisePlan:
    """What the engines need from a set of noise models for one log (built by
    :func:`plan_noise`).

    Attributes
    ----------
    method : str
        Step map of the engines (``"classical"`` for ClassicalNoise).
    direct : bool
        Direct-heading (compass) odometry: heading measured, not integrated.
    noise : NoiseSet
        The validated models.
    steps : BodySteps
        The log's steps the models are asked about.
    var_heading : ndarray, shape (M + 1,), or None
        Direct heading: variance of each heading sample [rad²].
    var_params : ndarray, shape (p,), or None
        Bias parameter variances; None when there is no bias term.
    bias_heading : ndarray, shape (p,), or None
        Direct heading with a bias term: ∂θ_k/∂β of every measured heading (a heading
        offset: 1); None otherwise.
    wheel : WheelInputs or None
        Set when a model can have its Q_k formed inside the compiled recursion and is the
        only white source of (Δd, Δθ) (a lateral slip beside it is added apart).
    """

    method: str
    direct: bool
    noise: NoiseSet
    steps: BodySteps
    var_heading: NDArray[np.float64] | None = None
    var_params: NDArray[np.float64] | None = None
    wheel: WheelInputs | None = None
    bias_heading: NDArray[np.float64] | None = None

    def cov_input(self, a: int, b: int) -> NDArray[np.float64]:
        """Summed white input covariance of steps a … b−1, (b − a, 2, 2)."""
        return self.noise.input_cov(self.steps, a, b)

    def var_dd(self, a: int, b: int) -> NDArray[np.float64]:
        """Variance of Δd of steps a … b−1 [m²] (direct heading)."""
        return self.cov_input(a, b)[:, 0, 0]

    def var_lateral(self, a: int, b: int) -> NDArray[np.float64] | None:
        """Variance of the sideways slip of steps a … b−1 [m²], (b − a,), or None
        without a position-only model (:mod:`odomkit.propagate.lateral`)."""
        return self.noise.lateral_variances(self.steps, a, b)

    def param_jacobian(self, a: int, b: int) -> NDArray[np.float64]:
        """K = ∂(Δd, Δθ)/∂β of steps a … b−1, (b − a, 2, p)."""
        return self.noise.bias_jacobian(self.steps, a, b)


def plan_noise(steps: BodySteps, noise: NoiseArg, method: str = "exact") -> NoisePlan:
    """Check noise models against a log's robot and plan the engines.

    Parameters
    ----------
    steps : BodySteps
        M steps of a log (or of a discretised path).
    noise : NoiseModel, sequence of NoiseModel, or NoiseSet
        Independent sources; each class at most once. Which apply to which robot is each
        model's own ``check_robot`` (see :mod:`odomkit.noise`).
    method : {"exact", "midpoint", "euler"}
        The track's step map; a model with a map of its own (classical) overrides it.

    Returns
    -------
    NoisePlan
    """
    if method not in ENGINE_METHODS[:3]:
        raise ModelError(f"unknown method {method!r}; expected exact, midpoint or euler")
    models = NoiseSet.of(noise)
    robot = steps.robot
    models.check_robot(robot)
    direct = robot.measures_heading
    var_heading = None
    if direct:
        var_heading = models.heading_variances(steps)
        if var_heading is None:
            var_heading = np.zeros(np.asarray(steps.dd).size + 1)
    var_params = models.bias_variances(robot) if models.bias else None
    bias_heading = models.bias_heading(robot) if direct and models.bias else None
    # A position-only model (lateral slip) is added apart from the recursion, so it
    # keeps the compiled per-wheel fast path.
    white = models.body_white
    wheel = white[0].compiled_inputs(steps) if len(white) == 1 and not direct else None
    return NoisePlan(models.step_map(method), direct, models, steps, var_heading, var_params,
                     wheel, bias_heading)
