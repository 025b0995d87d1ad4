"""``odomkit fit-amcl`` (issue 12 item 6): files in, the same fit as the library on the
updates AMCL would take, and a nav2 snippet a YAML parser reads with nav2's key names."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.calibrate.amcl import amcl_data, amcl_update_rows, fit_amcl
from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
ALPHA = (0.05, 0.1, 0.04, 0.2)


def _odometry(rng, n):
    """Moves of 0.3 m along the axes and quarter turns in five steps: every row passes
    AMCL's default thresholds (|dx| or |dy| > 0.25 m, or a turn > 0.2 rad)."""
    pose, out = np.zeros(3), [np.zeros(3)]
    for _ in range(n):
        if rng.random() < 0.5:
            d = 0.3 * rng.choice([1, -1])
            pose = pose + np.array([d * math.cos(pose[2]), d * math.sin(pose[2]), 0.0])
            out.append(pose.copy())
        else:
            turn = rng.choice([1, -1]) * math.pi / 10
            for _ in range(5):
                pose = pose + np.array([0.0, 0.0, turn])
                out.append(pose.copy())
    return np.array(out)


def _truth(rng, odom):
    """AMCL's differential sampler (nav2 differential_motion_model.cpp) along ``odom``."""
    a1, a2, a3, a4 = ALPHA

    def diff(a, b):
        return math.remainder(a - b, 2 * math.pi)

    poses = [np.array([2.0, 1.0, 0.5])]
    for p0, p1 in zip(odom[:-1], odom[1:], strict=True):
        dx, dy = p1[0] - p0[0], p1[1] - p0[1]
        trans = math.hypot(dx, dy)
        rot1 = 0.0 if trans < 0.01 else diff(math.atan2(dy, dx), p0[2])
        rot2 = diff(diff(p1[2], p0[2]), rot1)
        n1, n2 = min(abs(rot1), abs(diff(rot1, math.pi))), min(abs(rot2), abs(diff(rot2, math.pi)))
        r1 = rot1 - rng.normal(0, math.sqrt(a1 * n1**2 + a2 * trans**2))
        t = trans - rng.normal(0, math.sqrt(a3 * trans**2 + a4 * (n1**2 + n2**2)))
        r2 = rot2 - rng.normal(0, math.sqrt(a1 * n2**2 + a2 * trans**2))
        q = poses[-1].copy()
        q += [t * math.cos(q[2] + r1), t * math.sin(q[2] + r1), r1 + r2]
        poses.append(q)
    return np.array(poses)


def _write(path, t, poses, header):
    lines = ([header] if header else []) + [",".join(repr(v) for v in (tt, *p)) for tt, p in
                                             zip(t.tolist(), poses.tolist(), strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_fit_amcl_on_a_track_and_truth_file(run_cli, tmp_path):
    yaml = pytest.importorskip("yaml")
    rng = np.random.default_rng(11)
    odom = _odometry(rng, 250)
    truth = _truth(rng, odom)
    t = 0.5 * np.arange(len(odom))
    track = _write(tmp_path / "odom.csv", t, odom, "t,x,y,theta")
    gt = _write(tmp_path / "gt.txt", t, truth, None)  # headerless t,x,y,theta
    out_yaml = tmp_path / "amcl.yaml"
    code, out, err = run_cli("fit-amcl", track, "--truth", gt, "--truth-columns", "t,x,y,theta",
                             "--yaml-out", out_yaml, "--json")
    assert code == 0, err
    report = json.loads(out)
    rows = amcl_update_rows(odom)
    assert rows.tolist() == list(range(len(odom)))  # every row is an update, as built
    direct = fit_amcl(amcl_data(odom[:-1], odom[1:], truth[:-1], truth[1:]))
    assert report["updates"] == direct.updates == len(odom) - 1
    assert [report["alpha"][k] for k in ("alpha1", "alpha2", "alpha3", "alpha4")] == pytest.approx(
        direct.alpha, rel=1e-9)
    for name, true in zip(("alpha1", "alpha2", "alpha3", "alpha4"), ALPHA, strict=True):
        lo, hi = report["interval95"][name]
        assert lo <= true <= hi, (name, lo, true, hi)
    params = yaml.safe_load(out_yaml.read_text())["amcl"]["ros__parameters"]
    assert {k: params[k] for k in report["alpha"]} == report["alpha"]
    assert params["robot_model_type"] == "nav2_amcl::DifferentialMotionModel"
    assert report["outputs"] == {"yaml": str(out_yaml)}
    # never over an existing file without --force
    before = out_yaml.read_text()
    code, _, err = run_cli("fit-amcl", track, "--truth", gt, "--truth-columns", "t,x,y,theta",
                           "--yaml-out", out_yaml)
    assert code == 2 and "exists" in err and out_yaml.read_text() == before


def test_fit_amcl_on_optiodom_logs_with_a_robot(run_cli):
    code, out, err = run_cli("fit-amcl", *RUNS, "--robot", ROBOT, "--json")
    assert code == 0, err
    report = json.loads(out)
    assert set(report["alpha"]) == {"alpha1", "alpha2", "alpha3", "alpha4"}
    assert report["updates"] > 150 and report["updates_skipped"] == 0
    assert [p["updates"] for p in report["per_log"]] and sum(p["updates"] for p in report["per_log"]) == \
        report["updates"]
    assert all(lo <= report["alpha"][k] <= (math.inf if hi is None else hi)
               for k, (lo, hi) in report["interval95"].items())
    # coarser thresholds mean fewer updates
    code, out, _ = run_cli("fit-amcl", *RUNS, "--robot", ROBOT, "--update-min-d", "0.5", "--json")
    assert json.loads(out)["updates"] < report["updates"]


def test_fit_amcl_refuses_bad_input(run_cli, tmp_path):
    code, _, err = run_cli("fit-amcl", RUNS[0], "--robot", ROBOT, "--model", "ackermann")
    assert code == 2 and "--model" in err
    code, _, err = run_cli("fit-amcl", RUNS[0], "--robot", ROBOT, "--update-min-d", "0")
    assert code == 2 and "--update-min-d" in err
    code, _, err = run_cli("fit-amcl", RUNS[0], "--columns", "t=t")  # log options without --robot
    assert code == 2 and "--robot" in err
    track = _write(tmp_path / "odom.csv", np.arange(3.0), np.zeros((3, 3)), "t,x,y,theta")
    code, _, err = run_cli("fit-amcl", track)
    assert code == 2 and "no truth" in err


def test_a_track_written_by_odomkit_track_gives_the_same_fit_as_its_log(run_cli, tmp_path):
    """The track CSV carries the log's truth in gt_* columns: the same updates, the same α's."""
    track = tmp_path / "track.csv"
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", track)
    assert code == 0, err
    _, from_track, _ = run_cli("fit-amcl", track, "--json")
    _, from_log, _ = run_cli("fit-amcl", RUNS[0], "--robot", ROBOT, "--json")
    a, b = json.loads(from_track), json.loads(from_log)
    assert a["updates"] == b["updates"] > 0
    assert list(a["alpha"].values()) == pytest.approx(list(b["alpha"].values()), rel=1e-9)


def test_a_bags_odometry_topic_gives_the_same_fit_as_the_track(run_cli, tmp_path):
    """``track --bag-out`` writes nav_msgs/Odometry; fitted against the same truth it gives the
    track CSV's α's (the bag's stamps are the log's times to within a nanosecond)."""
    pytest.importorskip("rosbags")
    from odomkit.io.trackio import read_track_csv

    track, bag = tmp_path / "track.csv", tmp_path / "run.bag"
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", track, "--bag-out", bag)
    assert code == 0, err
    written = read_track_csv(track)
    truth = _write(tmp_path / "gt.txt", written.t, written.truth, None)
    _, from_bag, err = run_cli("fit-amcl", bag, "--truth", truth, "--truth-columns", "t,x,y,theta", "--json")
    _, from_track, _ = run_cli("fit-amcl", track, "--json")
    a, b = json.loads(from_bag), json.loads(from_track)
    assert a["updates"] == b["updates"] > 0
    assert list(a["alpha"].values()) == pytest.approx(list(b["alpha"].values()), rel=1e-8)
    code, _, err = run_cli("fit-amcl", track, "--topic", "/odom")
    assert code == 2 and "applies to a ROS bag" in err
