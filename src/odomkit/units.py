"""Unit factors: odomkit's one home for the non-SI units logs come in.

odomkit computes in SI (metres, seconds, radians; docs/reference/commands/index.md). Logs
arrive in other units: a CAN bus gives a car's speed in km/h or mph and its steering angle
in degrees, a gyro logs °/s. The readers (:mod:`odomkit.io.csvlog`) convert named columns
with these factors, and the data check (:mod:`odomkit.calibrate.check_ratios`) recognises a
track that is off by one of them. A time column may come in ms, µs or ns
(``--time-unit``, ``--truth-time-unit``: :data:`TIME_UNITS`); read as seconds, it drives and
turns a log of rates that factor too far, and spans that factor too long. Each constant is
the SI value of one unit, exactly (the international mile and foot are defined in metres:
1609.344 m and 0.3048 m).
"""
from __future__ import annotations

import math

__all__ = ["DEGREE", "FAST_TRAVEL", "FASTEST_SPEED", "FOOT", "KMH", "MILLIMETRE", "MPH", "period_unit",
           "SLOW_ROWS", "SLOWEST_PERIOD", "TIME_UNITS", "time_unit_factor"]

DEGREE = math.pi / 180
"""Radians per degree."""
KMH = 1 / 3.6
"""Metres per second per km/h (1000 m / 3600 s)."""
MPH = 0.44704
"""Metres per second per mph (1609.344 m / 3600 s, exactly)."""
FOOT = 0.3048
"""Metres per international foot."""
MILLIMETRE = 1e-3
"""Metres per millimetre (a motion capture's export: Vicon's x_mm, y_mm)."""

TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
"""Seconds per unit of a time column (``--time-unit``, ``--truth-time-unit``)."""


def time_unit_factor(ratio: float) -> str | None:
    """The time unit (``"ms"``, ``"us"``, ``"ns"``) whose factor ``ratio`` is, within 2x either
    way (1000, 1e6, 1e9: a time in that unit read as seconds makes a span, or a travel or turn
    integrated from rates, that many times too large), or None.

    Examples
    --------
    >>> time_unit_factor(1440.0), time_unit_factor(0.9e6), time_unit_factor(57.3)
    ('ms', 'us', None)
    """
    if not (math.isfinite(ratio) and ratio > 0):
        return None
    for unit in ("ms", "us", "ns"):
        if 0.5 <= ratio * TIME_UNITS[unit] <= 2.0:
            return unit
    return None


SLOWEST_PERIOD = 1.0
"""No odometry logger samples slower than this [s]: a median period above it is a time
column in another unit read as seconds (a 20 Hz log in ms reads 50 s)."""

FASTEST_SPEED = 100.0
"""No wheeled vehicle's odometry moves faster than this [m/s] (360 km/h, a race car's top
speed): a log whose moving steps go faster, at the median, reads its travel wrong (a raw
counter read as increments drove a tricycle 561 km in 113 s)."""

FAST_TRAVEL = "faster than any wheeled vehicle"
"""The words every message about :data:`FASTEST_SPEED` holds (``odomkit check`` says it once,
as its ``speed`` finding, not again as a reading warning)."""

SLOW_ROWS = "slower than any odometry logger"
"""The words every message about :data:`SLOWEST_PERIOD` holds (``odomkit check`` says it once,
as its ``time`` finding, not again as a reading warning)."""


def period_unit(median_period: float) -> str | None:
    """The time unit a log's time column is likely in where its median period [s], read as
    seconds, is slower than any odometry logger (:data:`SLOWEST_PERIOD`): the first of
    ``"ms"``, ``"us"``, ``"ns"`` that makes it 0.1 ms to 1 s (``"ms"`` where none does);
    None where the period is a logger's.

    Examples
    --------
    >>> period_unit(0.05), period_unit(50.0), period_unit(5e4)
    (None, 'ms', 'us')
    """
    if not median_period > SLOWEST_PERIOD:
        return None
    return next((u for u in ("ms", "us", "ns") if 1e-4 <= median_period * TIME_UNITS[u] <= SLOWEST_PERIOD),
                "ms")
