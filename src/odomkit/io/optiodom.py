"""The OptiOdom dataset (MIT licence, Sousa et al. 2022): run files and metadata.

Run files have six comma-separated columns and no header. Differential drive:
``time, x_gt, y_gt, theta_gt, odoR, odoL`` (column 5 is the RIGHT wheel; ticks per
50 ms cycle). Tricycle: ``time, x_gt, y_gt, theta_gt, odoWh, steer`` (traction ticks per
cycle; steering angle in rad, positive to the left). See ``data/optiodom/SOURCE.md``.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.io.csvlog import STEER_LIMIT
from odomkit.io.table import read_numeric, warn_if_cumulative
from odomkit.io.text import read_text
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive, Tricycle, metres_per_tick

__all__ = ["OptiOdomExperiment", "OptiOdomMetadata", "read_experiment", "read_metadata", "read_run"]


@dataclass(frozen=True)
class OptiOdomMetadata:
    """One experiment's nominal parameters (``<id>_metadata.csv``).

    ``wheel_base`` is Li: the wheel base b (diff) or the steering-wheel-to-rear-axle
    distance L (tricycle) [m]. ``wheel_diameters`` holds Di [m] (one or two values).
    ``side`` is the UMBmark square side [m] (None for other experiments).
    """

    experiment: str
    platform: str
    gear_ratio: float
    encoder_resolution: float
    wheel_base: float
    wheel_diameters: tuple[float, ...]
    steering_offset: float
    runs: int
    side: float | None
    source: str

    def robot(self) -> DiffDrive | Tricycle:
        """The experiment's nominal robot."""
        if self.platform == "diff":
            d = self.wheel_diameters
            return DiffDrive.from_wheels(self.wheel_base, d[0], d[-1], self.encoder_resolution,
                                         self.gear_ratio)
        return Tricycle(
            wheel_to_axle=self.wheel_base,
            m_per_tick=metres_per_tick(self.wheel_diameters[0], self.encoder_resolution,
                                       self.gear_ratio),
            steering_offset=self.steering_offset,
        )


def read_metadata(path: str | Path) -> OptiOdomMetadata:
    """Parse an OptiOdom ``*_metadata.csv`` (key in column 1, values after it)."""
    path = Path(path)
    rows: dict[str, list[str]] = {}
    for row in csv.reader(read_text(path).splitlines()):
        if row and row[0].strip():
            rows[row[0].strip()] = [v.strip() for v in row[1:] if v.strip()]

    def number(key: str, default: float | None = None) -> float:
        values = rows.get(key)
        if not values:
            if default is not None:
                return default
            raise InputError(f"metadata field {key!r} is missing", source=str(path))
        try:
            return float(values[0])
        except ValueError:
            raise InputError(f"metadata field {key!r}: {values[0]!r} is not a number",
                             source=str(path)) from None

    platform = (rows.get("type") or ["diff"])[0]
    if platform not in ("diff", "tricyc"):
        raise InputError(f"metadata field 'type' must be diff or tricyc, got {platform!r}",
                         source=str(path))
    try:
        diameters = tuple(float(v) for v in rows.get("Di", []))
    except ValueError:
        raise InputError("metadata field 'Di' must hold numbers", source=str(path)) from None
    if not diameters:
        raise InputError("metadata field 'Di' is missing", source=str(path))
    side = number("L", 0.0) if "L" in rows else None
    return OptiOdomMetadata(
        experiment=path.name.split("_")[0],
        platform=platform,
        gear_ratio=number("ngear"),
        encoder_resolution=number("encRes"),
        wheel_base=number("Li"),
        wheel_diameters=diameters,
        steering_offset=number("Thi", 0.0),
        runs=int(number("N", 0.0)),
        side=side if side else None,
        source=str(path),
    )


#: The platform words :func:`read_run` takes: the dataset's ``diff`` and ``tricyc``, and the
#: robot type's ``tricycle`` for ``tricyc``.
_PLATFORMS = {"diff": "diff", "tricyc": "tricyc", "tricycle": "tricyc"}


def _platform_of_columns(data: NDArray[np.float64]) -> tuple[str | None, int]:
    """What columns 5 and 6 say a run is, and the row that says it: ``"diff"`` where column 6
    goes beyond any steering angle (±π/2: a wheel's ticks per cycle, tens in every real
    run), ``"tricyc"`` where it is fractional within ±π/2 beside whole ticks in column 5 (a
    steering angle [rad]); None (row −1) where they cannot tell."""
    fifth, sixth = data[:, 4], data[:, 5]
    beyond = np.flatnonzero(np.abs(sixth) > STEER_LIMIT)
    if beyond.size:
        return "diff", int(beyond[0])
    fractional = np.flatnonzero(sixth != np.round(sixth))
    if fractional.size and np.all(fifth == np.round(fifth)):
        return "tricyc", int(fractional[0])
    return None, -1


def read_run(path: str | Path, platform: str | None = None) -> OdometryLog:
    """Read one synchronised run file ``<id>_run-NN.csv``.

    Parameters
    ----------
    path : the run file (plain or gzip)
    platform : "diff", "tricycle" (or the dataset's "tricyc"), or None
        What columns 5 and 6 mean: the right and left wheels' ticks per cycle (diff), or
        the traction wheel's ticks per cycle and the steering angle [rad] (tricycle). None:
        what the columns say (column 6 beyond ±π/2: ticks, a diff run; fractional within
        ±π/2 beside whole ticks in column 5: a steering angle, a tricycle run), an
        :class:`~odomkit.errors.InputError` where they cannot tell. A platform the columns
        contradict is an :class:`~odomkit.errors.InputError` too, never a steering angle
        read as ticks. :func:`read_experiment` takes it from the experiment's metadata.

    Warns
    -----
    UserWarning
        When a tick column never decreases and takes many values: the dataset's ticks are
        per-cycle increments, so such a column is a cumulative counter in a foreign file.
    """
    if platform is not None and platform not in _PLATFORMS:
        raise InputError(f"platform must be diff or tricycle (or tricyc), got {platform!r}", source=str(path))
    data = read_numeric(path, 6, delimiter=",")
    seen, row = _platform_of_columns(data)
    value = f"{data[row, 5]:.6g} in data row {row + 1}" if seen else ""
    if platform is None and seen is None:
        raise InputError("columns 5 and 6 cannot tell a diff run from a tricycle run (column 6 holds "
                         "only whole numbers within ±π/2: a left wheel that hardly turns, or a steering "
                         "held straight); pass platform='diff' or platform='tricycle'", source=str(path))
    platform = _PLATFORMS[platform] if platform is not None else seen
    if seen == "tricyc" and platform == "diff":
        raise InputError(f"column 6 holds {value}, no whole number of ticks: a tricycle run's steering "
                         "angle [rad], not a diff run's left-wheel ticks; read it as a tricycle run "
                         "(platform='tricycle'; on the command line, with a tricycle robot file)",
                         source=str(path))
    if seen == "diff" and platform == "tricyc":
        raise InputError(f"column 6 holds {value}, no steering angle (at most ±π/2 rad): a diff run's "
                         "left-wheel ticks; read it as a diff run (platform='diff'; on the command line, "
                         "with a diff robot file)", source=str(path))
    t = data[:, 0]
    truth = np.column_stack((data[:, 1], data[:, 2], unwrap_angle(data[:, 3])))
    if platform == "diff":
        channels = {"ticks_right": data[:, 4].copy(), "ticks_left": data[:, 5].copy()}
    else:
        channels = {"ticks": data[:, 4].copy(), "steer": data[:, 5].copy()}
    for col, name in ((5, "ticks_right"), (6, "ticks_left")) if platform == "diff" else ((5, "ticks"),):
        warn_if_cumulative(channels[name], str(path), f"column {col} ({name})")
    return OdometryLog(t, channels, truth, str(path), {"format": "optiodom", "platform": platform})


@dataclass(frozen=True)
class OptiOdomExperiment:
    """All runs of one experiment folder, with the direction of each run."""

    metadata: OptiOdomMetadata
    runs: tuple[OdometryLog, ...]

    @property
    def directions(self) -> tuple[str, ...]:
        """"cw" or "ccw" per run, from the sign of the ground-truth heading change."""
        return tuple("ccw" if r.ground_truth is not None and r.ground_truth[-1, 2] > r.ground_truth[0, 2]
                     else "cw" for r in self.runs)


def read_experiment(folder: str | Path) -> OptiOdomExperiment:
    """Read ``<folder>/<id>_metadata.csv`` and every ``<id>_run-NN.csv`` in run order."""
    folder = Path(folder)
    metas = sorted(folder.glob("*_metadata.csv"))
    if not metas:
        raise InputError("no *_metadata.csv in this folder", source=str(folder))
    meta = read_metadata(metas[0])
    run_files = sorted(folder.glob("*_run-*.csv"),
                       key=lambda p: int(re.findall(r"run-(\d+)", p.name)[0]))
    if not run_files:
        raise InputError("no *_run-NN.csv files in this folder", source=str(folder))
    return OptiOdomExperiment(meta, tuple(read_run(p, meta.platform) for p in run_files))
