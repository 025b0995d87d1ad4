"""Reading ground-truth files: TUM, KITTI-style pose rows with a time column, and text tables.

Formats (``--truth-format``):

``tum``
    ``t x y z qx qy qz qw`` per line (evo, the TUM RGB-D benchmark); the heading is the
    yaw of the quaternion, atan2(2(q_w q_z + q_x q_y), 1 − 2(q_y² + q_z²)).
``kitti``
    A KITTI pose row (the 3×4 matrix [R | p] row by row, 12 numbers) preceded by its time:
    ``t r11 r12 r13 px r21 r22 r23 py r31 r32 r33 pz`` (13 numbers). The plane is x–y
    with z up (a robot's map frame): x = px, y = py, θ = atan2(r21, r11). KITTI's own
    12-number rows carry no time, and truth must have a clock; put the time first (e.g.
    ``paste -d' ' times.txt poses.txt``). KITTI's camera frame has its ground plane in
    x–z: rotate such poses to z up first.
``csv``
    Text columns ``t,x,y[,theta]`` [s, m, m, rad] (``theta_deg`` for degrees), found by
    header names (``t``/``time``/``timestamp``, ``x``/``gt_x``, ``y``/``gt_y``,
    ``theta``/``yaw``/``heading``/``gt_theta``) or named by ``--truth-columns``: in order
    for a headerless file (``t,x,y,_,theta``; ``_`` skips a column) or as a map of header
    names (``t=stamp,x=px,y=py``). Without a heading column the truth is position-only.

    Or GPS fixes ``t,lat,lon[,alt][,heading_deg_north]`` [s, deg, deg, m, deg]: WGS 84
    latitude and longitude (headers ``lat``/``latitude``, ``lon``/``lng``/``long``/``longitude``,
    ``alt``/``altitude``/``height``, height above the ellipsoid, 0 when absent; or
    ``--truth-columns t=stamp,lat=LAT,lon=LON``), projected onto the local east-north plane
    of the first fix in time (:func:`project_latlon`: x east, y north [m], origin that fix).
    Their heading, if any, is ``heading_deg_north``: degrees clockwise from true north at the
    fix, as a compass or a two-antenna GNSS receiver gives it (the body's heading, not the
    course over ground), turned into odomkit's θ (counter-clockwise from x = east). A
    ``theta``/``yaw``/``heading`` column in such a file is refused: its convention is unknown.
    A file with both x, y and latitude/longitude columns is refused; so are a latitude
    beyond ±90° and a longitude beyond ±180°.

    Or GPS fixes ``t,ecef_x,ecef_y,ecef_z[,heading_deg_north]`` [s, m, m, m, deg]:
    earth-centred, earth-fixed WGS 84 coordinates (an RTK receiver's or a SPAN system's;
    headers ``ecef_x``/``x_ecef``/``ecefx`` and so on for y and z, any case), projected as
    latitude/longitude fixes are, about the first fix in time (:func:`project_ecef`). A
    file with ECEF and x, y or latitude/longitude columns is refused, and so is a point
    whose distance from the earth's centre is not one on or near the earth (6.30e6 m to
    6.42e6 m). Plain x, y columns that look like ECEF (beside a further column z with
    x² + y² + z² the earth's radius squared and a height above the ellipsoid that a point
    on the ground has) get a warning: read so, they are a plane through the earth's centre.
``auto``
    A header means ``csv``; otherwise 8 columns mean ``tum``, 13 (or 12) ``kitti``, 3 or 4
    ``csv``.

Every format: comma, semicolon, tab or whitespace separated, ``#`` comments, plain or gzip
(``.gz``), sniffed as a log's text is (:func:`odomkit.io.text.sniff_layout`); time in s, ms,
us or ns, or seconds per unit as a number (``--truth-time-unit``); of a file of tagged records
(libRSF's ``point2 t x y ...`` among ``angle ...`` lines), the lines of one type, their tag
dropped (``record``, ``--truth-record``: :func:`odomkit.io.text.select_record`). Rows are put in time order
(with a warning) and repeated times dropped (with a warning that counts them); a NaN is an
error naming its line: leave such fixes out, and the gap is left out and counted.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit import units
from odomkit.angles import unwrap_angle
from odomkit.errors import InputError
from odomkit.frames import UP_AXES, likely_up, planar_poses, quaternion_matrices
from odomkit.io._headers import no_such_column, time_text_error
from odomkit.io.table import to_seconds
from odomkit.io.text import (
    check_record_columns,
    content_lines,
    is_number,
    read_text,
    record_error,
    seconds_per_unit,
    select_record,
    sniff_layout,
    split_fields,
)
from odomkit.truth import Truth

__all__ = ["ECEF_RADIUS_RANGE", "GEO_SPAN_WARNING", "project_ecef", "project_latlon", "TRUTH_FORMATS",
           "parse_truth_columns", "read_truth"]

TRUTH_FORMATS = ("auto", "tum", "kitti", "csv")
_ECEF = ("ecef_x", "ecef_y", "ecef_z")
_TARGETS = ("t", "x", "y", "x_mm", "y_mm", "theta", "theta_deg", "lat", "lon", "alt", *_ECEF,
            "heading_deg_north")
_HEADER_NAMES = {
    "t": ("t", "time", "timestamp", "stamp", "time_s"),
    "x": ("x", "gt_x", "x_gt", "pos_x", "tx"),
    "y": ("y", "gt_y", "y_gt", "pos_y", "ty"),
    "x_mm": ("x_mm",),  # a motion capture's export in millimetres (Vicon's)
    "y_mm": ("y_mm",),
    "theta": ("theta", "gt_theta", "theta_gt", "yaw", "heading", "th"),
    "theta_deg": ("theta_deg", "yaw_deg", "heading_deg"),
    "lat": ("lat", "latitude"),
    "lon": ("lon", "lng", "long", "longitude"),
    "alt": ("alt", "altitude", "height"),
    "ecef_x": ("ecef_x", "x_ecef", "ecefx"),
    "ecef_y": ("ecef_y", "y_ecef", "ecefy"),
    "ecef_z": ("ecef_z", "z_ecef", "ecefz"),
    "heading_deg_north": ("heading_deg_north",),
}
#: Fixes farther than this from the first [m] get a warning: the east-north plane of the first
#: fix (tangent to the earth there, an orthographic projection) shortens a step taken at a
#: distance d from the first fix, along the line to it, by 1 − cos(d/R) (R the earth's
#: radius; across that line the scale stays 1): 4.9e-6 at 20 km (against Vincenty's
#: geodesic distances at 45° latitude: 4.90e-6 to 4.94e-6), 1e-5 at 28 km, 3.1e-5 at 50 km.
GEO_SPAN_WARNING = 20_000.0
#: The earth's mean radius (IUGG) [m]: only for the figure in that warning.
_MEAN_RADIUS = 6_371_008.8
_GEO_COLUMNS = "t=TIME,lat=LAT,lon=LON"
_GEO_HINT = f"--truth-columns {_GEO_COLUMNS}"
_ECEF_COLUMNS = "t=TIME,ecef_x=X,ecef_y=Y,ecef_z=Z"
#: Distances from the earth's centre [m] that an ECEF fix may have: the ellipsoid's radii run
#: from 6,356,752 m (poles) to 6,378,137 m (equator), and this range holds 57 km below the one
#: and 42 km above the other, so that it refuses only what is nowhere near the earth: local
#: x, y, z in metres, or kilometres, read as ECEF.
ECEF_RADIUS_RANGE = (6.30e6, 6.42e6)
# WGS 84 (NIMA TR8350.2, table 3.1): semi-major axis [m] and flattening; only for the
# ECEF-likeness of plain x, y, z (the projection itself is pymap3d's).
_WGS84_A = 6_378_137.0
_WGS84_F = 1 / 298.257223563


def parse_truth_columns(text: str) -> dict[str, str] | list[str]:
    """``--truth-columns``: ``"t,x,y,_,theta"`` (in order) or ``"t=stamp,x=px,y=py"`` (a map).

    Examples
    --------
    >>> parse_truth_columns("t,x,y,_,theta")
    ['t', 'x', 'y', '_', 'theta']
    >>> parse_truth_columns("t=stamp, x=px, y=py")
    {'t': 'stamp', 'x': 'px', 'y': 'py'}
    """
    items = [s.strip() for s in text.split(",") if s.strip()]
    if any("=" in s for s in items):
        mapping: dict[str, str] = {}
        for item in items:
            key, sep, name = (p.strip() for p in item.partition("="))
            if not sep or key not in _TARGETS or not name:
                raise InputError(f"--truth-columns item {item!r} must look like target=column with "
                                 f"target one of {', '.join(_TARGETS)}")
            mapping[key] = name
        return mapping
    bad = [s for s in items if s not in _TARGETS and s != "_"]
    if bad or len(set(s for s in items if s != "_")) != len([s for s in items if s != "_"]):
        raise InputError(f"--truth-columns {text!r}: name each column once as one of "
                         f"{', '.join(_TARGETS)}, or _ to skip it")
    return items


#: Position-only fixes that repeat the one before in at least this share of the rows are a
#: logger writing the receiver's last fix at each of its own rows (a 5 Hz GPS in a 10 Hz
#: CAN log), not a receiver standing still now and then.
HELD_SHARE = 0.2
#: A repeat that lasts longer than this [s] is a standstill: its last row is kept too.
HELD_SPAN = 1.0


def _held_fixes(t: NDArray[np.float64], position: NDArray[np.float64], path: Path
                ) -> NDArray[np.bool_] | None:
    """Rows to keep of position-only fixes that a logger held (repeated at its own rows), or
    None where there are few repeats. A held fix stamped at a later row is the position of
    an earlier time: read so, the truth lags the vehicle by up to a fix's period, and the
    clock offset and the noise fitted to it are wrong. The first row of each repeat is kept
    (when the fix arrived), and the last of one longer than :data:`HELD_SPAN` (a vehicle
    standing still, whose position holds)."""
    if len(t) < 3:
        return None
    same = np.all(position[1:] == position[:-1], axis=1)
    first = np.concatenate(([True], ~same))
    starts = np.flatnonzero(first)
    ends = np.concatenate((starts[1:], [len(t)])) - 1
    standing = t[ends] - t[starts] > HELD_SPAN
    # Only short repeats count: a receiver standing still repeats its fix too, for longer.
    held = int(np.sum((ends - starts)[~standing]))
    if held < HELD_SHARE * (len(t) - 1):
        return None
    keep = first.copy()
    keep[ends[standing]] = True
    warnings.warn(f"{path}: {held} of {len(t)} fixes repeat the one before (a logger "
                  "writing its last fix at every row): the first row of each fix is kept, when it "
                  f"arrived, and the last of a repeat longer than {HELD_SPAN:g} s (standing still)",
                  stacklevel=3)
    return keep


def _table(path: Path, rows: list[tuple[int, list[str]]], ncols: int,
           used: Sequence[int] | None = None) -> NDArray[np.float64]:
    """The fields as an (n, ncols) float array; errors name the line and column.

    Only the columns ``used`` (None: all) are read as numbers; the others may hold anything
    (a wall-clock date, nothing) and are NaN in the array. Every row must still have
    ``ncols`` fields: a delimiter inside a text field would shift the numbers after it.
    """
    for lineno, fields in rows:
        if len(fields) != ncols:
            raise InputError(f"expected {ncols} columns, found {len(fields)}", source=str(path),
                             line=lineno)
    cols = list(range(ncols)) if used is None else list(used)
    try:
        picked = np.array([f for _, f in rows] if used is None
                          else [[f[i] for i in cols] for _, f in rows], dtype=float)
    except ValueError:
        for lineno, fields in rows:
            for col in cols:
                if not is_number(fields[col]):
                    raise InputError(f"column {col + 1}: {fields[col]!r} is not a number", source=str(path),
                                     line=lineno) from None
        raise
    picked = picked.reshape(-1, len(cols))
    bad = ~np.isfinite(picked)
    if bad.any():
        row, k = np.argwhere(bad)[0]
        raise InputError(f"column {cols[k] + 1} is {picked[row, k]}; truth needs finite numbers (leave "
                         "the fix out: a gap is left out of the scores and counted)",
                         source=str(path), line=rows[row][0])
    if used is None:
        return picked
    data = np.full((len(rows), ncols), np.nan)
    data[:, cols] = picked
    return data


def _csv_columns(path: Path, header: list[str] | None, ncols: int,
                 columns: dict[str, str] | list[str] | None) -> dict[str, int]:
    """Target -> column index for a text truth file."""
    if isinstance(columns, list):
        if len(columns) > ncols:
            raise InputError(f"--truth-columns names {len(columns)} columns, the file has {ncols}",
                             source=str(path))
        index = {name: i for i, name in enumerate(columns) if name != "_"}
    elif isinstance(columns, dict):
        if header is None:
            raise InputError("--truth-columns maps header names, but the file has no header; "
                             "name the columns in order instead (t,x,y,theta)", source=str(path))
        index = {}
        for key, name in columns.items():
            if name not in header:
                raise InputError(no_such_column(name, header, "--truth-columns", key, "the truth file"),
                                 source=str(path))
            index[key] = header.index(name)
    elif header is not None:
        lower = [h.lower() for h in header]
        index = {}
        for key, names in _HEADER_NAMES.items():
            found = [i for i, h in enumerate(lower) if h in names]
            if found:
                index[key] = found[0]
    elif ncols in (3, 4):
        index = dict(zip(("t", "x", "y", "theta"), range(ncols), strict=False))
    else:
        raise InputError(f"{ncols} columns and no header: name them with --truth-columns "
                         "(e.g. t,x,y,theta) or give --truth-format tum|kitti", source=str(path))
    explicit = columns is not None
    geo = [k for k in ("lat", "lon", *_ECEF) if k in index]
    if any(k in index for k in _ECEF) and "alt" in index and not explicit:
        del index["alt"]  # a height beside ECEF coordinates (they hold it already): not read
    if not geo:
        if "alt" in index and not explicit:
            del index["alt"]  # a height beside x, y (it was never read): not a GPS file
        extra = [k for k in ("alt", "heading_deg_north") if k in index]
        if extra:
            raise InputError(f"{extra[0]} goes with latitude/longitude columns (lat, lon) or ECEF ones "
                             f"(ecef_x, ecef_y, ecef_z), and the file has none; x, y truth takes its "
                             f"heading as theta (rad, counter-clockwise from x) or theta_deg",
                             source=str(path))
    else:
        _check_geo_columns(path, header, index)
        return index
    millimetres = [k for k in ("x_mm", "y_mm") if k in index]
    if millimetres and (len(millimetres) == 1 or "x" in index or "y" in index):
        named = ", ".join(k for k in ("x", "y", "x_mm", "y_mm") if k in index)
        raise InputError("positions in millimetres are x_mm and y_mm together, not beside x or y "
                         f"(columns named: {named})",
                         source=str(path))
    missing = [k for k in ("t", "x", "y") if k not in index and f"{k}_mm" not in index]
    if missing:
        raise InputError(f"no column for {', '.join(missing)} (header {header}); name the columns "
                         "with --truth-columns, e.g. t=time,x=px,y=py,theta=yaw (or "
                         f"{_GEO_HINT} for GPS fixes, or {_ECEF_COLUMNS} for ECEF ones)",
                         source=str(path))
    if "theta" in index and "theta_deg" in index:
        raise InputError("give theta or theta_deg, not both", source=str(path))
    return index


def _column_name(header: list[str] | None, index: int) -> str:
    return repr(header[index]) if header is not None else f"column {index + 1}"


def _check_geo_columns(path: Path, header: list[str] | None, index: dict[str, int]) -> None:
    """A GPS file's columns: t and either lat, lon[, alt] or ecef_x, ecef_y, ecef_z, never
    two of these and x, y, and a heading only as ``heading_deg_north``."""
    kinds = [(what, keys, hint) for what, keys, hint in (
        ("x, y", ("x", "y", "x_mm", "y_mm"), "t=TIME,x=X,y=Y"),
        ("latitude/longitude", ("lat", "lon", "alt"), _GEO_COLUMNS),
        ("ECEF", _ECEF, _ECEF_COLUMNS)) if any(k in index for k in keys)]
    if len(kinds) > 1:
        found = ", ".join(f"{k} ({_column_name(header, index[k])})" for _, keys, _ in kinds for k in keys
                          if k in index)
        names = [what for what, _, _ in kinds]
        said = ("both " if len(names) == 2 else "") + ", ".join(names[:-1]) + " and " + names[-1]
        raise InputError(f"the file has {said} columns: {found}; name the ones to read with --truth-columns "
                         f"({' or '.join(hint for _, _, hint in kinds)})", source=str(path))
    ecef = any(k in index for k in _ECEF)
    position, columns = (_ECEF, _ECEF_COLUMNS) if ecef else (("lat", "lon", "alt"), _GEO_COLUMNS)
    missing = [k for k in ("t", *position[:3 if ecef else 2]) if k not in index]
    if missing:
        raise InputError(f"no column for {', '.join(missing)} (header {header}); name the columns "
                         f"with --truth-columns {columns}", source=str(path))
    angles = [k for k in ("theta", "theta_deg") if k in index]
    if angles:
        col = index[angles[0]]
        if header is not None:
            mapped = ",".join(f"{k}={header[index[k]]}" for k in ("t", *position) if k in index)
            hint = f"--truth-columns {mapped},heading_deg_north={header[col]}"
        else:
            order = {i: k for k, i in index.items()} | {col: "heading_deg_north"}
            hint = "--truth-columns " + ",".join(order.get(i, "_") for i in range(max(order) + 1))
        raise InputError(
            f"{'an ECEF' if ecef else 'a latitude/longitude'} file's heading must say its convention, and "
            f"{_column_name(header, col)} "
            "does not: if it is degrees clockwise from true north (a compass's, a GNSS receiver's), "
            f"read it as heading_deg_north ({hint}) and odomkit turns it into its θ (counter-clockwise "
            "from east); otherwise convert it to that, or leave it out (position-only truth)",
            source=str(path))


def _off_the_earth(x: NDArray[np.float64], y: NDArray[np.float64], z: NDArray[np.float64]
                   ) -> tuple[int, str] | None:
    """The first ECEF point outside :data:`ECEF_RADIUS_RANGE` and what to say of it, or None."""
    r = np.sqrt(x**2 + y**2 + z**2)
    lo, hi = ECEF_RADIUS_RANGE
    bad = np.flatnonzero(~((r >= lo) & (r <= hi)))
    if not bad.size:
        return None
    return int(bad[0]), (f"not ECEF (|r| = {r[bad[0]]:.4g} m; a point on or near the earth is "
                         f"{lo / 1e6:.2f}e6 to {hi / 1e6:.2f}e6 m from its centre); read local "
                         "coordinates as x, y")


def _check_geo_range(path: Path, rows: list[tuple[int, list[str]]], data: NDArray[np.float64],
                     header: list[str] | None, index: dict[str, int]) -> None:
    """|latitude| <= 90° and |longitude| <= 180°, or ECEF points near the earth
    (:data:`ECEF_RADIUS_RANGE`), else one line naming the row and columns."""
    if "ecef_x" in index:
        cols = [index[k] for k in _ECEF]
        off = _off_the_earth(*(data[:, c] for c in cols))
        if off is not None:
            names = ", ".join(k if header is None else header[index[k]] for k in _ECEF)
            raise InputError(f"columns {', '.join(str(c + 1) for c in cols)} ({names}) are {off[1]}",
                             source=str(path), line=rows[off[0]][0])
        return
    for key, limit, what in (("lat", 90.0, "latitude"), ("lon", 180.0, "longitude")):
        col = index[key]
        bad = np.flatnonzero(np.abs(data[:, col]) > limit)
        if bad.size:
            name = key if header is None else header[col]
            raise InputError(f"column {col + 1} ({name}) is {data[bad[0], col]:g}; a {what} is degrees "
                             f"within ±{limit:g}", source=str(path), line=rows[bad[0]][0])


#: Plain x, y [m] at least this far from 0 on every row can be ECEF X, Y (so can any point
#: farther than 100 km from the poles' axis, i.e. 0.9° from a pole); no local frame reaches it.
_ECEF_LIKE_XY = 1e5
#: ... and are, with a further column z, where x² + y² + z² is within this share of the earth's
#: radius squared on every row ...
_ECEF_LIKE_R2 = 0.01
#: ... and the point's height above the ellipsoid within this range [m] (no ground below the
#: first, hardly a road above the second): UTM eastings and northings near 57° N or 33° S
#: (~5e5, ~6.34e6) with a height beside them pass the first two tests, as a point near the
#: equator some 20 km under the ground, and fail this one.
_ECEF_LIKE_HEIGHT = (-1e3, 1e4)


def _warn_if_ecef(path: Path, rows: list[tuple[int, list[str]]], xy: NDArray[np.float64],
                  header: list[str] | None, index: dict[str, int]) -> None:
    """Warn where plain x, y look like ECEF X, Y: read so, the track is in the plane of the
    equator through the earth's centre (a drive in Berlin, 3.8e6 m from the origin, with its
    distances shortened by the angle between that plane and the ground, and no warning).

    The test: every row's x, y at least :data:`_ECEF_LIKE_XY` from 0, and a column not read
    whose every value z puts (x, y, z) at the earth's radius (:data:`_ECEF_LIKE_R2`) and at a
    height above the WGS 84 ellipsoid that ground has (:data:`_ECEF_LIKE_HEIGHT`). Only a
    warning: UTM eastings and northings in a band near 57° N or 33° S with a height
    beside them pass it.
    """
    p = np.hypot(xy[:, 0], xy[:, 1])
    if not np.all(p >= _ECEF_LIKE_XY):
        return
    used = set(index.values())
    for col in (c for c in range(len(rows[0][1])) if c not in used):
        try:
            z = np.array([f[col] for _, f in rows], dtype=float)
        except ValueError:
            continue  # text: not a coordinate
        r2 = p**2 + z**2
        if not np.all(np.abs(r2 / _MEAN_RADIUS**2 - 1) <= _ECEF_LIKE_R2):
            continue
        # The ellipsoid's radius at geocentric latitude ψ, a(1 − f sin²ψ), is good to f²a (~70 m),
        # plenty for a range of kilometres.
        h = np.sqrt(r2) - _WGS84_A * (1 - _WGS84_F * z**2 / r2)
        if not np.all((h >= _ECEF_LIKE_HEIGHT[0]) & (h <= _ECEF_LIKE_HEIGHT[1])):
            continue
        names = {"t": index["t"], "ecef_x": index["x"], "ecef_y": index["y"], "ecef_z": col}
        if header is not None:
            hint = ",".join(f"{k}={header[i]}" for k, i in names.items())
        else:
            order = {i: k for k, i in names.items()}
            hint = ",".join(order.get(i, "_") for i in range(max(order) + 1))
        radius = f"{np.sqrt(np.median(r2)):.2e}".replace("e+0", "e")  # 6.36e6
        warnings.warn(f"{path}: columns x ({_column_name(header, index['x'])}), y "
                      f"({_column_name(header, index['y'])}) and {_column_name(header, col)} look like "
                      f"earth-centred (ECEF) coordinates (|r| ≈ {radius} m): read them "
                      f"with ecef_x,ecef_y,ecef_z (--truth-columns {hint}) for metres east and north of "
                      "the first fix; read as x, y they lie in the plane of the equator, not of the ground",
                      stacklevel=3)
        return


def _require_pymap3d(what: str = "latitude/longitude") -> Any:
    """The ``pymap3d`` package (WGS 84 geodesy), or one line saying how to install it."""
    try:
        import pymap3d
    except ImportError:
        raise InputError(f"reading {what} needs pymap3d: pip install 'odomkit[gps]'") from None
    return pymap3d


def _onto_plane(
    pm: Any,
    east: NDArray[np.float64],
    north: NDArray[np.float64],
    lat0: float,
    lon0: float,
    heading: tuple[ArrayLike, NDArray[np.float64], NDArray[np.float64]] | None,
    source: str,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """The one projection home of GPS fixes, whatever their coordinates: east and north of
    the first fix [m] as x, y, with the warning beyond :data:`GEO_SPAN_WARNING`, and
    ``heading`` = (ψ [deg] clockwise from north, latitude, longitude [deg] of each fix) as θ
    in the first fix's plane (its latitude ``lat0``, longitude ``lon0`` [deg])."""
    xy = np.column_stack((east, north)).astype(float)
    reach = float(np.max(np.hypot(xy[:, 0], xy[:, 1])))
    if reach > GEO_SPAN_WARNING:
        short = 1.0 - math.cos(reach / _MEAN_RADIUS)
        warnings.warn(f"{source}: the fixes reach {reach / 1e3:.1f} km from the first, which is the origin "
                      f"of the east-north plane they are projected onto; distances there are short by up to "
                      f"{short:.1e} of their length (1 - cos(d/R)); split the drive into parts nearer "
                      "their first fix if that matters", stacklevel=4)
    if heading is None:
        return xy, None
    psi = np.radians(np.asarray(heading[0], dtype=float))
    lat, lon = heading[1], heading[2]
    # The heading as a unit vector in the fix's own east-north-up frame, then in the first fix's.
    ex, ey, ez = pm.enu2ecefv(np.sin(psi), np.cos(psi), np.zeros_like(psi), lat, lon)
    e, n, _ = pm.ecef2enuv(ex, ey, ez, lat0, lon0)
    return xy, unwrap_angle(np.arctan2(n, e))


#: A heading column read in degrees whose every value lies within ±(π + this) and that
#: spreads over more than :data:`_RADIAN_SPREAD` holds radians: a drive that turns spreads a
#: heading in degrees far wider, and one that keeps within ±3.15° hardly turns at all.
_RADIAN_LIMIT = math.pi + 0.01
_RADIAN_SPREAD = 2.0


def _warn_if_radians(path: Path, values: NDArray[np.float64], header: Sequence[str] | None, column: int,
                     key: str) -> None:
    """Warn where a heading column read in degrees (``theta_deg``, ``heading_deg_north``)
    holds radians (:data:`_RADIAN_LIMIT`, :data:`_RADIAN_SPREAD`): read as degrees, a heading
    that turns through 2π turns through 6°, and every window starts off the robot's heading.
    A user study copied the hint ``heading_deg_north=yaw`` for KITTI's yaw (radians,
    counter-clockwise from east) and was told the yaw rate's sign was flipped. A GPS file
    takes no heading in radians: the advice there is to convert it, or to leave it out."""
    finite = values[np.isfinite(values)]
    if finite.size < 2 or not (np.all(np.abs(finite) <= _RADIAN_LIMIT)
                               and float(np.ptp(finite)) > _RADIAN_SPREAD):
        return
    name = (f"column {header[column]!r}" if header is not None and column < len(header)
            else f"column {column + 1}")
    fix = ("read it as theta (radians, counter-clockwise from x)" if key == "theta_deg" else
           "heading_deg_north reads degrees clockwise from true north: convert the column to that, or leave "
           "it out (position-only truth)")
    warnings.warn(f"{path}: {name}, read as {key} in degrees, lies within ±{math.pi:.2f} over the whole file "
                  f"({float(finite.min()):.3g}..{float(finite.max()):.3g}): radians? {fix}", stacklevel=3)


def project_latlon(
    lat: ArrayLike,
    lon: ArrayLike,
    alt: ArrayLike | None = None,
    heading_north: ArrayLike | None = None,
    source: str = "<memory>",
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """GPS fixes onto the local east-north plane of the first fix (``pymap3d``, WGS 84).

    Each fix is turned into earth-centred coordinates and rotated into the east-north-up
    frame of the first fix (:func:`pymap3d.geodetic2enu`); east and north are kept, up is
    dropped: an orthographic projection onto the plane tangent to the ellipsoid at the
    first fix. Distances there are true at the first fix and short by 1 − cos(d/R) along
    the line to it at a distance d (:data:`GEO_SPAN_WARNING`, which warns beyond 20 km).

    Parameters
    ----------
    lat, lon : array_like, shape (K,)
        Geodetic latitude and longitude, WGS 84 [deg], east and north positive.
    alt : array_like, shape (K,), optional
        Height above the WGS 84 ellipsoid [m]; None: 0 for every fix.
    heading_north : array_like, shape (K,), optional
        Heading at each fix [deg], clockwise from true north there (a compass's or GNSS
        receiver's). It is turned into the plane exactly: the direction is rotated from the
        fix's own east-north-up frame into the first fix's (:func:`pymap3d.enu2ecefv`,
        :func:`pymap3d.ecef2enuv`), which takes in the meridians' convergence (about
        Δλ·sin φ: 0.3° at 20 km east of the first fix at 60° latitude).
    source : str
        Where the fixes came from (messages).

    Returns
    -------
    xy : ndarray, shape (K, 2)
        East and north of the first fix [m] (x east, y north; the first row is 0, 0).
    theta : ndarray, shape (K,) or None
        Heading counter-clockwise from x = east [rad], continuous (unwrapped); None
        without ``heading_north``.

    Raises
    ------
    InputError
        ``pymap3d`` is not installed (the ``gps`` extra).

    Warns
    -----
    UserWarning
        A fix farther than :data:`GEO_SPAN_WARNING` from the first, with the scale error
        there.
    """
    pm = _require_pymap3d()
    lat = np.asarray(lat, dtype=float)
    lon = np.asarray(lon, dtype=float)
    h = np.zeros_like(lat) if alt is None else np.asarray(alt, dtype=float)
    east, north, _ = pm.geodetic2enu(lat, lon, h, lat[0], lon[0], h[0])
    return _onto_plane(pm, east, north, lat[0], lon[0],
                       None if heading_north is None else (heading_north, lat, lon), source)


def project_ecef(
    x: ArrayLike,
    y: ArrayLike,
    z: ArrayLike,
    heading_north: ArrayLike | None = None,
    source: str = "<memory>",
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """GPS fixes in earth-centred, earth-fixed coordinates onto the local east-north plane of
    the first fix (``pymap3d``, WGS 84), as :func:`project_latlon` projects latitude/longitude.

    The first fix's latitude and longitude (:func:`pymap3d.ecef2geodetic`) set the
    east-north-up frame; each fix's offset from the first is rotated into it (the rotation
    of :func:`pymap3d.ecef2enu`, :func:`pymap3d.uvw2enu`, applied to the offsets themselves,
    so that the first fix is exactly 0, 0); east and north are kept, up is dropped. The same
    plane, the same scale error away from the first fix (:data:`GEO_SPAN_WARNING`) and the
    same heading as the fixes' latitude, longitude and height give.

    Parameters
    ----------
    x, y, z : array_like, shape (K,)
        ECEF coordinates, WGS 84 [m]: x towards latitude 0, longitude 0; z towards the north
        pole. Each fix's distance from the centre must be within :data:`ECEF_RADIUS_RANGE`.
    heading_north : array_like, shape (K,), optional
        Heading at each fix [deg], clockwise from true north there; turned into the first
        fix's plane as :func:`project_latlon` does.
    source : str
        Where the fixes came from (messages).

    Returns
    -------
    xy : ndarray, shape (K, 2)
        East and north of the first fix [m] (x east, y north; the first row is 0, 0).
    theta : ndarray, shape (K,) or None
        Heading counter-clockwise from x = east [rad], continuous (unwrapped); None
        without ``heading_north``.

    Raises
    ------
    InputError
        A point off the earth (``not ECEF (|r| = ... m)``), or ``pymap3d`` is not installed
        (the ``gps`` extra).

    Warns
    -----
    UserWarning
        A fix farther than :data:`GEO_SPAN_WARNING` from the first, with the scale error
        there.
    """
    x, y, z = (np.asarray(v, dtype=float).reshape(-1) for v in (x, y, z))
    off = _off_the_earth(x, y, z)
    if off is not None:
        raise InputError(f"fix {off[0]} is {off[1]}", source=source)
    pm = _require_pymap3d("ECEF coordinates")
    lat0, lon0, _ = pm.ecef2geodetic(x[0], y[0], z[0])
    east, north, _ = pm.uvw2enu(x - x[0], y - y[0], z - z[0], lat0, lon0)
    heading = None
    if heading_north is not None:
        lat, lon, _ = pm.ecef2geodetic(x, y, z)
        heading = (heading_north, np.asarray(lat, dtype=float), np.asarray(lon, dtype=float))
    return _onto_plane(pm, east, north, float(lat0), float(lon0), heading, source)


def _warn_if_not_z_up(truth: Truth, positions: NDArray[np.float64]) -> None:
    """Warn where a 3-D pose file's path lies in a plane across x or y
    (:func:`odomkit.frames.likely_up`): read z-up, its track is one ground axis against the
    height, and its heading no turn of the robot's (a Y-up file's heading read about z is 0
    or π throughout, which even follows a track squeezed onto a line)."""
    other = likely_up(positions)
    if other is None:
        return
    x, y, z = np.std(positions, axis=0)
    warnings.warn(f"{truth.source}: the positions' path lies across {other[1]} (spread x {x:.3g} m, "
                  f"y {y:.3g} m, z {z:.3g} m), and read z-up it is squeezed onto a line: "
                  f"the file's {other[1]} axis points up (a motion capture's Y-up frame, a camera's y-down "
                  "one), and read as z-up its track is one ground axis against the height; give --truth-up "
                  f"{other} (-{other[1]} for a camera's frame, x right, y down, z forward)", stacklevel=4)


def read_truth(
    path: str | Path,
    fmt: str = "auto",
    columns: str | None = None,
    time_unit: str = "s",
    sigma: float = 0.0,
    *,
    record: str | None = None,
    up: str = "+z",
) -> Truth:
    """Read a ground-truth file (formats in the module docstring).

    Parameters
    ----------
    path : the file (``.gz`` read transparently)
    fmt : {"auto", "tum", "kitti", "csv"}
    columns : ``--truth-columns`` text (csv only), see :func:`parse_truth_columns`
    time_unit : {"s", "ms", "us", "ns"} or seconds per unit, unit of the time column
        (:func:`odomkit.io.text.seconds_per_unit`)
    sigma : standard deviation of each truth position per axis [m]
    record : read only the lines whose first field is this word (``--truth-record``: a file
        of tagged records such as libRSF's ``point2 t x y ...`` beside ``angle t heading 0``,
        or CARMEN's ``TRUEPOS ...`` among other types), the tag dropped: ``columns`` then
        name the fields after it (:func:`odomkit.io.text.select_record`). None: every line,
        and a file whose lines are records of several types is refused, naming them.
    up : the axis of a TUM or KITTI file's frame that points up (``--truth-up``, one of
        :data:`odomkit.frames.UP_AXES`): its poses are read onto the plane across it
        (:func:`odomkit.frames.planar_poses`). A z-up reading of positions that hold another
        axis nearly constant (a Y-up motion capture) is warned about.

    Returns
    -------
    Truth with strictly increasing times [s] and, unless the file is position-only, a
    continuous heading [rad]. GPS fixes (latitude/longitude or ECEF columns) are east and
    north of the first fix [m] (:func:`project_latlon`, :func:`project_ecef`).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    if fmt not in TRUTH_FORMATS:
        raise InputError(f"unknown truth format {fmt!r}; expected one of {', '.join(TRUTH_FORMATS)}")
    seconds = seconds_per_unit(time_unit, "--truth-time-unit")
    if up not in UP_AXES:
        raise InputError(f"--truth-up must be one of {', '.join(UP_AXES)} (the file's axis that points up), "
                         f"got {up!r}")
    spec = parse_truth_columns(columns) if columns else None
    if spec is not None and fmt in ("tum", "kitti"):
        raise InputError(f"--truth-columns applies to csv truth, not {fmt}")
    text = read_text(path, kind="truth file")
    try:
        return _truth_of_text(path, select_record(text, str(path), record, "truth"), fmt, spec, seconds,
                              sigma, record, up, text)
    except InputError as exc:
        raise record_error(exc, text, record, "truth") from None


def _truth_of_text(path: Path, text: str, fmt: str, spec: dict[str, str] | list[str] | None, seconds: float,
                   sigma: float, record: str | None, up: str = "+z", whole: str | None = None) -> Truth:
    """The truth in ``text``, the lines of the file (``whole``) that :func:`read_truth` reads."""
    layout = sniff_layout(text, str(path))
    if record is not None:
        check_record_columns(spec, layout.ncols, record, str(path), "truth", whole=whole, selected=text,
                             delimiter=layout.delimiter)
    if isinstance(spec, list) and layout.header is not None and fmt in ("auto", "csv"):
        read = [layout.header[i] for i, key in enumerate(spec) if key != "_" and i < layout.ncols]
        if read and all(map(is_number, read)):
            # Numbers in every column read: a data row, taken for a header because a column
            # not read holds text (a date); there is no header.
            layout = sniff_layout(text, str(path), header=False)
    delimiter = layout.delimiter
    header = None if layout.header is None else list(layout.header)
    lines = [(n, s) for n, s in content_lines(text) if n > layout.header_line]
    if not lines:
        raise InputError("the file has a header but no data rows", source=str(path))
    ncols = layout.ncols
    if fmt == "auto":
        fmt = ("csv" if header is not None or spec is not None or ncols in (3, 4)
               else {8: "tum", 12: "kitti", 13: "kitti"}.get(ncols, ""))
        if not fmt:
            raise InputError(f"cannot tell the truth format from {ncols} columns; give --truth-format "
                             "tum|kitti|csv (and --truth-columns for csv)", source=str(path))
    if fmt in ("tum", "kitti") and header is not None:
        raise InputError(f"a {fmt} file has no header, but this line is not numbers",
                         source=str(path), line=layout.header_line)
    if fmt == "kitti" and ncols == 12:
        raise InputError("KITTI pose rows carry no time, and truth needs a clock: put the time first "
                         "(13 numbers: t r11 r12 r13 px r21 r22 r23 py r31 r32 r33 pz)", source=str(path))
    want = {"tum": 8, "kitti": 13}.get(fmt, ncols)
    rows = [(n, split_fields(s, delimiter)) for n, s in lines]
    index = _csv_columns(path, header, ncols, spec) if fmt == "csv" else {}
    if "t" in index and index["t"] < len(rows[0][1]):
        said = time_text_error(rows[0][1][index["t"]], rows[0][1], header, index["t"], "--truth-columns",
                               "--truth-time-unit", others=None if isinstance(spec, dict) else index)
        if said:
            raise InputError(said, source=str(path), line=rows[0][0])
    # Only the columns named are read as numbers: the others may hold text (a GPS log's date).
    data = _table(path, rows, want, sorted(set(index.values())) if fmt == "csv" else None)
    theta: NDArray[np.float64] | None
    # GPS fixes (lat, lon, alt, heading, or ECEF x, y, z, heading), whether they are ECEF, and
    # whether the heading is given.
    geo, ecef, north = None, False, False
    if up != "+z" and fmt not in ("tum", "kitti"):
        raise InputError(f"--truth-up {up} turns a 3-D pose file (TUM or KITTI); a text truth's "
                         "--truth-columns pick its ground axes (t,x,_,y reads the second and fourth "
                         "columns as x, y)", source=str(path))
    if fmt == "tum":
        t = data[:, 0]
        q = data[:, 4:8]
        norm = np.sum(q**2, axis=1)
        if np.any(norm == 0):
            row = int(np.flatnonzero(norm == 0)[0])
            raise InputError("the quaternion is zero; expected a unit quaternion qx qy qz qw",
                             source=str(path), line=lines[row][0])
        # The yaw about the up axis (for z up, the Z-Y-X yaw); scale-free, so an unnormalised
        # quaternion gives the same angle.
        positions = data[:, 1:4]
        xy, theta = planar_poses(positions, quaternion_matrices(q), up)
    elif fmt == "kitti":
        t = data[:, 0]
        rotations = data[:, [1, 2, 3, 5, 6, 7, 9, 10, 11]].reshape(-1, 3, 3)
        positions = data[:, [4, 8, 12]]
        xy, theta = planar_poses(positions, rotations, up)
    else:
        t = data[:, index["t"]]
        ecef = "ecef_x" in index
        if ecef or "lat" in index:
            _check_geo_range(path, rows, data, header, index)
            north = "heading_deg_north" in index
            # lat, lon, alt, heading (or ECEF x, y, z, heading): sorted and thinned with the times,
            # projected after (the origin is the first fix in time); xy and θ are set from them then.
            keys = (*(_ECEF if ecef else ("lat", "lon", "alt")), "heading_deg_north")
            geo = np.column_stack([data[:, index[k]] if k in index else np.zeros(len(t)) for k in keys])
            xy, theta = geo[:, :2], None
            if north:
                _warn_if_radians(path, geo[:, 3], header, index["heading_deg_north"], "heading_deg_north")
        else:
            theta = (data[:, index["theta"]] if "theta" in index
                     else np.radians(data[:, index["theta_deg"]]) if "theta_deg" in index else None)
            if "theta_deg" in index:
                _warn_if_radians(path, data[:, index["theta_deg"]], header, index["theta_deg"], "theta_deg")
            if "x_mm" in index:
                xy = data[:, [index["x_mm"], index["y_mm"]]] * units.MILLIMETRE
            else:
                xy = data[:, [index["x"], index["y"]]]
                _warn_if_ecef(path, rows, xy, header, index)
    t = to_seconds(t, seconds)
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(t) < 0):
        warnings.warn(f"{path}: truth times are not in order; rows were sorted by time", stacklevel=2)
        t, xy = t[order], xy[order]
        theta = None if theta is None else theta[order]
        geo = None if geo is None else geo[order]
    keep = np.concatenate(([True], np.diff(t) > 0))
    if not keep.all():
        warnings.warn(f"{path}: {int(np.count_nonzero(~keep))} truth rows repeat an earlier time and "
                      "were dropped (the first fix at each time is kept)", stacklevel=2)
        t, xy = t[keep], xy[keep]
        theta = None if theta is None else theta[keep]
        geo = None if geo is None else geo[keep]
    if theta is None:
        held = _held_fixes(t, geo[:, :3 if ecef else 2] if geo is not None else xy, path)
        if held is not None:
            t, xy = t[held], xy[held]
            geo = None if geo is None else geo[held]
    if not math.isfinite(sigma) or sigma < 0:
        raise InputError(f"--truth-sigma must be a non-negative number of metres, got {sigma!r}")
    if geo is not None:
        project = project_ecef if ecef else project_latlon
        xy, theta = project(geo[:, 0], geo[:, 1], geo[:, 2], geo[:, 3] if north else None, str(path))
    truth = Truth(t.copy(), np.ascontiguousarray(xy, dtype=float),
                  None if theta is None else unwrap_angle(theta), float(sigma), str(path))
    if fmt in ("tum", "kitti") and up == "+z":
        _warn_if_not_z_up(truth, positions)
    return truth
