"""An odometry log in memory: timestamps, named sensor channels, optional ground truth.

Channel conventions (SI units; readers convert at the edge):

* increment channels ``ticks_left``, ``ticks_right``, ``ticks`` [ticks] and ``dist_left``,
  ``dist_right``, ``dist`` [m]: what was counted *since the previous row*. Row 0's value is
  motion before the log starts and is ignored. Cumulative counters are differenced by the
  readers (after unwrapping, if asked), so inside odomkit increments are the only form.
* rate channels ``speed`` [m/s], ``yaw_rate`` [rad/s]: the value at a row holds until the
  next row (zero-order hold), so step k (row k -> k+1) uses the rate of row k.
* absolute channels ``steer`` [rad], ``heading`` [rad]: the value at a row.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.errors import InputError

__all__ = ["ABSOLUTE_CHANNELS", "INCREMENT_CHANNELS", "KNOWN_CHANNELS", "RATE_CHANNELS", "OdometryLog"]

INCREMENT_CHANNELS = frozenset({"ticks_left", "ticks_right", "ticks", "dist_left", "dist_right", "dist"})
RATE_CHANNELS = frozenset({"speed", "yaw_rate"})
ABSOLUTE_CHANNELS = frozenset({"steer", "heading"})
KNOWN_CHANNELS = INCREMENT_CHANNELS | RATE_CHANNELS | ABSOLUTE_CHANNELS


@dataclass(frozen=True)
class OdometryLog:
    """A log of N rows.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time of each row [s]. Repeated timestamps are allowed (zero-length steps);
        decreasing ones are rejected by the readers.
    channels : mapping of str to ndarray, shape (N,)
        Sensor channels named as in the module docstring.
    ground_truth : ndarray, shape (N, 3), optional
        True pose ``[x, y, θ]`` at each row [m, m, rad], θ continuous.
    source : str
        Where the log came from (used in error messages).
    """

    t: NDArray[np.float64]
    channels: Mapping[str, NDArray[np.float64]]
    ground_truth: NDArray[np.float64] | None = None
    source: str = "<memory>"
    meta: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        error = partial(InputError, source=self.source)
        n = validate.shape(self.t, "time", ("N",), error=error).shape[0]
        for name, values in self.channels.items():
            if name not in KNOWN_CHANNELS:
                raise error(f"unknown channel {name!r}; expected one of {sorted(KNOWN_CHANNELS)}")
            validate.shape(values, f"channel {name!r}", (n,), error=error)
        if self.ground_truth is not None:
            validate.shape(self.ground_truth, "ground truth", (n, 3), error=error)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def channel(self, name: str) -> NDArray[np.float64]:
        """The channel ``name``; a clear error naming the missing channel otherwise."""
        try:
            return self.channels[name]
        except KeyError:
            raise InputError(
                f"log has no channel {name!r} (it has {sorted(self.channels)})", source=self.source
            ) from None

    def from_row(self, row: int) -> OdometryLog:
        """The log from row ``row`` on, its ground truth too (a run that starts late: the
        first row's increments led up to it and are no step of the slice)."""
        return self.rows(row, len(self))

    def rows(self, start: int, stop: int) -> OdometryLog:
        """Rows ``start`` … ``stop − 1`` of the log, its ground truth too; the first row's
        increments led up to it and are no step of the slice (as :meth:`from_row`)."""
        part = slice(start, stop)
        gt = None if self.ground_truth is None else self.ground_truth[part]
        return OdometryLog(self.t[part], {k: v[part] for k, v in self.channels.items()}, gt, self.source,
                           self.meta)

    def decimate(self, every: int) -> OdometryLog:
        """Keep every ``every``-th row, as if the sensors had been read less often.

        Increments are summed over the dropped rows (a counter read less often sees the
        same total), rate and absolute channels are sampled.
        """
        every = validate.positive_int(every, "decimation", error=partial(InputError, source=self.source))
        if every == 1:
            return self
        # Beyond the log's length every step keeps row 0 alone; capping keeps the index an
        # int64 (np.arange with a Python int above 2**63 makes an object array).
        keep = np.arange(0, len(self), min(every, max(len(self), 1)))
        channels = {}
        for name, values in self.channels.items():
            if name in INCREMENT_CHANNELS:
                cumulative = np.concatenate(([0.0], np.cumsum(values[1:])))
                channels[name] = np.concatenate(([values[0]], np.diff(cumulative[keep])))
            else:
                channels[name] = values[keep]
        gt = None if self.ground_truth is None else self.ground_truth[keep]
        return OdometryLog(self.t[keep], channels, gt, self.source, dict(self.meta, decimation=every))
