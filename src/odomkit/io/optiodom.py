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

from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
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


def read_run(path: str | Path, platform: str = "diff") -> OdometryLog:
    """Read one synchronised run file ``<id>_run-NN.csv``.

    Parameters
    ----------
    path : the run file (plain or gzip)
    platform : "diff" or "tricyc" (decides what columns 5 and 6 mean)

    Warns
    -----
    UserWarning
        When a tick column never decreases and takes many values: the dataset's ticks are
        per-cycle increments, so such a column is a cumulative counter in a foreign file.
    """
    if platform not in ("diff", "tricyc"):
        raise InputError(f"platform must be diff or tricyc, got {platform!r}", source=str(path))
    data = read_numeric(path, 6, delimiter=",")
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
