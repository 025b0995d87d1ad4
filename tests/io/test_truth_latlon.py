"""GPS truth in latitude/longitude (text files and ROS NavSatFix topics), projected onto the
east-north plane of the first fix.

The projection is checked against the WGS 84 radii of curvature written out here (not
pymap3d's code): a small step north is the meridian arc M·Δφ, a small step east the
parallel's arc N·cos φ·Δλ (e.g. Torge & Müller, *Geodesy*, 4th ed., eq. 6.13, 6.15). A
heading is checked against the geodetic east and north unit vectors (the same reference,
eq. 6.27). A planar truth file turned into latitude/longitude by pymap3d's inverse
(``enu2geodetic``) must read back as the planar file does, and ``evaluate`` must give the
same numbers with either.
"""

from __future__ import annotations

import json
import math
import re
import sys
import warnings

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.errors import InputError
from odomkit.io.optiodom import read_run
from odomkit.io.truth import read_truth

pm = pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")

# WGS 84 (NIMA TR8350.2, table 3.1): semi-major axis [m] and flattening.
A = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)
DELTA = 0.001  # [deg]

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")
LOG_COLUMNS = ("--columns", "t=t,ticks_left=L,ticks_right=R")
ORIGIN = (-33.8688, 151.2093, 42.0)  # lat [deg], lon [deg], height [m]


def _meridian_radius(phi):
    return A * (1 - E2) / (1 - E2 * math.sin(phi) ** 2) ** 1.5


def _prime_vertical_radius(phi):
    return A / math.sqrt(1 - E2 * math.sin(phi) ** 2)


def _write(path, header, rows):
    lines = [header] + [",".join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("lat", [0.0, 30.0, 45.0, 60.0, -33.0, -80.0])
def test_small_steps_are_the_wgs84_arcs(tmp_path, lat):
    lon = 11.5
    # North: from lat − Δ/2 to lat + Δ/2, so that M at lat is the arc's mean radius (M's
    # change over the step is then second order, ~1e-11 relative).
    north = read_truth(_write(tmp_path / "n.csv", "t,lat,lon",
                              [(0, lat - DELTA / 2, lon), (1, lat + DELTA / 2, lon)]))
    arc = _meridian_radius(math.radians(lat)) * math.radians(DELTA)
    assert north.xy[1, 1] == pytest.approx(arc, rel=1e-8)
    assert abs(north.xy[1, 0]) < 1e-9 * arc
    # East along the parallel: its radius is N cos φ.
    east = read_truth(_write(tmp_path / "e.csv", "time,latitude,longitude",
                             [(0, lat, lon), (1, lat, lon + DELTA)]))
    arc = _prime_vertical_radius(math.radians(lat)) * math.cos(math.radians(lat)) * math.radians(DELTA)
    assert east.xy[1, 0] == pytest.approx(arc, rel=1e-8)
    assert north.xy[0].tolist() == east.xy[0].tolist() == [0.0, 0.0]  # origin: the first fix
    assert north.theta is None  # position-only


def _enu_basis(lat, lon):
    """Geodetic east and north unit vectors in earth-centred coordinates."""
    phi, lam = np.radians(lat), np.radians(lon)
    east = np.array([-np.sin(lam), np.cos(lam), 0.0])
    north = np.array([-np.sin(phi) * np.cos(lam), -np.sin(phi) * np.sin(lam), np.cos(phi)])
    return east, north


def test_a_north_heading_becomes_theta_in_the_first_fixs_plane(tmp_path):
    """θ = π/2 − ψ at the first fix; away from it the meridians converge (0.26° here, 16 km
    east at 60°), taken in exactly."""
    fixes = [(0, 60.0, 10.0, 30.0), (1, 60.0, 10.3, 0.0), (2, 60.05, 10.3, 250.0)]
    truth = read_truth(_write(tmp_path / "h.csv", "t,lat,lon,heading_deg_north", fixes))
    e0, n0 = _enu_basis(60.0, 10.0)
    for (_, lat, lon, psi), theta in zip(fixes, truth.theta, strict=True):
        e, n = _enu_basis(lat, lon)
        d = np.sin(np.radians(psi)) * e + np.cos(np.radians(psi)) * n
        want = math.atan2(d @ n0, d @ e0)
        assert math.remainder(theta - want, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    assert truth.theta[0] == pytest.approx(math.pi / 2 - math.radians(30.0), abs=1e-14)
    convergence = math.remainder(truth.theta[1] - math.pi / 2, 2 * math.pi)
    assert convergence == pytest.approx(math.radians(0.3) * math.sin(math.radians(60.0)), rel=1e-3)


def _path(n=600, radius=600.0):
    """A drive of about 3.5 km around a loop 1.2 km across, from (0, 0)."""
    t = np.arange(n) * 1.0
    a = t / t[-1] * 2 * np.pi
    x = radius * np.sin(a) + 150 * np.sin(3 * a)
    y = radius * (1 - np.cos(a)) + 80 * np.sin(2 * a)
    return t, x, y


def _latlon(x, y, origin=ORIGIN):
    lat, lon, h = pm.enu2geodetic(x, y, np.zeros_like(x), *origin)
    return lat, lon, h


def test_a_planar_file_turned_into_latlon_reads_back(tmp_path):
    t, x, y = _path()
    planar = read_truth(_write(tmp_path / "xy.csv", "t,x,y", np.column_stack((t, x, y))))
    lat, lon, h = _latlon(x, y)
    # With the heights enu2geodetic gives (the plane rises above the ellipsoid away from
    # its origin) the round trip is exact; without them, 0 for every fix, within 1 mm where
    # the origin is on the ellipsoid (42 m above it, every distance would be short by
    # 42 m / R = 6.6e-6: 8 mm across this loop).
    with_h = read_truth(_write(tmp_path / "g.csv", "t,lat,lon,alt", np.column_stack((t, lat, lon, h))))
    np.testing.assert_allclose(with_h.xy, planar.xy, rtol=0, atol=1e-6)
    lat, lon, _ = _latlon(x, y, (*ORIGIN[:2], 0.0))
    semicolons = tmp_path / "g2.csv"
    semicolons.write_text(_write(semicolons, "stamp,longitude,latitude",
                                 np.column_stack((t, lon, lat))).read_text().replace(",", ";"))
    np.testing.assert_allclose(read_truth(semicolons).xy, planar.xy, rtol=0, atol=1e-3)
    mapped = read_truth(_write(tmp_path / "g3.csv", "when,B,A", np.column_stack((t, lat, lon))),
                        columns="t=when,lat=B,lon=A")
    np.testing.assert_allclose(mapped.xy, planar.xy, rtol=0, atol=1e-3)
    ordered = _write(tmp_path / "g4.csv", "# no header", np.column_stack((lon, t, lat)))
    np.testing.assert_allclose(read_truth(ordered, columns="lon,t,lat").xy, planar.xy, rtol=0, atol=1e-3)


@pytest.fixture(scope="module")
def optiodom(tmp_path_factory):
    """OptiOdom run 01 as a CSV log, and its OptiTrack positions as truth on their own clock
    (every other row, 10 ms late): planar t,x,y and the same fixes in latitude/longitude."""
    d = tmp_path_factory.mktemp("latlon")
    log = read_run(RUN)
    rows = np.column_stack((log.t, log.channels["ticks_left"], log.channels["ticks_right"]))
    np.savetxt(d / "log.csv", rows, delimiter=",", header="t,L,R", comments="", fmt="%.17g")
    t = log.t[::2] + 0.01
    xy = log.ground_truth[::2, :2] - log.ground_truth[0, :2]  # the projection's origin: the first fix
    _write(d / "planar.csv", "t,x,y", np.column_stack((t, xy)))
    lat, lon, h = _latlon(xy[:, 0], xy[:, 1])
    _write(d / "latlon.csv", "t,lat,lon,alt", np.column_stack((t, lat, lon, h)))
    return d, t, lat, lon, h


def _close(a, b, rel):
    if isinstance(a, dict):
        assert set(a) == set(b)
        for key in a:
            _close(a[key], b[key], rel)
    elif isinstance(a, list):
        assert len(a) == len(b)
        for u, v in zip(a, b, strict=True):
            _close(u, v, rel)
    elif isinstance(a, float) and math.isfinite(a):
        assert b == pytest.approx(a, rel=rel, abs=1e-12)
    else:
        assert a == b


def _evaluate(run_cli, log, *truth):
    code, out, err = run_cli("evaluate", log, "--robot", ROBOT, *LOG_COLUMNS, *truth, "--window", "10s",
                             "--json")
    assert code == 0, err
    result = json.loads(out)
    return result, [w for w in result.pop("warnings", []) if "sigma" not in w]


def test_evaluate_with_latlon_truth_equals_the_planar_truth(run_cli, optiodom):
    d, *_ = optiodom
    # The fixes read back within 1e-8 m (float64 in earth-centred coordinates, ~6.4e6 m,
    # holds ~1e-9 m) ...
    np.testing.assert_allclose(read_truth(d / "latlon.csv").xy, read_truth(d / "planar.csv").xy,
                               rtol=0, atol=1e-8)
    planar, planar_warnings = _evaluate(run_cli, d / "log.csv", "--truth", d / "planar.csv")
    geo, geo_warnings = _evaluate(run_cli, d / "log.csv", "--truth", d / "latlon.csv")
    # ... and the scores agree to 3e-5 relative: the whole run's start heading, and a window's
    # that starts at a fix as the robot starts off, are fitted to fixes a few millimetres
    # apart, which turns those 1e-9 m into ~1e-6 rad (measured: ATE RMSE 2.6e-6 relative; the
    # window ends' NEES 1.2e-5 at most, since windows against this truth, sparser than the
    # log, start at its fixes).
    _close(json.loads(json.dumps(planar).replace("planar.csv", "X")),
           json.loads(json.dumps(geo).replace("latlon.csv", "X")), rel=3e-5)
    assert [w.replace("planar.csv", "X") for w in planar_warnings] == \
        [w.replace("latlon.csv", "X") for w in geo_warnings]


def _one_line(run_cli, *args):
    code, out, err = run_cli(*args)
    assert code == 2 and out == "", err
    assert err.startswith("odomkit: error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


@pytest.mark.parametrize(("lines", "match"), [
    (["t,lat,lon", "0,60,10", "1,95,10"], r"bad.csv, line 3: column 2 \(lat\) is 95; a latitude is degrees "
                                          r"within ±90$"),
    (["t,lat,lon", "0,60,10", "1,60,-180.5"], r"bad.csv, line 3: column 3 \(lon\) is -180.5; a longitude "
                                              r"is degrees within ±180$"),
    (["t,lat,lon", "0,60,10", "1,nan,10"], r"bad.csv, line 3: column 2 is nan; truth needs finite numbers"),
    (["t,lat,lon", "0,60,10", "1,60,inf"], r"bad.csv, line 3: column 3 is inf; truth needs finite numbers"),
    (["t,x,y,lat,lon", "0,0,0,60,10"], r"bad.csv: the file has both x, y and latitude/longitude columns: "
                                       r"x \('x'\), y \('y'\), lat \('lat'\), lon \('lon'\)"),
    (["t,lat,x", "0,60,10"], r"bad.csv: the file has both x, y and latitude/longitude columns"),
    (["t,lat,lon,heading", "0,60,10,0"], r"bad.csv: a latitude/longitude file's heading must say its "
                                         r"convention, and 'heading' does not: .*heading_deg_north=heading"),
    (["t,lat,lon2", "0,60,10"], r"bad.csv: no column for lon"),
    (["t,x,y,heading_deg_north", "0,0,0,0"], r"bad.csv: heading_deg_north goes with latitude/longitude"),
])
def test_bad_gps_files_are_one_line_exit_2(run_cli, optiodom, lines, match):
    d, *_ = optiodom
    bad = d / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    err = _one_line(run_cli, "track", d / "log.csv", "--robot", ROBOT, *LOG_COLUMNS, "--truth", bad)
    assert re.search(match, err.strip()), err


def test_a_height_beside_x_y_is_still_ignored(tmp_path):
    truth = read_truth(_write(tmp_path / "a.csv", "t,x,y,height", [(0, 0, 0, 5), (1, 1, 2, 6)]))
    assert truth.xy.tolist() == [[0, 0], [1, 2]]


def test_without_pymap3d_reading_latlon_says_how_to_install_it(run_cli, optiodom, monkeypatch):
    d, *_ = optiodom
    monkeypatch.setitem(sys.modules, "pymap3d", None)  # `import pymap3d` raises ImportError
    err = _one_line(run_cli, "evaluate", d / "log.csv", "--robot", ROBOT, *LOG_COLUMNS,
                    "--truth", d / "latlon.csv")
    assert err == ("odomkit: error: reading latitude/longitude needs pymap3d: "
                   "pip install 'odomkit[gps]'\n")
    with pytest.raises(InputError, match="pymap3d"):
        read_truth(d / "latlon.csv")
    read_truth(d / "planar.csv")  # x, y truth does not need it


def test_fixes_far_from_the_first_warn_with_the_scale_error(tmp_path):
    # 0.27° of latitude at 45°: about 30 km north of the first fix.
    with pytest.warns(UserWarning, match=r"reach (\d+\.\d) km from the first") as caught:
        truth = read_truth(_write(tmp_path / "far.csv", "t,lat,lon", [(0, 45.0, 7.0), (1, 45.27, 7.0)]))
    reach = float(truth.xy[1, 1])
    text = str(caught[0].message)
    stated = float(text.split("short by up to ")[1].split()[0])
    assert stated == pytest.approx(reach**2 / 2 / 6_371_000.0**2, rel=0.05)  # 1 − cos(d/R) ≈ (d/R)²/2
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # 19 km: no warning
        read_truth(_write(tmp_path / "near.csv", "t,lat,lon", [(0, 45.0, 7.0), (1, 45.17, 7.0)]))


def test_a_heading_in_radians_read_as_degrees_is_warned_about(tmp_path):
    """KITTI's yaw is radians counter-clockwise from east; a user study read it as
    heading_deg_north, as a refusal's hint suggested for "degrees clockwise from north", and
    was told the yaw rate's sign was flipped. A heading column read in degrees that spreads
    over more than 2 yet stays within ±π is radians: said, with what to do (a GPS file takes
    no radians: convert it or leave it out; a planar file: theta). Degrees that turn are not."""
    t = np.arange(200) * 0.1
    yaw = np.angle(np.exp(1j * 0.3 * t))  # radians, turning through ±π
    lat, lon = 49.0 + 1e-5 * t, 8.4 + 1e-5 * t
    gps = _write(tmp_path / "g.csv", "t,lat,lon,heading_deg_north", np.column_stack([t, lat, lon, yaw]))
    with pytest.warns(UserWarning, match=r"read as heading_deg_north in degrees, lies within ±3\.14 .* "
                                         r"radians\? .* convert the column to that, or leave it out"):
        read_truth(gps)
    planar = _write(tmp_path / "p.csv", "t,x,y,theta_deg", np.column_stack([t, t, 0 * t, yaw]))
    with pytest.warns(UserWarning, match=r"read as theta_deg in degrees, .* read it as theta \(radians"):
        read_truth(planar)
    turning = _write(tmp_path / "d.csv", "t,x,y,theta_deg", np.column_stack([t, t, 0 * t, np.degrees(yaw)]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_truth(turning)
