"""Kelly's speed, gyro and compass noise (Kelly 2001, Table 1).

=====================  ===============================================================
model                  contribution
=====================  ===============================================================
:class:`SpeedNoise`    var Δd = α_ss·|Δd| (any robot with a distance channel)
:class:`GyroNoise`     var Δθ = σ_gg·Δt (integrated heading)
:class:`CompassNoise`  var θ_k = psd/Δt of each measured heading (direct heading;
                       propagated by its own engine,
                       :func:`odomkit.propagate.transition.propagate_direct_heading`)
=====================  ===============================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import validate
from odomkit.errors import ModelError
from odomkit.kinematics import unicycle_moving
from odomkit.noise.base import NoiseModel, register, require_non_negative, sym2

if TYPE_CHECKING:
    from odomkit.kinematics import BodySteps

__all__ = [
    "SpeedNoise",
    "GyroNoise",
    "CompassNoise",
    "DEFAULT_COMPASS_PERIOD",
    "compass_sample_count",
    "speed_gyro_input_cov",
    "direct_heading_variances",
]

DEFAULT_COMPASS_PERIOD = 0.1
"""Sample period [s] of the compass of a planned path (``odomkit predict`` and
``simulate``, ``--compass-period``) when none is given: a 10 Hz heading output. A log
needs none: its rows are the samples."""


@register
@dataclass(frozen=True)
class SpeedNoise(NoiseModel):
    """Kelly Table 1: speed-encoder noise, σ_vv = α_ss·|V| (a spectral density).

    Over a step of length Δs the travelled distance has variance ``alpha_ss · |Δs|``
    (the white speed noise of any vehicle: a unicycle's, gyro's or compass robot's speed).

    Parameters
    ----------
    alpha_ss : float
        Distance-variance per metre travelled [m²/m = m].
    """

    alpha_ss: float

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """α_ss·|Δd| of each step [m²], (n, 1)."""
        return (self.alpha_ss * np.abs(np.asarray(steps.dd[a:b], dtype=float)))[:, None]

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """The distance error enters Δd alone: [[1], [0]], (n, 2, 1)."""
        return np.broadcast_to(np.array([[1.0], [0.0]]), (b - a, 2, 1))

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`speed_gyro_input_cov` with no gyro."""
        return speed_gyro_input_cov(steps.dd[a:b], steps.dt[a:b], self, None)


@register
@dataclass(frozen=True)
class GyroNoise(NoiseModel):
    """Kelly Table 1, integrated heading: gyro rate noise with constant spectral density
    σ_ωω = σ_gg, so the integrated heading has variance ``psd_gyro · Δt`` over a step
    (the white yaw-rate noise of a gyro robot or a unicycle).

    Parameters
    ----------
    psd_gyro : float
        Power spectral density of the yaw-rate noise [rad²/s].
    """

    psd_gyro: float

    # Any robot that integrates its heading (not a compass robot, which measures it).
    robot_types: ClassVar[tuple[str, ...]] = ("gyro", "diff", "tricycle", "unicycle", "car")
    family: ClassVar[str | None] = "gyro"

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """σ_gg·|Δt| of each step [rad²], (n, 1) (:meth:`noisy_time`)."""
        return (self.psd_gyro * self.noisy_time(steps, a, b))[:, None]

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """The integrated-rate error enters Δθ alone: [[0], [1]], (n, 2, 1)."""
        return np.broadcast_to(np.array([[0.0], [1.0]]), (b - a, 2, 1))

    def input_cov(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """:func:`speed_gyro_input_cov` with no speed noise."""
        return speed_gyro_input_cov(steps.dd[a:b], self.noisy_time(steps, a, b), None, self)

    @staticmethod
    def noisy_time(steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """|Δt| of steps a … b−1 [s] over which the yaw-rate noise acts, (n,).

        A gyro drifts whether or not the vehicle moves, so its noise acts all the time. A
        unicycle's yaw rate is a body velocity, commanded (``cmd_vel``) or reported by the
        base (``odom``): a step with zero speed and zero yaw rate is a vehicle standing
        still, which gathers no heading error (as a tricycle's wheel that reads no travel,
        issue 11), so its Δt does not count.
        """
        dt = np.abs(np.asarray(steps.dt[a:b], dtype=float))
        if steps.robot.type_name == "unicycle":
            dt = np.where(unicycle_moving(steps.dd[a:b], steps.inputs["yaw_rate"][a:b]), dt, 0.0)
        return dt


@register
@dataclass(frozen=True)
class CompassNoise(NoiseModel):
    """Kelly Table 1, direct heading: compass noise σ_θθ = const.

    In Kelly's continuous-time model the heading error is white with spectral density
    ``psd_compass``; the position error it causes grows as ``V²·psd_compass·t``
    (Kelly eq. 13), but the heading itself has no finite variance. A real compass is
    sampled: read every T seconds (averaging the white error over T), each reading has an
    independent error of variance ``psd_compass / T`` (:meth:`sample_variance`). That is
    odomkit's one convention: ``track`` takes T from the log's time stamps
    (:func:`direct_heading_variances`), ``predict`` and ``simulate`` from their compass
    period (:data:`DEFAULT_COMPASS_PERIOD` unless given).

    Parameters
    ----------
    psd_compass : float
        Spectral density of the heading noise [rad²·s].
    """

    psd_compass: float

    robot_types: ClassVar[tuple[str, ...]] = ("compass",)
    family: ClassVar[str | None] = "compass"
    # one error of variance psd/T per reading (a planned path: its compass_period)
    per_sample: ClassVar[bool] = True

    def __post_init__(self) -> None:
        require_non_negative(self)

    def input_variances(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """No white input to (Δd, Δθ): the heading is measured, (n, 0)."""
        return np.zeros((b - a, 0))

    def input_jacobian(self, steps: BodySteps, a: int, b: int) -> NDArray[np.float64]:
        """(n, 2, 0): see :meth:`input_variances`."""
        return np.zeros((b - a, 2, 0))

    def heading_variances(self, steps: BodySteps) -> NDArray[np.float64]:
        """:func:`direct_heading_variances` of the steps' durations."""
        return direct_heading_variances(steps.dt, self)

    def sample_variance(self, period: float) -> float:
        """Variance of one compass reading taken every ``period`` [s]: psd/T [rad²].

        Examples
        --------
        >>> CompassNoise(1e-5).sample_variance(0.1)
        0.0001
        """
        return self.psd_compass / validate.positive(period, "compass_period", unit="s")


def compass_sample_count(duration: float, period: float, segment: int | None = None,
                         *, sensor: str = "compass") -> int:
    """How many compass periods a segment of ``duration`` [s] lasts; a ModelError unless
    it is a whole number (to 1e-9 relative), so that every segment starts and ends on a
    compass sample. ``sensor`` names the period in the messages (``"sample"``: the
    ``sample_period`` of per-sample noise, :func:`odomkit.propagate.paths.path_model`).

    Examples
    --------
    >>> compass_sample_count(2.5, 0.1)
    25
    """
    period = validate.positive(period, f"{sensor}_period", unit="s")
    n = round(duration / period)
    if abs(n * period - duration) > 1e-9 * max(duration, period):
        which = f"segment {segment} " if segment is not None else "a segment "
        raise ModelError(f"{which}lasts {duration:g} s, not a whole number of {sensor} periods "
                         f"({period:g} s); change the duration or the {sensor} period")
    return int(n)


def speed_gyro_input_cov(
    dd: ArrayLike, dt: ArrayLike, speed: SpeedNoise | None = None, gyro: GyroNoise | None = None
) -> NDArray[np.float64]:
    """Integrated-heading odometry (Kelly Table 1): encoder and gyro noise per step.

    ``var Δd = α_ss·|Δd|`` (σ_vv = α_ss|V| integrated over the step) and
    ``var Δθ = σ_gg·Δt`` (white yaw-rate noise of density σ_gg integrated over Δt);
    independent (σ_vω = 0). Either model may be None (zero).

    Parameters
    ----------
    dd : array_like, shape (M,)
        Distance of each step [m].
    dt : array_like, shape (M,)
        Duration of each step [s].

    Returns
    -------
    cov_input : ndarray, shape (M, 2, 2)

    Examples
    --------
    >>> speed_gyro_input_cov([0.5], [0.1], SpeedNoise(0.01), GyroNoise(1e-4))[0].tolist()
    [[0.005, 0.0], [0.0, 1e-05]]
    """
    dd, dt = np.asarray(dd, dtype=float), np.asarray(dt, dtype=float)
    var_dd = (speed.alpha_ss if speed else 0.0) * np.abs(dd)
    var_dtheta = (gyro.psd_gyro if gyro else 0.0) * np.abs(dt)
    return sym2(var_dd, np.zeros_like(var_dd), var_dtheta)


def direct_heading_variances(dt: ArrayLike, noise: CompassNoise) -> NDArray[np.float64]:
    """Variance of each measured heading sample [rad²], shape (M + 1,).

    A compass with white heading noise of density ``psd_compass`` [rad²·s], sampled
    (averaged) over Δt, has ``var = psd_compass / Δt`` (:class:`CompassNoise`). Row k
    uses the spacing around it: the mean of the two adjacent step durations (one at the
    ends). With this, the position variance on a straight line at speed V grows as
    |V|·psd·s, Kelly eq. (13).
    """
    dt = np.asarray(dt, dtype=float)
    if dt.size == 0:
        return np.zeros(1)
    if np.any(dt <= 0):
        raise ModelError("direct-heading noise needs strictly increasing time stamps (dt > 0)")
    spacing = np.empty(dt.size + 1)
    spacing[0], spacing[-1] = dt[0], dt[-1]
    spacing[1:-1] = 0.5 * (dt[:-1] + dt[1:])
    return noise.psd_compass / spacing
