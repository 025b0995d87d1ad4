"""Pose tracks: odomkit CSV (with covariance and optional truth), TUM and KITTI trajectory files."""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import wrap_angle
from odomkit.errors import InputError
from odomkit.io.files import refuse_overwrite
from odomkit.io.table import polars_module
from odomkit.track import Track

__all__ = ["kitti_times_path", "read_pose_file", "read_track_csv", "TRACK_COLUMNS", "track_table",
           "TrackFile", "TRUTH_COLUMNS", "write_kitti", "write_track_csv", "write_tum"]

TRACK_COLUMNS = ("t", "x", "y", "theta", "cov_xx", "cov_xy", "cov_xtheta", "cov_yy",
                 "cov_ytheta", "cov_thetatheta")
#: Columns a track carries after ``odomkit track --truth`` (or a log with truth): the truth
#: at each row, empty outside the truth's span or gaps (and ``gt_theta`` for position-only truth).
TRUTH_COLUMNS = ("gt_x", "gt_y", "gt_theta")
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


def write_track_csv(path: str | Path, track: Track, overwrite: bool = False,
                    truth: NDArray[np.float64] | None = None) -> Path:
    """Write ``t,x,y,theta,cov_xx,...`` (:data:`TRACK_COLUMNS`; docs/reference/commands/track.md,
    "Outputs"); covariance cells are empty when the track has no covariance. θ is written
    continuous (unwrapped). Numbers are written with all the digits that read back to the
    same double; with polars installed (the ``fast`` extra) the file is written about 5x
    faster.

    ``truth`` (N, 3), NaN where there is none, adds the :data:`TRUTH_COLUMNS` (empty cells
    for NaN).
    """
    path = Path(path)
    refuse_overwrite(path, overwrite=overwrite)
    table = track_table(track)
    columns: tuple[str, ...] = TRACK_COLUMNS
    if truth is not None:
        table = np.column_stack((table, np.asarray(truth, dtype=float).reshape(-1, 3)))
        columns = TRACK_COLUMNS + TRUTH_COLUMNS
    pl: Any = polars_module()
    if pl is not None:
        frame = pl.DataFrame(table, schema=list(columns), orient="row")
        frame = frame.with_columns(pl.col(c).fill_nan(None) for c in columns[4:])
        frame.write_csv(path, null_value="")
        return path
    buffer = io.StringIO()
    if truth is not None:
        np.savetxt(buffer, table, delimiter=",", fmt="%.17g")
        body = buffer.getvalue().replace("nan", "")  # NaN cells are written empty
    elif track.cov is None:
        np.savetxt(buffer, table[:, :4], delimiter=",", fmt="%.17g")
        # Empty covariance cells keep every row as wide as the header.
        body = "".join(line + ",,,,,,\n" for line in buffer.getvalue().splitlines())
    else:
        np.savetxt(buffer, table, delimiter=",", fmt="%.17g")
        body = buffer.getvalue()
    path.write_text(",".join(columns) + "\n" + body, encoding="utf-8")
    return path


@dataclass(frozen=True)
class TrackFile:
    """A track read back from :func:`write_track_csv`'s CSV.

    Parameters
    ----------
    t : ndarray, shape (N,)
        [s]
    poses : ndarray, shape (N, 3)
        [m, m, rad], θ continuous.
    cov : ndarray, shape (N, 3, 3), optional
        None when the file has no covariance columns or they are empty.
    truth : ndarray, shape (N, 3), optional
        The ``gt_*`` columns (NaN where empty); None when the file has none.
    source : str
    """

    t: NDArray[np.float64]
    poses: NDArray[np.float64]
    cov: NDArray[np.float64] | None
    truth: NDArray[np.float64] | None
    source: str


def read_track_csv(path: str | Path) -> TrackFile:
    """Read a track CSV written by ``odomkit track --out`` (header ``t,x,y,theta[,cov_*][,gt_*]``).

    Columns are found by their header names, in any order; the covariance and truth
    columns are optional, and their empty cells read as NaN.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    with path.open(encoding="utf-8", errors="replace") as fh:
        header = [h.strip() for h in fh.readline().split(",")]
    missing = [c for c in TRACK_COLUMNS[:4] if c not in header]
    if missing:
        raise InputError(f"not a track CSV: no column {', '.join(missing)} in the header (expected "
                         f"{','.join(TRACK_COLUMNS)}, as written by odomkit track --out)",
                         source=str(path), line=1)
    lines = [(n, line) for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace")
                                                  .splitlines()[1:], start=2)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise InputError("the track has no rows", source=str(path))
    rows = []
    for n, line in lines:
        fields = line.split(",")
        if len(fields) != len(header):
            raise InputError(f"expected {len(header)} columns, found {len(fields)}", source=str(path), line=n)
        try:
            rows.append([float(f) if f.strip() else np.nan for f in fields])
        except ValueError:
            bad = next(f for f in fields if f.strip() and not _is_float(f))
            raise InputError(f"{bad.strip()!r} is not a number", source=str(path), line=n) from None
    data = np.array(rows, dtype=float)
    col = {name: i for i, name in enumerate(header)}
    core = data[:, [col[c] for c in TRACK_COLUMNS[:4]]]
    if not np.all(np.isfinite(core)):
        r, c = np.argwhere(~np.isfinite(core))[0]
        raise InputError(f"column {TRACK_COLUMNS[c]} is empty or not finite", source=str(path),
                         line=lines[r][0])
    cov = None
    if all(c in col for c in TRACK_COLUMNS[4:]):
        cells = data[:, [col[c] for c in TRACK_COLUMNS[4:]]]
        if np.all(np.isfinite(cells)):
            cov = np.empty((data.shape[0], 3, 3))
            for j, (a, b) in enumerate(_COV_INDEX):
                cov[:, a, b] = cov[:, b, a] = cells[:, j]
        elif np.any(np.isfinite(cells)):
            r = int(np.flatnonzero(~np.all(np.isfinite(cells), axis=1))[0])
            raise InputError("covariance cells are empty in some rows only", source=str(path),
                             line=lines[r][0])
    truth = None
    if any(c in col for c in TRUTH_COLUMNS):
        truth = np.column_stack([data[:, col[c]] if c in col else np.full(data.shape[0], np.nan)
                                 for c in TRUTH_COLUMNS])
    if np.any(np.diff(core[:, 0]) < 0):
        raise InputError("track times decrease; expected a track in time order", source=str(path))
    return TrackFile(core[:, 0].copy(), core[:, 1:4].copy(), cov, truth, str(path))


def read_pose_file(path: str | Path, what: str = "track") -> TrackFile:
    """A track CSV (``odomkit track --out``, found by its header ``t,x,y,theta``), else any
    pose file the truth reader takes (TUM, KITTI rows with time, headerless
    ``t,x,y,theta``), which must then have a heading; the latter has no covariance.

    ``what`` names the file in the error message (e.g. ``"track"``, ``"odometry"``).
    """
    from odomkit.io.truth import read_truth

    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    with path.open("rb") as fh:
        head = fh.read(4096).decode("utf-8", errors="replace")
    first = next((line for line in head.splitlines() if line.strip() and not line.startswith("#")), "")
    if {"t", "x", "y", "theta"} <= {f.strip() for f in first.split(",")}:
        return read_track_csv(path)
    poses = read_truth(path)
    if poses.theta is None:
        raise InputError(f"the {what} has no heading column; expected a track CSV (odomkit track --out), "
                         "a TUM file or t,x,y,theta", source=str(path))
    return TrackFile(poses.t, np.column_stack((poses.xy, poses.theta)), None, None, str(path))


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


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


def kitti_times_path(path: str | Path) -> Path:
    """Where :func:`write_kitti` puts the times of a KITTI pose file: beside it, its last
    suffix replaced by ``.times.txt`` (``run.kitti`` -> ``run.times.txt``, ``poses.txt`` ->
    ``poses.times.txt``).

    Examples
    --------
    >>> kitti_times_path("out/run.kitti").as_posix()
    'out/run.times.txt'
    """
    path = Path(path)
    if path.name in ("", ".", ".."):  # "", "." and "/" have no name to put the times beside
        raise InputError("--kitti names a folder; give a file path", source=str(path))
    return path.with_name(path.stem + ".times.txt")


def write_kitti(path: str | Path, track: Track, overwrite: bool = False) -> tuple[Path, Path]:
    """Write a KITTI pose file and its times (:func:`kitti_times_path`), readable by evo
    (``evo_traj kitti``, ``evo_ape kitti``).

    A KITTI pose is the 3×4 matrix [R | p] of the pose in the first frame's world, written
    row by row: 12 numbers a line, ``r11 r12 r13 px r21 r22 r23 py r31 r32 r33 pz`` (KITTI
    odometry development kit, readme). The planar pose is a rotation about z by θ and
    z = 0: R = [[cos θ, −sin θ, 0], [sin θ, cos θ, 0], [0, 0, 1]], p = (x, y, 0), so the
    plane is x–y with z up (KITTI's own camera frame has its ground in x–z; evo compares
    any two files alike). KITTI rows carry no time, and evo pairs KITTI poses by their
    index: the times go to a file of their own, one per line in seconds, as KITTI's
    ``times.txt``. ``paste -d' ' TIMES POSES`` makes the 13-number rows that
    ``--truth-format kitti`` reads. Numbers are written with 17 significant digits (they
    read back to the same doubles).

    Returns
    -------
    (Path, Path)
        The pose file and the times file.
    """
    path = Path(path)
    times = kitti_times_path(path)
    refuse_overwrite(path, times, overwrite=overwrite)
    x, y, theta = track.poses.T
    c, s = np.cos(theta), np.sin(theta)
    zero, one = np.zeros_like(x), np.ones_like(x)
    rows = np.column_stack((c, 0.0 - s, zero, x, s, c, zero, y, zero, zero, one, zero))  # 0 - s: no '-0'
    np.savetxt(path, rows, fmt="%.17g", delimiter=" ")
    np.savetxt(times, track.t, fmt="%.17g")
    return path, times
