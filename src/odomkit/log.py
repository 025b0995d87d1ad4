"""An odometry log in memory: timestamps, named sensor channels, optional ground truth.

Channel conventions (SI units; readers convert at the edge):

* increment channels ``ticks_left``, ``ticks_right``, ``ticks`` [ticks] and ``dist_left``,
  ``dist_right``, ``dist`` [m]: what was counted *since the previous row*. Row 0's value is
  motion before the log starts and is ignored. Cumulative counters are differenced by the
  readers (after unwrapping, if asked), so inside odomkit increments are the only form.
* rate channels ``speed``, ``speed_left``, ``speed_right`` [m/s], ``yaw_rate`` [rad/s]: the
  value at a row holds until the next row (zero-order hold), so step k (row k -> k+1) uses
  the rate of row k: a rate sampled at row k is the best knowledge of the step after it
  (the step before it is past when it is logged), and a command logged when it changes
  holds exactly so. ``speed_left``/``speed_right`` are a differential drive's wheel speeds
  (a ``JointState`` velocity times the wheel radius, or a dataset's wheel speeds).
* absolute channels ``steer`` [rad], ``heading`` [rad]: the value at a row.

A differential drive's wheels are read in one form, both sides alike (:data:`WHEEL_PAIRS`,
:func:`wheel_channels`): ``ticks_*``, ``dist_*`` or ``speed_*``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.errors import InputError

__all__ = ["ABSOLUTE_CHANNELS", "clock_text", "INCREMENT_CHANNELS", "KNOWN_CHANNELS", "OdometryLog",
           "RATE_CHANNELS", "SPEED_CHANNELS", "WHEEL_PAIRS", "wheel_channels"]

INCREMENT_CHANNELS = frozenset({"ticks_left", "ticks_right", "ticks", "dist_left", "dist_right", "dist"})
RATE_CHANNELS = frozenset({"speed", "speed_left", "speed_right", "yaw_rate"})
ABSOLUTE_CHANNELS = frozenset({"steer", "heading"})
KNOWN_CHANNELS = INCREMENT_CHANNELS | RATE_CHANNELS | ABSOLUTE_CHANNELS
#: The rate channels that measure travel [m/s] (held from each row over the step after it).
SPEED_CHANNELS = frozenset({"speed", "speed_left", "speed_right"})
#: The forms a differential drive's wheels are logged in, each a (left, right) pair: tick
#: increments, metre increments, wheel speeds [m/s].
WHEEL_PAIRS = (("ticks_left", "ticks_right"), ("dist_left", "dist_right"), ("speed_left", "speed_right"))


def clock_text(t: float) -> str:
    """A log or truth time [s] for a message: six significant digits for a clock that starts
    near zero (``12.3457``), milliseconds for an epoch clock (``1432235497.989``; ``.6g``
    would print ``1.43224e+09`` for every time of a ROS bag's day).

    Examples
    --------
    >>> clock_text(12.345678), clock_text(1432235497.98895)
    ('12.3457', '1432235497.989')
    """
    return f"{t:.3f}" if abs(t) >= 1e6 else f"{t:.6g}"


def wheel_channels(names: Iterable[str], source: str | None = None) -> tuple[str, str] | None:
    """The (left, right) wheel channels among ``names``, one pair of :data:`WHEEL_PAIRS`;
    None where there is none.

    A wheel read in one form and the other wheel in another (``ticks_left`` with
    ``speed_right``), two forms at once, or one wheel alone is an :class:`InputError`
    naming the channels: read so, one wheel would be off by a unit (or a row's timing)
    from the other, and the track would turn wrongly without a word.

    Examples
    --------
    >>> wheel_channels(["speed_right", "speed_left", "t"])
    ('speed_left', 'speed_right')
    >>> wheel_channels(["speed", "yaw_rate"]) is None
    True
    """
    given = set(names)
    found = [(pair, [c for c in pair if c in given]) for pair in WHEEL_PAIRS]
    present = [(pair, have) for pair, have in found if have]
    if not present:
        return None
    names_given = ", ".join(c for _, have in present for c in have)
    *first, last = (f"{left}/{right}" for left, right in WHEEL_PAIRS)
    forms = f"{', '.join(first)} or {last}"
    if len(present) > 1:
        raise InputError(f"the wheels are given in two forms ({names_given}): a differential drive "
                         f"reads both wheels in one: {forms}", source=source)
    pair, have = present[0]
    if len(have) == 1:
        missing = pair[1 - pair.index(have[0])]
        raise InputError(f"{have[0]} is given without {missing}: a differential drive reads both "
                         f"wheels in one form: {forms}", source=source)
    return pair


def _rows_from_zero(rows: NDArray[np.intp]) -> str:
    """What a message naming ``rows[0]`` adds: rows count from 0, and how many more there are."""
    more = rows.size - 1
    return "rows count from 0" + (f"; {more} more row{'s' if more > 1 else ''}" if more else "")


@dataclass(frozen=True)
class OdometryLog:
    """A log of N rows.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time of each row [s], finite. Repeated timestamps are allowed (zero-length steps);
        decreasing ones are an :class:`~odomkit.errors.InputError` naming the row (counted
        from 0), here as in the readers.
    channels : mapping of str to ndarray, shape (N,)
        Sensor channels named as in the module docstring; a value that is NaN or infinite
        is an :class:`~odomkit.errors.InputError` naming the channel and row (from 0).
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
        t = validate.shape(self.t, "time", ("N",), error=error)
        n = t.shape[0]
        # The readers refuse these at their file's line; a log built in Python is checked
        # here, or time going back is dead-reckoned silently and a NaN fails deep inside.
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise error(f"time is {t[bad[0]]} at row {bad[0]} ({_rows_from_zero(bad)}); expected finite "
                        "times [s]")
        back = np.flatnonzero(np.diff(t) < 0) + 1
        if back.size:
            i = int(back[0])
            raise error(f"time goes backwards at row {i} ({_rows_from_zero(back)}): {clock_text(t[i])} s "
                        f"after {clock_text(t[i - 1])} s; expected times that never decrease (repeated "
                        "times are zero-length steps)")
        for name, values in self.channels.items():
            if name not in KNOWN_CHANNELS:
                raise error(f"unknown channel {name!r}; expected one of {sorted(KNOWN_CHANNELS)}")
            checked = validate.shape(values, f"channel {name!r}", (n,), error=error)
            bad = np.flatnonzero(~np.isfinite(checked))
            if bad.size:
                raise error(f"channel {name!r} is {checked[bad[0]]} at row {bad[0]} "
                            f"({_rows_from_zero(bad)}); expected finite numbers (drop or interpolate "
                            "the row first)")
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
