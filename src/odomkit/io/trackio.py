"""Writing pose tracks: odomkit CSV (with covariance) and TUM trajectory files."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from odomkit.angles import wrap_angle
from odomkit.io.files import refuse_overwrite
from odomkit.io.table import polars_module
from odomkit.track import Track

__all__ = ["TRACK_COLUMNS", "track_table", "write_track_csv", "write_tum"]

TRACK_COLUMNS = ("t", "x", "y", "theta", "cov_xx", "cov_xy", "cov_xtheta", "cov_yy",
                 "cov_ytheta", "cov_thetatheta")
_COV_INDEX = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def track_table(track: Track) -> np.ndarray:
    """The track as an ``(N, 10)`` array in :data:`TRACK_COLUMNS` order (NaN covariance
    when none was propagated)."""
    n = track.poses.shape[0]
    table = np.full((n, len(TRACK_COLUMNS)), np.nan)
    table[:, 0] = track.t
    table[:, 1:4] = track.poses
    if track.cov is not None:
        for j, (a, b) in enumerate(_COV_INDEX):
            table[:, 4 + j] = track.cov[:, a, b]
    return table


def write_track_csv(path: str | Path, track: Track, overwrite: bool = False) -> Path:
    """Write ``t,x,y,theta,cov_xx,...`` (DESIGN.md); covariance cells are empty when the
    track has no covariance. θ is written continuous (unwrapped). Numbers are written
    with all the digits that read back to the same double; with polars installed (the
    ``fast`` extra) the file is written about 5x faster.
    """
    path = Path(path)
    refuse_overwrite(path, overwrite=overwrite)
    table = track_table(track)
    pl: Any = polars_module()
    if pl is not None:
        frame = pl.DataFrame(table, schema=list(TRACK_COLUMNS), orient="row")
        frame = frame.with_columns(pl.col(c).fill_nan(None) for c in TRACK_COLUMNS[4:])
        frame.write_csv(path, null_value="")
        return path
    buffer = io.StringIO()
    if track.cov is None:
        np.savetxt(buffer, table[:, :4], delimiter=",", fmt="%.17g")
        # Empty covariance cells keep every row as wide as the header.
        body = "".join(line + ",,,,,,\n" for line in buffer.getvalue().splitlines())
    else:
        np.savetxt(buffer, table, delimiter=",", fmt="%.17g")
        body = buffer.getvalue()
    path.write_text(",".join(TRACK_COLUMNS) + "\n" + body, encoding="utf-8")
    return path


def write_tum(path: str | Path, track: Track, overwrite: bool = False) -> Path:
    """Write a TUM trajectory (``timestamp tx ty tz qx qy qz qw``), readable by evo.

    The planar pose becomes z = 0 and a rotation about z by θ: q = (0, 0, sin θ/2, cos θ/2)
    with θ wrapped to [−π, π), so that q_w >= 0 (q and −q are the same rotation).
    """
    path = Path(path)
    refuse_overwrite(path, overwrite=overwrite)
    theta = wrap_angle(track.poses[:, 2])
    n = theta.size
    table = np.column_stack((track.t, track.poses[:, 0], track.poses[:, 1], np.zeros(n),
                             np.zeros(n), np.zeros(n), np.sin(theta / 2), np.cos(theta / 2)))
    np.savetxt(path, table, fmt="%.9f", delimiter=" ")
    return path
