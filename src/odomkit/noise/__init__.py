"""Noise models: one protocol (:class:`NoiseModel`), one class per source of noise.

==========================  ======  ======================================================
model                       kind    applies to
==========================  ======  ======================================================
:class:`WheelNoise`         white   diff: per-wheel travel error, variance k²·|d|
:class:`ClassicalNoise`     white   any: fixed σ per step (Chong–Kleeman eq. 1–3)
:class:`SpeedNoise`         white   any: distance error, variance α_ss·|Δd|
:class:`GyroNoise`          white   integrated heading (gyro, unicycle, ...): variance
                                    psd_gyro·Δt
:class:`CompassNoise`       white   compass: measured heading, variance psd_compass/Δt
:class:`TricycleNoise`      white   tricycle and car: speed, steering and period errors
:class:`LateralSlipNoise`   white   any: sideways slip across the track, variance
                                    α_lat·|Δd| (position only)
:class:`TurnNoise`          white   unicycle, gyro: heading and travel errors that grow
                                    with turning, variances α_turn·|Δθ| and
                                    α_turn_travel·|Δθ|
:class:`ParameterUncertainty`  bias  every vehicle's parameters, constant over a run
                            (wheel base, wheel or speed scales, steering offset,
                            yaw-rate offset and scale, heading offset; or white)
==========================  ======  ======================================================

Several independent models combine in a :class:`NoiseSet` (a tuple of models is accepted
wherever a noise argument is).
"""

from odomkit.noise.base import NOISE_MODELS, NoiseKind, NoiseModel, NoiseSet, noise_fields, register
from odomkit.noise.kelly import CompassNoise, GyroNoise, SpeedNoise
from odomkit.noise.parameters import ParameterUncertainty
from odomkit.noise.slip import LateralSlipNoise
from odomkit.noise.tricycle import TricycleNoise
from odomkit.noise.turn import TurnNoise
from odomkit.noise.wheel import ClassicalNoise, WheelNoise

__all__ = [
    "NoiseModel",
    "NoiseSet",
    "NoiseKind",
    "NOISE_MODELS",
    "register",
    "noise_fields",
    "WheelNoise",
    "ClassicalNoise",
    "SpeedNoise",
    "GyroNoise",
    "CompassNoise",
    "TricycleNoise",
    "LateralSlipNoise",
    "TurnNoise",
    "ParameterUncertainty",
]
