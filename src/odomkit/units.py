"""Unit factors: odomkit's one home for the non-SI units logs come in.

odomkit computes in SI (metres, seconds, radians; docs/reference/commands/index.md). Logs
arrive in other units: a CAN bus gives a car's speed in km/h or mph and its steering angle
in degrees, a gyro logs °/s. The readers (:mod:`odomkit.io.csvlog`) convert named columns
with these factors, and the data check (:mod:`odomkit.calibrate.check_ratios`) recognises a
track that is off by one of them. Each constant is the SI value of one unit, exactly (the
international mile and foot are defined in metres: 1609.344 m and 0.3048 m).
"""
from __future__ import annotations

import math

__all__ = ["DEGREE", "FOOT", "KMH", "MILLIMETRE", "MPH"]

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
