"""A ROS bag's GPS topic (``sensor_msgs/NavSatFix``) as ground truth: the same truth as a
latitude/longitude text file holding the same fixes (the independent reference: the text
reader, itself checked against WGS 84's radii in ``test_truth_latlon.py``), fixes without a
fix status left out and counted, and the fixes' stated σ reported, never used unasked.

The bag is the built-in OptiOdom run 01: its wheel angles as ``sensor_msgs/JointState`` and
its OptiTrack positions, every other row and 10 ms late, as GPS fixes around Sydney.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.io.optiodom import read_run
from odomkit.io.truth import read_truth

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
pm = pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")

from odomkit.io.bag import read_bag  # noqa: E402

RUN = builtin_data_path("230620202042_run-01.csv")
T0 = 1_687_000_000 * 10**9  # the run's times, moved to an epoch time [ns]
ORIGIN = (-33.8688, 151.2093, 42.0)
NO_FIX = 3  # every 7th fix, from the 4th, has status -1 (no fix)


def _seconds(ns):
    return ns // 10**9 + (ns % 10**9) / 1e9


@pytest.fixture(scope="module")
def gps_bag(tmp_path_factory, bag_writer, stamp, wheel_angles, rad_robot):
    """Bags in every format, the fixes with a fix as a text file, and the stated σ's median."""
    d = tmp_path_factory.mktemp("navsat")
    log = read_run(RUN)
    left, right = wheel_angles(log)
    msgs = []
    for k, t in enumerate(log.t):
        ns = T0 + round(t * 1e9)
        msgs.append(("/joint_states", "sensor_msgs/msg/JointState", ns + 2_000_000,
                     {"header": stamp(ns), "name": ["wheel_left_joint", "wheel_right_joint"],
                      "position": [left[k], right[k]]}))
    xy = log.ground_truth[::2, :2] - log.ground_truth[0, :2]
    lat, lon, h = pm.enu2geodetic(xy[:, 0], xy[:, 1], np.zeros(len(xy)), *ORIGIN)
    fix_ns = T0 + np.round((log.t[::2] + 0.01) * 1e9).astype(np.int64)
    rows, sigmas = [], []
    for k, ns in enumerate(fix_ns):
        lost = k % 7 == NO_FIX
        east, north = 0.002 + 2e-6 * k, 0.003 + 1e-6 * k  # σ per axis [m], stated per fix
        cov = [east**2, 0, 0, 0, north**2, 0, 0, 0, 4.0]
        msgs.append(("/fix", "sensor_msgs/msg/NavSatFix", int(ns) + 1_000_000,
                     {"header": stamp(int(ns), "gps"), "status": {"status": -1 if lost else 0},
                      # a receiver without a fix may say anything: these must not be read
                      "latitude": 0.0 if lost else lat[k], "longitude": 0.0 if lost else lon[k],
                      "altitude": h[k], "position_covariance": cov, "position_covariance_type": 2}))
        if not lost:
            rows.append((_seconds(int(ns)), lat[k], lon[k], h[k]))
            sigmas.append(math.sqrt((east**2 + north**2) / 2))
    text = d / "fixes.csv"
    text.write_text("t,lat,lon,alt\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    (d / "rad.toml").write_text(rad_robot)
    bags = {fmt: bag_writer(d / f"run_{fmt}", fmt, msgs) for fmt in ("ros1", "db3", "mcap")}
    return {"dir": d, "text": text, "bags": bags, "fixes": len(fix_ns), "kept": len(rows),
            "sigma": float(np.median(sigmas))}


@pytest.mark.parametrize("fmt", ["ros1", "db3", "mcap"])
def test_a_navsatfix_topic_is_the_truth_the_text_file_gives(gps_bag, fmt):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        log = read_bag(gps_bag["bags"][fmt], ("/joint_states",), truth_topic="/fix")
    lost = gps_bag["fixes"] - gps_bag["kept"]
    assert lost > 100
    assert [str(w.message) for w in caught] == [
        f"{gps_bag['bags'][fmt]}: /fix: {lost} of {gps_bag['fixes']} NavSatFix messages have no fix "
        "(status < 0) and are left out"]
    truth = log.meta["truth"]
    text = read_truth(gps_bag["text"])
    assert truth.t.tolist() == text.t.tolist()
    np.testing.assert_allclose(truth.xy, text.xy, rtol=0, atol=1e-9)
    assert truth.theta is None and log.ground_truth is None  # position-only, on its own clock
    assert log.meta["truth_position_sigma"] == pytest.approx(gps_bag["sigma"], rel=1e-12)
    # Every row of the log is kept: the fixes are not resampled at the rows.
    assert len(log) == len(read_run(RUN))


def _evaluate(run_cli, gps_bag, *args):
    code, out, err = run_cli("evaluate", gps_bag["bags"]["mcap"], "--robot", gps_bag["dir"] / "rad.toml",
                             "--topic", "/joint_states", "--window", "10s", *args, "--json")
    assert code == 0, err
    result = json.loads(out)
    return result, result.pop("warnings", [])


def test_evaluate_with_the_gps_topic_equals_the_text_file(run_cli, gps_bag):
    topic, topic_warnings = _evaluate(run_cli, gps_bag, "--truth-topic", "/fix")
    text, text_warnings = _evaluate(run_cli, gps_bag, "--truth", gps_bag["text"])
    assert topic == text
    hint = [w for w in topic_warnings if "--truth-sigma" in w]
    assert len(hint) == 1 and f"median horizontal sigma {gps_bag['sigma']:.3g} m per axis" in hint[0]
    assert f"--truth-sigma {gps_bag['sigma']:.3g} takes it" in hint[0]
    assert any("NavSatFix messages have no fix" in w for w in topic_warnings)
    assert not [w for w in text_warnings if "--truth-sigma" in w or "NavSatFix" in w]
    # Given, the σ is used and the hint is gone; the scores change (the σ is not taken silently).
    given, given_warnings = _evaluate(run_cli, gps_bag, "--truth-topic", "/fix",
                                      "--truth-sigma", f"{gps_bag['sigma']:.3g}")
    assert not [w for w in given_warnings if "--truth-sigma" in w]
    assert given["nees_position_mean"] < topic["nees_position_mean"]


def test_calibrate_with_the_gps_topic_equals_the_text_file(run_cli, gps_bag):
    """A bag whose truth is a GPS topic calibrates from its fixes, as --truth FILE does:
    same parameters, same fitted clock offset, the stated σ taken only when given."""
    def calibrate(*args):
        code, out, err = run_cli("calibrate", gps_bag["bags"]["mcap"], "--robot", gps_bag["dir"] / "rad.toml",
                                 "--topic", "/joint_states", "--truth-sigma", "0.003", *args, "--json")
        assert code == 0, err
        return json.loads(out)

    topic = calibrate("--truth-topic", "/fix")
    text = calibrate("--truth", gps_bag["text"])
    assert topic["parameters"] == pytest.approx(text["parameters"], rel=1e-9)
    assert topic["truth_time_offset"]["value"] == pytest.approx(text["truth_time_offset"]["value"], abs=1e-9)
    assert topic["truth_time_offset"]["fitted"] and abs(topic["truth_time_offset"]["value"]) < 0.1
    code, _, err = run_cli("calibrate", gps_bag["bags"]["mcap"], "--robot", gps_bag["dir"] / "rad.toml",
                           "--topic", "/joint_states", "--truth-topic", "/fix", "--from", "trajectory")
    assert code == 2 and "--from does not apply with --truth" in err


def test_too_few_fixes_and_bad_fixes_are_one_line(run_cli, tmp_path, bag_writer, stamp, rad_robot):
    (tmp_path / "rad.toml").write_text(rad_robot)
    joints = [("/js", "sensor_msgs/msg/JointState", T0 + k * 10**8,
               {"header": stamp(T0 + k * 10**8), "name": ["left", "right"],
                "position": [k, k]}) for k in range(5)]

    def fix(k, status=0, lat=-33.0):
        return ("/fix", "sensor_msgs/msg/NavSatFix", T0 + k * 10**8 + 1,
                {"header": stamp(T0 + k * 10**8), "status": {"status": status}, "latitude": lat,
                 "longitude": 151.0})

    def error(name, fixes):
        bag = bag_writer(tmp_path / name, "mcap", joints + fixes)
        code, out, err = run_cli("track", bag, "--robot", tmp_path / "rad.toml", "--topic", "/js",
                                 "--truth-topic", "/fix")
        errors = [line for line in err.splitlines() if not line.startswith("odomkit: warning: ")]
        assert code == 2 and out == "" and len(errors) == 1 and "Traceback" not in err
        return errors[0]

    err = error("lost", [fix(0), fix(1, -1), fix(2, -1)])
    assert "/fix: 1 of 3 NavSatFix messages have a fix (status >= 0); truth needs two or more" in err
    err = error("far", [fix(0), fix(1, lat=-95.0), fix(2)])
    assert "/fix: message 2 has latitude -95.0; expected degrees within ±90" in err


def test_report_calibrates_from_the_gps_topic_and_names_it(run_cli, gps_bag, tmp_path):
    """A bag's GPS topic is the report's truth as it is calibrate's: the page calibrates from
    its fixes (it said "No calibration: --from does not apply with --truth", a flag never
    given) and names that topic as the truth (it said "the log's own gt_* columns")."""
    out = tmp_path / "r.html"
    code, text, err = run_cli("report", gps_bag["bags"]["mcap"], "--robot", gps_bag["dir"] / "rad.toml",
                              "--topic", "/joint_states", "--truth-topic", "/fix", "--truth-sigma", "0.003",
                              "--out", out, "--json")
    assert code == 0, err
    page = out.read_text()
    # Each scoring of the log (robot file, calibrated, fitted noise) says a thing once: what an
    # earlier one said word for word is not repeated, and the late start is the track's alone.
    said = json.loads(text)["warnings"]
    bare = [w.removeprefix("after calibration: ").removeprefix("with the fitted noise: ") for w in said]
    repeated = [w for w in bare if bare.count(w) > 1 and "starts from a heading fitted" not in w]
    assert not repeated, repeated
    assert sum(" starts at " in w and "left out" in w for w in said) <= 1
    # The start-heading warning of each scoring says which scoring it is (it came twice, with
    # different numbers and no word of which was which).
    heading = [w for w in said if "starts from a heading fitted" in w]
    assert len(heading) >= 2 and not heading[0].startswith(("after", "with"))
    assert all(w.startswith(("after calibration: ", "with the fitted noise: ")) for w in heading[1:])
    assert "--from does not apply" not in page and "No calibration" not in page
    assert f"truth: {gps_bag['bags']['mcap']}:/fix" in page and "gt_* columns" not in page
    code, text, err = run_cli("calibrate", gps_bag["bags"]["mcap"], "--robot", gps_bag["dir"] / "rad.toml",
                              "--topic", "/joint_states", "--truth-topic", "/fix", "--truth-sigma", "0.003",
                              "--json")
    assert code == 0, err
    for name, value in json.loads(text)["parameters"].items():  # the page shows calibrate's values
        assert f"{value:.6g}" in page, name


def test_the_robot_files_clock_offset_moves_a_gps_topic_as_it_moves_the_text_file(run_cli, gps_bag, tmp_path,
                                                                                   rad_robot):
    """calibrate fits the GPS's clock offset into [truth] time_offset; a bag's GPS topic is on
    its own clock as a latitude/longitude file is, so the offset moves both alike (a user
    study's calibrated Husky: 20.7 m ATE from the topic, 19.2 m from the same fixes as a file)
    and fit-noise keeps it in the file it writes. A log's gt_* columns are never moved by it."""
    robot = tmp_path / "late.toml"
    robot.write_text(rad_robot + "\n[truth]\ntime_offset = 0.3\n")
    args = ("--robot", robot, "--topic", "/joint_states", "--window", "10s", "--truth-sigma", "0.003",
            "--json")
    runs = {}
    for name, truth in (("topic", ("--truth-topic", "/fix")), ("file", ("--truth", gps_bag["text"]))):
        code, out, err = run_cli("evaluate", gps_bag["bags"]["mcap"], *args, *truth)
        assert code == 0, err
        runs[name] = json.loads(out)
        runs[name].pop("warnings", None)
    assert runs["topic"] == runs["file"]
    fitted = tmp_path / "fit.toml"
    code, _, err = run_cli("fit-noise", "--robot", robot, "--log", gps_bag["bags"]["mcap"], "--topic",
                           "/joint_states", "--truth-topic", "/fix", "--truth-sigma", "0.003", "--window",
                           "10s", "--out", fitted)
    assert code == 0, err
    assert "time_offset = 0.3" in fitted.read_text()
