"""Noise models, each with its units and its source.

Every field name says whether it is a standard deviation (``sigma_*``), a variance
(``var_*``) or a variance density (``k_*``, ``alpha_*``, ``psd_*``), as GTSAM does at
construction: nothing here is ambiguous between σ and σ².
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

from odomkit.errors import ModelError


def _require_non_negative(owner: str, obj: object) -> None:
    for f in fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        if isinstance(value, str):
            continue
        if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
            raise ModelError(f"{owner}.{f.name} must be a non-negative finite number, got {value!r}")


@dataclass(frozen=True)
class WheelNoise:
    """Per-wheel white noise, Chong–Kleeman eq. (4), (18).

    The distance a wheel travels over a step has variance ``k² · |d|``.

    Parameters
    ----------
    k_left, k_right : float
        Noise coefficients [m^½]; e.g. 0.001 m^½ gives σ = 1 mm after 1 m of wheel travel.
    """

    k_left: float
    k_right: float

    def __post_init__(self) -> None:
        _require_non_negative("WheelNoise", self)


@dataclass(frozen=True)
class ClassicalNoise:
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

    def __post_init__(self) -> None:
        _require_non_negative("ClassicalNoise", self)


@dataclass(frozen=True)
class SpeedNoise:
    """Kelly Table 1: speed-encoder noise, σ_vv = α_ss·|V| (a spectral density).

    Over a step of length Δs the travelled distance has variance ``alpha_ss · |Δs|``.

    Parameters
    ----------
    alpha_ss : float
        Distance-variance per metre travelled [m²/m = m].
    """

    alpha_ss: float

    def __post_init__(self) -> None:
        _require_non_negative("SpeedNoise", self)


@dataclass(frozen=True)
class GyroNoise:
    """Kelly Table 1, integrated heading: gyro rate noise with constant spectral density
    σ_ωω = σ_gg, so the integrated heading has variance ``psd_gyro · Δt`` over a step.

    Parameters
    ----------
    psd_gyro : float
        Power spectral density of the yaw-rate noise [rad²/s].
    """

    psd_gyro: float

    def __post_init__(self) -> None:
        _require_non_negative("GyroNoise", self)


@dataclass(frozen=True)
class CompassNoise:
    """Kelly Table 1, direct heading: compass noise σ_θθ = const.

    In Kelly's continuous-time model the heading error is white with spectral density
    ``psd_compass``; the position error it causes grows as ``V²·psd_compass·t``
    (Kelly eq. 13). For a sampled compass, ``var_heading = psd_compass / Δt`` per sample.

    Parameters
    ----------
    psd_compass : float
        Spectral density of the heading noise [rad²·s].
    """

    psd_compass: float

    def __post_init__(self) -> None:
        _require_non_negative("CompassNoise", self)


@dataclass(frozen=True)
class TricycleNoise:
    """The exercise's tricycle noise: independent white noise on each sample's speed,
    steering angle and sample period (Sun–Gao, Snowhite part).

    Parameters
    ----------
    sigma_speed : float
        Standard deviation of the measured front-wheel speed [m/s] (or, for a ticks
        channel, of the per-step travelled distance divided by the step duration).
    sigma_steer : float
        Standard deviation of the steering angle [rad].
    sigma_dt : float
        Standard deviation of the sample period [s].
    """

    sigma_speed: float
    sigma_steer: float
    sigma_dt: float = 0.0

    def __post_init__(self) -> None:
        _require_non_negative("TricycleNoise", self)


@dataclass(frozen=True)
class ParameterUncertainty:
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

    def __post_init__(self) -> None:
        _require_non_negative("ParameterUncertainty", self)
        if self.mode not in ("bias", "white"):
            raise ModelError(f"ParameterUncertainty.mode must be 'bias' or 'white', got {self.mode!r}")


NoiseModel = (
    WheelNoise | ClassicalNoise | SpeedNoise | GyroNoise | CompassNoise | TricycleNoise
    | ParameterUncertainty
)
