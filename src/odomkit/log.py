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

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

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
        n = self.t.shape[0]
        if self.t.ndim != 1:
            raise InputError(f"time must be 1-D, got shape {self.t.shape}", source=self.source)
        for name, values in self.channels.items():
            if name not in KNOWN_CHANNELS:
                raise InputError(
                    f"unknown channel {name!r}; expected one of {sorted(KNOWN_CHANNELS)}",
                    source=self.source,
                )
            if values.shape != (n,):
                raise InputError(f"channel {name!r} has shape {values.shape}, expected ({n},)",
                                 source=self.source)
        if self.ground_truth is not None and self.ground_truth.shape != (n, 3):
            raise InputError(f"ground truth has shape {self.ground_truth.shape}, expected ({n}, 3)",
                             source=self.source)

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

    def decimate(self, every: int) -> OdometryLog:
        """Keep every ``every``-th row, as if the sensors had been read less often.

        Increments are summed over the dropped rows (a counter read less often sees the
        same total), rate and absolute channels are sampled.
        """
        if every < 1:
            raise InputError(f"decimation must be a positive integer, got {every}", source=self.source)
        if every == 1:
            return self
        keep = np.arange(0, len(self), every)
        channels = {}
        for name, values in self.channels.items():
            if name in INCREMENT_CHANNELS:
                cumulative = np.concatenate(([0.0], np.cumsum(values[1:])))
                channels[name] = np.concatenate(([values[0]], np.diff(cumulative[keep])))
            else:
                channels[name] = values[keep]
        gt = None if self.ground_truth is None else self.ground_truth[keep]
        return OdometryLog(self.t[keep], channels, gt, self.source, dict(self.meta, decimation=every))
