"""One result of the data checks before calibrating: :class:`Finding` and its :data:`Status`.

Every check module makes findings (:mod:`odomkit.calibrate.check` the checks of the log
itself, :mod:`odomkit.calibrate.check_channels` the channel mapping,
:mod:`odomkit.calibrate.check_identifiable` what the motion pins), and
:func:`odomkit.calibrate.check.check_log` imports the other two to run them all: kept in
``check.py``, :class:`Finding` would make an import cycle (which the architecture rules
refuse even through a lazy import), so it lives here, below all three.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

__all__ = ["Finding", "Status"]

Status = Literal["ok", "warn", "fail"]


@dataclass(frozen=True)
class Finding:
    """One result of a check.

    Parameters
    ----------
    check : str
        Which check (``time``, ``values``, ``counters``, ``stuck``, ``channels``,
        ``truth_heading``, ``truth_interpolated``, ``travel_ratio``, ``turn_ratio``, ``distance``,
        ``turning``, ``identifiable``, ``reading``).
    status : {"ok", "warn", "fail"}
    message : str
        What was found, in the log's numbers.
    advice : str, optional
        What to do or record next.
    value : float, optional
        The figure the status was judged on, where there is one (``identifiable``: the
        standard error, relative for a scale or length, rad for a steering offset, rad/s
        for a yaw-rate bias; ``channels``: the misfit of the mapping as given;
        ``truth_heading``: the truth's heading minus its direction of motion, rad;
        ``truth_interpolated``: the share of its moving fixes on straight lines;
        ``travel_ratio``: the odometry's distance over the truth's; ``turn_ratio``: its
        turning over the truth's, per metre driven for a wheeled base).
    """

    check: str
    status: Status
    message: str
    advice: str | None = None
    value: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (an unbounded ``value`` is None)."""
        value = None if self.value is None or not math.isfinite(self.value) else float(self.value)
        return {"check": self.check, "status": self.status, "message": self.message, "advice": self.advice,
                "value": value}
