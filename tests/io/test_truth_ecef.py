"""GPS truth in earth-centred, earth-fixed coordinates (ECEF, WGS 84: ``ecef_x, ecef_y, ecef_z``),
projected onto the east-north plane of the first fix as latitude/longitude fixes are.

The ECEF coordinates are computed here with the closed-form WGS 84 formulas (NIMA TR8350.2,
eq. 4-14, 4-15; not pymap3d's code): N = a/√(1−e² sin²φ), X = (N+h) cos φ cos λ,
Y = (N+h) cos φ sin λ, Z = (N(1−e²)+h) sin φ. A file of such coordinates must read as the
latitude/longitude file of the same fixes does (itself checked against WGS 84's radii in
``test_truth_latlon.py``), and a fix 100 m along the geodetic east or north unit vector of
the first fix must land 100 m east or north of it. ECEF coordinates read as plain x, y (the
ECEF X–Y plane: the equator's, not the local horizontal) are warned about; UTM eastings and
northings with a height are not ECEF and get no warning.
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
from odomkit.io.truth import project_ecef, read_truth

pm = pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")

# WGS 84 (NIMA TR8350.2, table 3.1): semi-major axis [m] and flattening.
A = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")
LOG_COLUMNS = ("--columns", "t=t,ticks_left=L,ticks_right=R")
ORIGIN = (52.5046, 13.3737, 76.0)  # lat [deg], lon [deg], height [m]: Berlin


def _ecef(lat, lon, h):
    """Geodetic latitude, longitude [deg] and height [m] -> ECEF X, Y, Z [m] (closed form)."""
    phi, lam = np.radians(lat), np.radians(lon)
    n = A / np.sqrt(1 - E2 * np.sin(phi) ** 2)
    return ((n + h) * np.cos(phi) * np.cos(lam), (n + h) * np.cos(phi) * np.sin(lam),
            (n * (1 - E2) + h) * np.sin(phi))


def _enu_basis(lat, lon):
    """Geodetic east, north and up unit vectors in ECEF."""
    phi, lam = math.radians(lat), math.radians(lon)
    return (np.array([-math.sin(lam), math.cos(lam), 0.0]),
            np.array([-math.sin(phi) * math.cos(lam), -math.sin(phi) * math.sin(lam), math.cos(phi)]),
            np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam), math.sin(phi)]))


def _point3(t, x, y, z):
    """A smartLoc ground-truth row's start: ``point3 t X Y Z 0 0 0`` (the rest is its covariance)."""
    return f"point3 {float(t)!r} {float(x)!r} {float(y)!r} {float(z)!r} 0 0 0"


def _write(path, header, rows):
    lines = ([header] if header else []) + [",".join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _fixes(n=300):
    """A drive of a few km around ORIGIN, with heights changing by 40 m and a heading."""
    t = np.arange(n) * 0.5
    a = t / t[-1] * 2 * np.pi
    lat = ORIGIN[0] + 0.012 * np.sin(a) + 0.002 * np.sin(3 * a)
    lon = ORIGIN[1] + 0.02 * (1 - np.cos(a))
    h = ORIGIN[2] + 40 * np.sin(2 * a)
    heading = np.degrees(a) % 360.0
    return t, lat, lon, h, heading


def test_ecef_reads_as_the_same_fixes_in_latitude_longitude(tmp_path):
    t, lat, lon, h, heading = _fixes()
    x, y, z = _ecef(lat, lon, h)
    geo = read_truth(_write(tmp_path / "g.csv", "t,lat,lon,alt", np.column_stack((t, lat, lon, h))))
    ecef = read_truth(_write(tmp_path / "e.csv", "t,ecef_x,ecef_y,ecef_z", np.column_stack((t, x, y, z))))
    assert ecef.xy[0].tolist() == [0.0, 0.0]  # the origin: the first fix
    assert ecef.theta is None  # position-only
    assert np.max(np.hypot(*geo.xy.T)) > 2000  # a drive of km: a wrong plane would show
    # Measured 7e-10 m: float64 at 6.4e6 m holds 1e-9 m.
    np.testing.assert_allclose(ecef.xy, geo.xy, rtol=0, atol=1e-6)
    # Other header spellings, any case; a map of header names; columns in order.
    named = read_truth(_write(tmp_path / "e2.csv", "time,X_ECEF,Y_ECEF,Z_ECEF",
                              np.column_stack((t, x, y, z))))
    np.testing.assert_allclose(named.xy, geo.xy, rtol=0, atol=1e-3)
    mapped = read_truth(_write(tmp_path / "e3.csv", "when,Z,X,Y", np.column_stack((t, z, x, y))),
                        columns="t=when,ecef_x=X,ecef_y=Y,ecef_z=Z")
    np.testing.assert_allclose(mapped.xy, geo.xy, rtol=0, atol=1e-3)
    ordered = read_truth(_write(tmp_path / "e4.csv", "", np.column_stack((z, t, x, y))),
                         columns="ecef_z,t,ecef_x,ecef_y")
    np.testing.assert_allclose(ordered.xy, geo.xy, rtol=0, atol=1e-3)
    # The Python API gives the same plane.
    xy, theta = project_ecef(x, y, z)
    np.testing.assert_allclose(xy, geo.xy, rtol=0, atol=1e-3)
    assert theta is None
    # With a heading clockwise from north: the same θ as the latitude/longitude file's.
    geo_h = read_truth(_write(tmp_path / "gh.csv", "t,lat,lon,alt,heading_deg_north",
                              np.column_stack((t, lat, lon, h, heading))))
    ecef_h = read_truth(_write(tmp_path / "eh.csv", "t,ecef_x,ecef_y,ecef_z,heading_deg_north",
                               np.column_stack((t, x, y, z, heading))))
    np.testing.assert_allclose(ecef_h.theta, geo_h.theta, rtol=0, atol=1e-9)


def test_a_smartloc_style_file_reads_by_its_columns(tmp_path):
    """``point3 t X Y Z 0 ... 0`` rows (the smartLoc data set's ground truth), no header,
    trailing blanks; rows out of time order: the origin is the first fix in time."""
    t, lat, lon, h, _ = _fixes(60)
    x, y, z = _ecef(lat, lon, h)
    geo = read_truth(_write(tmp_path / "g.csv", "t,lat,lon,alt", np.column_stack((t, lat, lon, h))))
    rows = [_point3(t[k], x[k], y[k], z[k]) + " 0 0 0 0 0 0      " for k in range(len(t))]
    path = tmp_path / "gt.txt"
    path.write_text("\n".join(rows[3:] + rows[:3]) + "\n")
    with pytest.warns(UserWarning, match="not in order"):
        truth = read_truth(path, columns="_,t,ecef_x,ecef_y,ecef_z")
    np.testing.assert_allclose(truth.t, t, rtol=0, atol=0)
    np.testing.assert_allclose(truth.xy, geo.xy, rtol=0, atol=1e-3)


@pytest.mark.parametrize("origin", [ORIGIN, (0.0, 0.0, 0.0), (-33.87, 151.21, 42.0), (40.0, -105.0, 1600.0),
                                    (-89.5, -170.0, 2800.0)])
def test_a_fix_100_m_east_or_north_lands_there(tmp_path, origin):
    east, north, up = _enu_basis(origin[0], origin[1])
    p0 = np.array(_ecef(*origin))
    # The first fix, 100 m east, 100 m north, 100 m up (dropped), 100 m east and 50 m north.
    fixes = [p0, p0 + 100 * east, p0 + 100 * north, p0 + 100 * up, p0 + 100 * east + 50 * north]
    truth = read_truth(_write(tmp_path / "e.csv", "t,ecef_x,ecef_y,ecef_z",
                              [(k, *p) for k, p in enumerate(fixes)]))
    np.testing.assert_allclose(truth.xy, [[0, 0], [100, 0], [0, 100], [0, 0], [100, 50]], rtol=0, atol=1e-6)


def test_fixes_far_from_the_first_warn_with_the_scale_error(tmp_path):
    x, y, z = _ecef(np.array([45.0, 45.27]), np.array([7.0, 7.0]), np.zeros(2))
    with pytest.warns(UserWarning, match=r"reach 30\.\d km from the first"):
        read_truth(_write(tmp_path / "far.csv", "t,ecef_x,ecef_y,ecef_z", np.column_stack(([0, 1], x, y, z))))


@pytest.fixture(scope="module")
def optiodom(tmp_path_factory):
    """OptiOdom run 01 as a CSV log, and its OptiTrack positions as truth on their own clock,
    as latitude/longitude and as ECEF."""
    d = tmp_path_factory.mktemp("ecef")
    log = read_run(RUN)
    rows = np.column_stack((log.t, log.channels["ticks_left"], log.channels["ticks_right"]))
    np.savetxt(d / "log.csv", rows, delimiter=",", header="t,L,R", comments="", fmt="%.17g")
    t = log.t[::2] + 0.01
    xy = log.ground_truth[::2, :2] - log.ground_truth[0, :2]
    lat, lon, h = pm.enu2geodetic(xy[:, 0], xy[:, 1], np.zeros(len(t)), *ORIGIN)
    _write(d / "latlon.csv", "t,lat,lon,alt", np.column_stack((t, lat, lon, h)))
    _write(d / "ecef.csv", "t,ecef_x,ecef_y,ecef_z", np.column_stack((t, *_ecef(lat, lon, h))))
    return d


def _json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out)


def test_track_with_ecef_truth_is_track_with_latlon_truth(run_cli, optiodom):
    d = optiodom
    common = ("track", d / "log.csv", "--robot", ROBOT, *LOG_COLUMNS)
    geo = _json(run_cli, *common, "--truth", d / "latlon.csv")
    ecef = _json(run_cli, *common, "--truth", d / "ecef.csv")
    assert abs(ecef["pose"][0]) < 5  # metres of the room, not 3.8e6 m of the earth's X
    assert ecef["final_position_error"] == pytest.approx(geo["final_position_error"], rel=1e-4, abs=1e-6)
    np.testing.assert_allclose(ecef["pose"], geo["pose"], rtol=0, atol=1e-5)
    assert ecef["warnings"] == [w.replace("latlon.csv", "ecef.csv") for w in geo["warnings"]]


def _one_line(run_cli, *args):
    code, out, err = run_cli(*args)
    assert code == 2 and out == "", err
    assert err.startswith("odomkit: error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


ROW = "3785108.1,899901.5,5037234.5"  # a fix in Berlin


@pytest.mark.parametrize(("lines", "columns", "match"), [
    (["t,ecef_x,ecef_y,ecef_z", f"0,{ROW}", "1,1.5,2,3"], None,
     r"bad.csv, line 3: columns 2, 3, 4 \(ecef_x, ecef_y, ecef_z\) are not ECEF \(\|r\| = 3\.905 m; "),
    (["t,ecef_x,ecef_y,ecef_z", "0,3785108.1,899901.5,50372345"], None,
     r"line 2: .* not ECEF \(\|r\| = 5\.05\de\+07 m"),
    (["t,x,y,ecef_x,ecef_y,ecef_z", f"0,0,0,{ROW}"], None,
     r"bad.csv: the file has both x, y and ECEF columns: x \('x'\), y \('y'\), ecef_x \('ecef_x'\)"),
    (["t,lat,lon,ecef_x,ecef_y,ecef_z", f"0,52,13,{ROW}"], None,
     r"bad.csv: the file has both latitude/longitude and ECEF columns: lat \('lat'\), lon \('lon'\), ecef_x"),
    ([f"0,{ROW},40"], "t,ecef_x,ecef_y,ecef_z,alt",
     r"bad.csv: the file has both latitude/longitude and ECEF columns: alt \(column 5\)"),
    (["t,ecef_x,ecef_y", "0,3785108.1,899901.5"], None, r"bad.csv: no column for ecef_z"),
    (["t,ecef_x,ecef_y,ecef_z,yaw", f"0,{ROW},0"], None,
     r"bad.csv: an ECEF file's heading must say its convention, and 'yaw' does not: .*heading_deg_north=yaw"),
])
def test_bad_ecef_files_are_one_line_exit_2(run_cli, optiodom, lines, columns, match):
    bad = optiodom / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    extra = ("--truth-columns", columns) if columns else ()
    err = _one_line(run_cli, "track", optiodom / "log.csv", "--robot", ROBOT, *LOG_COLUMNS, "--truth", bad,
                    *extra)
    assert re.search(match, err.strip()), err


def test_project_ecef_refuses_points_off_the_earth():
    with pytest.raises(InputError, match=r"not ECEF \(\|r\| = 1\.732 m"):
        project_ecef([1.0], [1.0], [1.0])


def test_without_pymap3d_reading_ecef_says_how_to_install_it(run_cli, optiodom, monkeypatch):
    monkeypatch.setitem(sys.modules, "pymap3d", None)  # `import pymap3d` raises ImportError
    err = _one_line(run_cli, "track", optiodom / "log.csv", "--robot", ROBOT, *LOG_COLUMNS,
                    "--truth", optiodom / "ecef.csv")
    assert err == "odomkit: error: reading ECEF coordinates needs pymap3d: pip install 'odomkit[gps]'\n"


# ECEF read as plain x, y: the user study's smartLoc file read with --truth-columns _,t,x,y.
def _smartloc(path, n=40):
    t, lat, lon, h, _ = _fixes(n)
    x, y, z = _ecef(lat, lon, h)
    path.write_text("".join(_point3(t[k], x[k], y[k], z[k]) + "\n" for k in range(n)))
    return path


def test_ecef_read_as_x_y_is_warned_about(tmp_path):
    path = _smartloc(tmp_path / "gt.txt")
    with pytest.warns(UserWarning) as caught:
        read_truth(path, columns="_,t,x,y")
    text = [str(w.message) for w in caught if "ECEF" in str(w.message)]
    assert len(text) == 1, [str(w.message) for w in caught]
    assert re.fullmatch(r".*gt.txt: columns x \(column 3\), y \(column 4\) and column 5 look like "
                        r"earth-centred \(ECEF\) coordinates \(\|r\| ≈ 6\.3\de6 m\): read them with "
                        r"ecef_x,ecef_y,ecef_z "
                        r"\(--truth-columns _,t,ecef_x,ecef_y,ecef_z\).*", text[0]), text[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the hint reads them, without a warning
        read_truth(path, columns="_,t,ecef_x,ecef_y,ecef_z")
    # With a header: the hint maps its names.
    t, lat, lon, h, _ = _fixes(40)
    x, y, z = _ecef(lat, lon, h)
    headed = _write(tmp_path / "h.csv", "time,X,Y,Z", np.column_stack((t, x, y, z)))
    with pytest.warns(UserWarning, match=r"--truth-columns t=time,ecef_x=X,ecef_y=Y,ecef_z=Z\)"):
        read_truth(headed)


def test_ecef_read_as_x_y_is_warned_about_in_the_json(run_cli, optiodom, tmp_path):
    path = _smartloc(tmp_path / "gt.txt", 400)
    result = _json(run_cli, "track", optiodom / "log.csv", "--robot", ROBOT, *LOG_COLUMNS, "--truth", path,
                   "--truth-columns", "_,t,x,y", "--initial-pose", "0,0,0")
    said = result["warnings"]
    assert any("look like earth-centred (ECEF) coordinates" in w for w in said), said


@pytest.mark.parametrize(("x", "y", "z"), [
    (5.0e5, 5.0e6, 300.0),  # UTM easting, northing (45° N) and a height
    (5.5e5, 6.335e6, 50.0),  # UTM near Aberdeen (57° N): x² + y² + z² within 1 % of R², but no ECEF point
    (5.5e5, 6.335e6, 0.5),  # ... with a heading [rad] beside them
])
def test_utm_with_a_height_is_not_ecef(tmp_path, x, y, z):
    rows = [(k, x + 3.0 * k, y + 4.0 * k, z + 0.1 * k) for k in range(20)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        truth = read_truth(_write(tmp_path / "utm.csv", "t,x,y,z", rows))
        read_truth(_write(tmp_path / "utm2.csv", "", rows), columns="t,x,y")
    assert truth.xy[1].tolist() == [x + 3.0, y + 4.0]
