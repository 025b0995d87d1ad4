"""What the fuzz suite found (issue 10, item 8), each pinned by the smallest input that showed
it, so that it stays fixed whatever the fuzz budgets draw."""

from __future__ import annotations

import warnings

import pytest

from odomkit.data import builtin_data_path
from odomkit.errors import InputError, ModelError, OdomkitError

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")


def _one_line_error(code: int, err: str) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    return lines[0]


# --- a message is one line, whatever text it wraps ---------------------------------------------

@pytest.mark.parametrize("cls", [OdomkitError, ModelError])
def test_an_error_that_wraps_a_multi_line_message_is_one_line(cls):
    # A YAML parser's message (a corrupt ROS 2 bag's metadata.yaml) spans several lines.
    exc = cls("not a readable ROS bag (while scanning a simple key\n  in \"<unicode string>\", line 3\n"
              "could not find expected ':')")
    assert "\n" not in str(exc)
    assert str(exc) == ("not a readable ROS bag (while scanning a simple key in \"<unicode string>\", "
                        "line 3 could not find expected ':')")


def test_an_input_error_names_its_source_on_one_line():
    exc = InputError("bad\nyaml", source="b_mcap", line=2)
    assert str(exc) == "b_mcap, line 2: bad yaml"
    assert (exc.source, exc.line) == ("b_mcap", 2)


def test_a_corrupt_bag_metadata_is_one_line(run_cli, tmp_path):
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    bag = tmp_path / "b"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  a: b\n  c\n")
    code, _, err = run_cli("track", bag, "--robot", ROBOT)
    assert "not a readable ROS bag" in _one_line_error(code, err)


# --- a Khepera/Snowhite period that overflows the time column -----------------------------------

@pytest.mark.parametrize("reader", ["read_khepera", "read_snowhite"])
def test_a_period_whose_times_overflow_is_refused(tmp_path, reader):
    from odomkit.io import halmstad

    path = tmp_path / "log.txt"
    path.write_text("".join(f"{i} {i} {i} {i} {i}\n" for i in range(3)) if reader == "read_snowhite"
                    else "".join(f"{i} {i}\n" for i in range(3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(InputError, match="period 1e.308 s .* overflows"):
            getattr(halmstad, reader)(path, period=1e308)


def test_khepera_with_a_huge_period_is_one_line(run_cli, tmp_path):
    log = tmp_path / "khepera.txt"
    log.write_text("".join(f"{10 * i} {12 * i}\n" for i in range(5)))
    code, _, err = run_cli("track", log, "--robot", ROBOT, "--period", "1e308")
    assert "overflows" in _one_line_error(code, err)


# --- --kitti '' (or another path with no file name) ---------------------------------------------

@pytest.mark.parametrize("path", ["", ".", "/"])
def test_kitti_times_of_a_path_without_a_name_is_an_input_error(path):
    from odomkit.io.trackio import kitti_times_path

    with pytest.raises(InputError, match="a file path"):
        kitti_times_path(path)


def test_track_kitti_empty_path_is_one_line(run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--kitti", "")
    _one_line_error(code, err)
    assert list(tmp_path.iterdir()) == []


# --- fit-noise --scheduler with something that is not an address --------------------------------

@pytest.mark.parametrize("address", ["", "a b"])
def test_fit_noise_scheduler_that_is_no_address_is_one_line(run_cli, tmp_path, address):
    pytest.importorskip("dask.distributed", reason="the dask extra is not installed")
    out = tmp_path / "fit.toml"
    code, _, err = run_cli("fit-noise", "--robot", ROBOT, "--log", RUN, "--out", out, "--scheduler", address)
    assert "--scheduler" in _one_line_error(code, err)
    assert not out.exists()


# --- odomkit check's warnings are one line each, like every command's ------------------------

def test_check_reports_its_warnings_as_one_line_each(tmp_path, capsys):
    import json

    import numpy as np

    from odomkit.cli import main

    rows = np.loadtxt(RUN, delimiter=",")[::4, :4]
    truth = tmp_path / "truth.csv"
    np.savetxt(truth, np.vstack([rows[:3], rows[2:]]), delimiter=",", fmt="%.10g", header="t,x,y,theta",
               comments="")
    with warnings.catch_warnings(record=True) as escaped:
        warnings.simplefilter("always")
        code = main(["check", str(RUN), "--robot", str(ROBOT), "--truth", str(truth), "--json"])
    out, err = capsys.readouterr()
    assert code in (0, 1)
    assert [str(w.message) for w in escaped if issubclass(w.category, UserWarning)] == []
    assert err.strip().splitlines() == [f"odomkit: warning: {truth}: 1 truth rows repeat an earlier time "
                                        "and were dropped (the first fix at each time is kept)"]
    assert json.loads(out)["warnings"] == [err.strip().removeprefix("odomkit: warning: ")]


# --- every output is checked before any is written ------------------------------------------

def test_an_empty_frame_id_is_refused_before_anything_is_written(run_cli, tmp_path):
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    kitti, bag = tmp_path / "t.txt", tmp_path / "t.bag"
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--frame-id", "", "--kitti", kitti,
                           "--bag-out", bag)
    _one_line_error(code, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


# --- found by the fuzz suite in workflows/*, calibrate/* and cli/__init__.py (fixed since) -------

def test_track_ground_truth_figures_are_numbers_or_one_line(run_cli, tmp_path):
    log = tmp_path / "big.csv"
    log.write_text("t,gt_x,gt_y,gt_theta,R,L\n0,0,0,0,0,0\n1,1e199,0,0,10,10\n2,2e199,0,0,10,10\n")
    code, out, err = run_cli("track", log, "--robot", ROBOT, "--json", "--columns",
                             "t=t,ticks_left=L,ticks_right=R,gt_x=gt_x,gt_y=gt_y,gt_theta=gt_theta")
    if code == 2:
        _one_line_error(code, err)
        return
    import json

    truth = json.loads(out)["ground_truth"]
    assert truth["ate_rmse"] is not None and truth["nees_position_mean"] is not None, truth


def test_bare_odomkit_is_help_on_stdout_or_one_line(run_cli):
    code, out, err = run_cli()
    if code == 2:
        _one_line_error(code, err)
    else:
        assert code == 0 and "Commands:" in out and not err.strip(), (code, err)


def test_predict_classical_with_a_denormal_wheel_base_is_one_line(run_cli):
    code, out, err = run_cli("predict", "--model", "diff", "--noise", "classical", "--wheel-base", "1e-320",
                             "--sigma-distance", "0.01", "--sigma-angle", "0.01", "--segment", "arc:0.0,1.0",
                             "--json")
    assert code in (0, 2), err
    if code == 2:
        _one_line_error(code, err)


def test_fit_noise_with_huge_truth_is_one_line(run_cli, tmp_path):
    import numpy as np

    rows = np.loadtxt(RUN, delimiter=",")
    rows[:, 1] *= 1e200
    log = tmp_path / "big_run-01.csv"
    np.savetxt(log, rows, delimiter=",", fmt="%.17g")
    code, _, err = run_cli("fit-noise", "--robot", ROBOT, "--log", log, "--out", tmp_path / "f.toml",
                           "--json")
    assert code in (0, 2), err
    if code == 2:
        # The truth moving at 1e200 m/s is said first (a unit read wrong, as a rule); then the
        # one error line, no traceback.
        *said, error = err.strip().splitlines()
        assert all(line.startswith("odomkit: warning: ") for line in said), err
        assert error.startswith("odomkit: error: "), err


def test_simulate_standard_errors_are_numbers_or_one_line(run_cli):
    import json

    code, out, err = run_cli("simulate", "--model", "gyro", "--speed-noise", "1e-4", "--gyro-noise", "1e200",
                             "--segment", "straight:0.0,1", "--runs", "64", "--partitions", "8", "--workers",
                             "1", "--json")
    if code == 2:
        _one_line_error(code, err)
        return
    assert code == 0, err
    se = json.loads(out)["simulation"]["se"]
    assert all(v is not None for row in se["cov"] for v in row) and None not in se["mean"], se


def test_check_with_huge_times_is_one_line(run_cli, tmp_path):
    inputs = RUN.parents[3] / "tests" / "golden" / "inputs"
    rows = (inputs / "tricycle_speed.csv").read_text().splitlines()
    log = tmp_path / "big.csv"
    log.write_text("\n".join([rows[0]] + [",".join([repr(float(r.split(",")[0]) * 1e200), *r.split(",")[1:]])
                                          for r in rows[1:]]) + "\n")
    code, _, err = run_cli("check", log, "--robot", inputs / "tricycle.toml", "--columns",
                           "t=t,speed=speed,steer=steer", "--json")
    assert code in (0, 1, 2), err
    if code == 2:
        _one_line_error(code, err)


def test_fit_noise_never_writes_over_its_robot_file(run_cli, tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_bytes(ROBOT.read_bytes())
    code, _, err = run_cli("fit-noise", "--robot", robot, "--log", RUN, "--out", robot, "--force")
    assert robot.read_bytes() == ROBOT.read_bytes()
    assert "would replace an input" in _one_line_error(code, err)
