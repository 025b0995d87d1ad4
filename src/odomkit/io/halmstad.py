"""The Halmstad course-exercise logs (Khepera encoder counts, Snowhite tricycle).

Formats from ``data/halmstad-khepera-snowhite/SOURCE.md``: the Khepera files hold two
whitespace-separated columns of *cumulative* pulse counts ``left right``; ``snowhite.txt``
holds ``v [mm/s], alpha [rad], TrueX [mm], TrueY [mm], TrueTheta [rad]`` at T = 50 ms.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from odomkit import validate
from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io.table import counter_increments, read_numeric, read_table
from odomkit.log import OdometryLog

__all__ = ["SNOWHITE_PERIOD", "read_khepera", "read_snowhite"]

#: Sampling period of the Snowhite log (exercise handout) [s].
SNOWHITE_PERIOD = 0.05


def read_khepera(path: str | Path, period: float = 1.0, wrap_bits: int | None = None) -> OdometryLog:
    """Read a Khepera log of cumulative ``left right`` encoder counts.

    Parameters
    ----------
    path : the text file (plain or gzip)
    period : sampling period [s]; the handout does not state it, so time is in samples
        by default.
    wrap_bits : undo wrap-around of a counter of this width (None: the counts never wrap).
    """
    period = validate.positive(period, "period", unit="s", error=InputError)
    table = read_table(path, 2, integer_columns=(0, 1))
    # Integer counts are differenced (and unwrapped) exactly, in int64 arithmetic.
    left, right = table.counter(0, wrap_bits), table.counter(1, wrap_bits)
    t = _sample_times(table.values.shape[0], period, path)
    channels = {"ticks_left": counter_increments(left, wrap_bits),
                "ticks_right": counter_increments(right, wrap_bits)}
    return OdometryLog(t, channels, None, str(path), {"format": "khepera"})


def _sample_times(rows: int, period: float, path: str | Path) -> np.ndarray:
    """``0, T, 2T, ...`` for a log without a time column; refused when the last time is not
    a finite number (``--period 1e308``), before numpy would warn about the overflow."""
    if rows > 1 and not np.isfinite(period * float(rows - 1)):
        raise InputError(f"--period {period:g} s times {rows - 1} steps overflows the time column; "
                         "give the sample period in seconds", source=str(path))
    return np.arange(rows, dtype=float) * period


def read_snowhite(path: str | Path, period: float = SNOWHITE_PERIOD) -> OdometryLog:
    """Read ``snowhite.txt``: front-wheel speed and steering angle with ground truth.

    Millimetres are converted to metres here; the ground-truth heading (given in
    [0, 2π)) is unwrapped so that it is continuous like odomkit's θ.
    """
    period = validate.positive(period, "period", unit="s", error=InputError)
    data = read_numeric(path, 5)
    t = _sample_times(data.shape[0], period, path)
    channels = {"speed": data[:, 0] / 1000.0, "steer": data[:, 1].copy()}
    truth = np.column_stack((data[:, 2] / 1000.0, data[:, 3] / 1000.0, unwrap_angle(data[:, 4])))
    return OdometryLog(t, channels, truth, str(path), {"format": "snowhite"})
