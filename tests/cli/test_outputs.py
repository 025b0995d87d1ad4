"""Every command checks all its output paths before it computes or writes anything
(issue 10, item 8): one line, exit 2, nothing half-written, nothing the user had lost."""

from __future__ import annotations

import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]


def _one_line_error(code: int, err: str, message: str) -> None:
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    assert message in lines[0], err


def test_track_out_in_a_missing_folder(run_cli, tmp_path):
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", tmp_path / "nodir" / "out.csv")
    _one_line_error(code, err, "--out: no such folder")


def test_track_out_naming_a_folder(run_cli, tmp_path):
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", tmp_path, "--force")
    _one_line_error(code, err, "--out names a folder")


def test_track_out_and_tum_on_one_path_write_nothing(run_cli, tmp_path):
    target = tmp_path / "t.txt"
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", target, "--tum", target)
    _one_line_error(code, err, "--out and --tum name the same file")
    assert not target.exists()


def test_track_never_writes_over_its_own_log(run_cli, tmp_path):
    log = tmp_path / "230620202042_run-01.csv"
    log.write_bytes(RUNS[0].read_bytes())
    code, _, err = run_cli("track", log, "--robot", ROBOT, "--out", log, "--force")
    _one_line_error(code, err, "--out would replace an input")
    assert log.read_bytes() == RUNS[0].read_bytes()


def test_track_refuses_a_second_output_before_writing_the_first(run_cli, tmp_path):
    out, tum = tmp_path / "t.csv", tmp_path / "t.tum"
    tum.write_text("mine\n")
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--out", out, "--tum", tum)
    _one_line_error(code, err, "exists already; pass --force")
    assert not out.exists() and tum.read_text() == "mine\n"


def test_calibrate_out_robot_in_a_missing_folder(run_cli, tmp_path):
    code, _, err = run_cli("calibrate", *RUNS, "--robot", ROBOT,
                           "--out-robot", tmp_path / "nodir" / "r.toml")
    _one_line_error(code, err, "--out-robot: no such folder")


def test_calibrate_out_robot_and_ros_yaml_on_one_path(run_cli, tmp_path):
    target = tmp_path / "both.txt"
    code, _, err = run_cli("calibrate", *RUNS, "--robot", ROBOT, "--out-robot", target,
                           "--ros-yaml", target, "--wheel-radius", "0.042")
    _one_line_error(code, err, "--out-robot and --ros-yaml name the same file")
    assert not target.exists()


def test_calibrate_noise_plot_is_checked_up_front(run_cli, tmp_path):
    picture = tmp_path / "mine.png"
    picture.write_bytes(b"not yours")
    code, _, err = run_cli("calibrate-noise", *RUNS, "--robot", ROBOT, "--plot", picture)
    _one_line_error(code, err, "exists already; pass --force")
    assert picture.read_bytes() == b"not yours"
    code, _, err = run_cli("calibrate-noise", *RUNS, "--robot", ROBOT, "--plot", tmp_path / "no" / "p.png")
    _one_line_error(code, err, "--plot: no such folder")


def test_demo_out_an_existing_file(run_cli, tmp_path):
    existing = tmp_path / "notes.txt"
    existing.write_text("mine\n")
    code, _, err = run_cli("demo", "--out", existing)
    _one_line_error(code, err, "--out names an existing file; give a folder")
    assert existing.read_text() == "mine\n"


@pytest.mark.parametrize("flag", ["--out", "--tum"])
def test_an_existing_output_is_replaced_only_with_force(run_cli, tmp_path, flag):
    target = tmp_path / "t.out"
    target.write_text("old\n")
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, flag, target, "--no-covariance")
    _one_line_error(code, err, "exists already")
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, flag, target, "--no-covariance", "--force")
    assert code == 0, err
    assert target.read_text() != "old\n"


def test_a_bad_bag_option_is_refused_before_any_output_is_written(run_cli, tmp_path):
    pytest.importorskip("rosbags")
    kitti, bag = tmp_path / "out.txt", tmp_path / "out.bag"
    code, _, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--kitti", kitti, "--bag-out", bag,
                           "--frame-id", "")
    _one_line_error(code, err, "--frame-id and --child-frame-id must not be empty")
    assert sorted(p.name for p in tmp_path.iterdir()) == []
