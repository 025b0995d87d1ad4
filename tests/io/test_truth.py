"""Truth-file readers: TUM, KITTI rows with time, text tables; gzip, comments, units, bad input."""

from __future__ import annotations

import gzip
import warnings

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.truth import parse_truth_columns, read_truth

T = np.array([0.0, 0.1, 0.2, 0.3])
X = np.array([0.0, 0.5, 1.0, 1.2])
Y = np.array([0.0, 0.1, 0.4, 0.9])
TH = np.array([0.1, 3.0, -3.0, -2.5])  # crosses ±π: must come out continuous
TH_CONT = np.array([0.1, 3.0, 2 * np.pi - 3.0, 2 * np.pi - 2.5])


def _write(path, lines, gz=False):
    text = "\n".join(lines) + "\n"
    if gz:
        with gzip.open(path, "wt") as fh:
            fh.write(text)
    else:
        path.write_text(text)
    return path


def _tum_lines(theta=TH, scale=1.0):
    # q = (0, 0, sin θ/2, cos θ/2) times an arbitrary scale (the yaw must not depend on it),
    # plus a z that must be ignored.
    return ["# timestamp tx ty tz qx qy qz qw"] + [
        f"{float(t)!r} {float(x)!r} {float(y)!r} 0.7 0 0 "
        f"{float(scale * np.sin(h / 2))!r} {float(scale * np.cos(h / 2))!r}"
        for t, x, y, h in zip(T, X, Y, theta, strict=True)]


def _check(truth, heading=True):
    np.testing.assert_allclose(truth.t, T, atol=1e-15)
    np.testing.assert_allclose(truth.xy, np.column_stack((X, Y)), atol=1e-15)
    if heading:
        np.testing.assert_allclose(truth.theta, TH_CONT, atol=1e-12)
    else:
        assert truth.theta is None


@pytest.mark.parametrize("gz", [False, True])
def test_tum_yaw_from_quaternion(tmp_path, gz):
    path = _write(tmp_path / ("gt.tum.gz" if gz else "gt.tum"), _tum_lines(scale=2.0), gz)
    _check(read_truth(path))
    _check(read_truth(path, "tum"))


def test_tum_yaw_ignores_roll(tmp_path):
    # A rotation about z by 0.4 after a roll of 0.3 about x: its ZYX yaw is still 0.4.
    yaw, roll = 0.4, 0.3
    qz = (0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2))
    qx = (np.sin(roll / 2), 0.0, 0.0, np.cos(roll / 2))

    def mul(a, b):  # Hamilton product, (x, y, z, w)
        ax, ay, az, aw = a
        bx, by, bz, bw = b
        return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)

    q = " ".join(repr(float(v)) for v in mul(qz, qx))
    path = _write(tmp_path / "q.tum", [f"0 0 0 0 {q}", f"1 1 0 0 {q}"])
    assert read_truth(path).theta[0] == pytest.approx(yaw, abs=1e-12)


def test_kitti_rows_with_time(tmp_path):
    lines = []
    for t, x, y, h in zip(T, X, Y, TH, strict=True):
        c, s = np.cos(h), np.sin(h)
        row = [c, -s, 0, x, s, c, 0, y, 0, 0, 1, 0.0]
        lines.append(" ".join(repr(float(v)) for v in [t, *row]))
    path = _write(tmp_path / "poses.txt", lines)
    _check(read_truth(path))
    _check(read_truth(path, "kitti"))


def test_kitti_rows_without_time_are_refused(tmp_path):
    path = _write(tmp_path / "poses.txt", ["1 0 0 0 0 1 0 0 0 0 1 0"] * 3)
    with pytest.raises(InputError, match="carry no time"):
        read_truth(path)


@pytest.mark.parametrize("sep", [",", ";", "\t", " "])
def test_text_with_header_any_separator(tmp_path, sep):
    lines = [sep.join(["time", "gt_x", "gt_y", "yaw"])]
    lines += [sep.join(repr(float(v)) for v in row) for row in zip(T, X, Y, TH, strict=True)]
    _check(read_truth(_write(tmp_path / "gt.csv", lines)))


def test_headerless_text_three_and_four_columns(tmp_path):
    rows4 = [",".join(repr(float(v)) for v in row) for row in zip(T, X, Y, TH, strict=True)]
    _check(read_truth(_write(tmp_path / "a.csv", ["# t,x,y,theta", "", *rows4])))
    rows3 = [",".join(repr(float(v)) for v in row) for row in zip(T, X, Y, strict=True)]
    _check(read_truth(_write(tmp_path / "b.csv", rows3)), heading=False)


def test_truth_columns_in_order_with_skips_and_degrees(tmp_path):
    rows = [" ".join(repr(float(v)) for v in (9.0, y, t, x, np.degrees(h)))
            for t, x, y, h in zip(T, X, Y, TH, strict=True)]
    path = _write(tmp_path / "odd.txt", rows)
    _check(read_truth(path, "csv", columns="_,y,t,x,theta_deg"))
    _check(read_truth(path, columns="_,y,t,x"), heading=False)


def test_truth_columns_as_a_header_map(tmp_path):
    lines = ["stamp,px,py,heading_rad,quality"]
    lines += [",".join(repr(float(v)) for v in (t, x, y, h, 1))
              for t, x, y, h in zip(T, X, Y, TH, strict=True)]
    path = _write(tmp_path / "gt.csv", lines)
    _check(read_truth(path, columns="t=stamp,x=px,y=py,theta=heading_rad"))
    _check(read_truth(path, columns="t=stamp,x=px,y=py"), heading=False)
    with pytest.raises(InputError, match="no column named 'nope'"):
        read_truth(path, columns="t=nope,x=px,y=py")


@pytest.mark.parametrize(("unit", "scale"), [("ms", 1e3), ("us", 1e6), ("ns", 1e9)])
def test_time_units(tmp_path, unit, scale):
    rows = [f"{int(round(t * scale))},{float(x)!r},{float(y)!r}" for t, x, y in zip(T, X, Y, strict=True)]
    truth = read_truth(_write(tmp_path / "gt.csv", rows), time_unit=unit)
    np.testing.assert_allclose(truth.t, T, atol=1e-12)


def test_unsorted_rows_are_sorted_and_repeats_dropped_with_warnings(tmp_path):
    rows = ["0.2,1.0,0.4", "0.0,0.0,0.0", "0.1,0.5,0.1", "0.1,9,9", "0.3,1.2,0.9"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        truth = read_truth(_write(tmp_path / "gt.csv", rows))
    messages = " ".join(str(w.message) for w in caught)
    assert "sorted by time" in messages and "1 truth rows repeat" in messages
    _check(truth, heading=False)


def test_sigma_is_carried(tmp_path):
    rows = [f"{float(t)!r},{float(x)!r},{float(y)!r}" for t, x, y in zip(T, X, Y, strict=True)]
    assert read_truth(_write(tmp_path / "gt.csv", rows), sigma=0.002).sigma == 0.002


@pytest.mark.parametrize(("lines", "kwargs", "match"), [
    (["0,0,0", "0.1,nan,0", "0.2,1,1"], {}, r"line 2: column 2 is nan"),
    (["0,0,0", "0.1,abc,0"], {}, r"line 2: column 2: 'abc' is not a number"),
    (["0,0,0", "0.1,0"], {}, r"line 2: expected 3 columns, found 2"),
    (["# only a comment"], {}, "empty"),
    (["1,2,3,4,5"], {}, "cannot tell the truth format"),
    (["0,0,0"], {"fmt": "xyz"}, "unknown truth format"),
    (["0,0,0"], {"time_unit": "min"}, "--truth-time-unit must be one of s, ms"),
    (["0 0 0 0 0 0 0 0"], {}, "quaternion is zero"),
    (["a,b,c", "0,0,0"], {}, r"no column for t, x, y"),
    (["0,0,0"], {"columns": "t=a,x=b,y=c"}, "no header"),
    (["0,0,0"], {"columns": "t,x,q"}, "name each column once"),
    (["0,0,0"], {"fmt": "tum", "columns": "t,x,y"}, "applies to csv truth"),
])
def test_bad_truth_files_name_the_problem(tmp_path, lines, kwargs, match):
    path = _write(tmp_path / "bad.txt", lines)
    with pytest.raises(InputError, match=match):
        read_truth(path, **kwargs)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_truth(tmp_path / "nope.csv")


def test_parse_truth_columns():
    assert parse_truth_columns("t, x ,y") == ["t", "x", "y"]
    assert parse_truth_columns("x=b,t=a,y=c") == {"x": "b", "t": "a", "y": "c"}
    with pytest.raises(InputError):
        parse_truth_columns("t,x,x")


def test_fixes_a_logger_held_at_its_own_rows_are_thinned_to_when_each_arrived(tmp_path):
    """A 5 Hz GPS written at each row of a 10 Hz log repeats every fix once (a real car's CAN
    logger did, 1,245 of 4,708 rows). Read as they are, the repeats are positions stamped
    0.1 s late. Each fix is kept at its first row; a repeat longer than 1 s (the car
    standing) keeps its last row too, so that the truth stands still over it; positions
    are untouched. A 1 Hz GPS whose car stands once (few repeats) is read as it is."""
    t = np.round(np.arange(0.0, 30.0, 0.1), 3)
    arrived = np.floor(t * 5) / 5  # the fix of the last 0.2 s update
    x = np.where(arrived < 10, 10.0 * arrived, np.where(arrived < 15, 100.0, 100.0 + 10.0 * (arrived - 15)))
    rows = np.column_stack((t, x, 0.5 * x))
    path = tmp_path / "held.csv"
    np.savetxt(path, rows, delimiter=",", header="t,x,y", comments="", fmt="%.4f")
    with pytest.warns(UserWarning, match=r"of 300 fixes repeat the one before"):
        truth = read_truth(path)
    # Each 0.2 s update at its first row; the stand at x = 100 holds from the update at 10.0 s
    # to the row before the update at 15.2 s (the one at 15.0 s is still at 100 m).
    even = np.round(t * 10) % 2 == 0
    expected_times = np.concatenate([t[even & (t < 10)], [10.0, 15.1], t[even & (t >= 15.2)]])
    np.testing.assert_allclose(truth.t, expected_times)
    np.testing.assert_allclose(truth.xy[:, 0], np.interp(truth.t, t, x))  # each fix at its arrival
    assert np.all(truth.xy[(truth.t >= 10) & (truth.t <= 15), 0] == 100.0)  # standing: both ends
    sparse = tmp_path / "sparse.csv"
    t1 = np.arange(0.0, 60.0)
    x1 = np.where((t1 > 20) & (t1 < 24), 200.0, 10.0 * t1)
    np.savetxt(sparse, np.column_stack((t1, x1, 0 * t1)), delimiter=",", header="t,x,y", comments="")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_truth(sparse).t) == 60
