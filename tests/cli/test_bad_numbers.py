"""Extreme but finite inputs never crash, never print NaN or null as a result, and never leak
numpy's RuntimeWarnings before the error (issue 10, item 8): the answer is either finite
numbers (exit 0) or one line ``odomkit: error: ...`` naming what overflowed (exit 2)."""

from __future__ import annotations

import json
import math
import re

import pytest

from odomkit.data import builtin_data_path

# A RuntimeWarning anywhere is a failure: outside pytest it would print before the error.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]

# Results that must be finite numbers when a command succeeds.
PRIMARY = {
    "track": ("pose", "cov", "path_length"),
    "calibrate": ("parameters", "E_d", "E_b", "wheel_base"),
    "calibrate-noise": ("k_left", "k_right", "cov_fitted", "mean"),
    "umbmark": ("cg", "alpha", "beta", "E_d", "E_b", "c_left", "c_right", "wheel_base"),
}


def _numbers(value):
    if isinstance(value, dict):
        for v in value.values():
            yield from _numbers(v)
    elif isinstance(value, list):
        for v in value:
            yield from _numbers(v)
    else:
        yield value


def _robot(tmp_path, field, value):
    text = re.sub(rf"^{field} = \S+", f"{field} = {value}", ROBOT.read_text(), flags=re.M)
    assert f"{field} = {value}" in text
    path = tmp_path / f"{field}.toml"
    path.write_text(text)
    return path


def _check(code, out, err, command):
    assert "Traceback" not in err and "RuntimeWarning" not in err and "encountered" not in err, err
    if code == 2:
        lines = [ln for ln in err.strip().splitlines() if not ln.startswith("odomkit: warning:")]
        assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
        return
    assert code == 0, err
    result = json.loads(out)
    for key in PRIMARY[command]:
        for number in _numbers(result[key]):
            assert isinstance(number, int | float) and math.isfinite(number), (key, result[key])


COMMANDS = {
    "track": lambda robot: ["track", RUNS[0], "--robot", robot],
    "calibrate": lambda robot: ["calibrate", *RUNS, "--robot", robot, "--side", "0.75"],
    "calibrate-trajectory": lambda robot: ["calibrate", *RUNS, "--robot", robot, "--from", "trajectory"],
    "calibrate-noise": lambda robot: ["calibrate-noise", *RUNS, "--robot", robot],
    "umbmark": lambda robot: ["umbmark", "--runs", *RUNS, "--robot", robot, "--side", "0.75"],
}


EXTREME = [("wheel_base", "1e-300"), ("wheel_base", "1e-320"), ("wheel_base", "1e200"),
           ("wheel_base", "1e308"), ("wheel_diameter", "1e200"), ("wheel_diameter", "1e-300")]
# Only track propagates the robot file's noise.
NOISY = [("k_left", "1e200"), ("k_right", "1e308"), ("k_left", "1e-320")]


@pytest.mark.parametrize("command, field, value",
                         [(c, f, v) for c in COMMANDS for f, v in EXTREME]
                         + [("track", f, v) for f, v in NOISY])
def test_extreme_robot_files_give_numbers_or_one_line(run_cli, tmp_path, command, field, value):
    code, out, err = run_cli(*COMMANDS[command](_robot(tmp_path, field, value)), "--json")
    _check(code, out, err, command.split("-trajectory")[0])


@pytest.mark.parametrize("side", ["1e-300", "1e-100", "0.001", "4"])
@pytest.mark.parametrize("x", ["-0.1", "1e200", "-1e308"])
def test_umbmark_large_return_errors(run_cli, tmp_path, side, x):
    errors = tmp_path / "errors.csv"
    errors.write_text(f"direction,x,y\ncw,{x},-0.12\ncw,-0.1,-0.12\nccw,-0.1,0.1\nccw,{x},0.1\n")
    code, out, err = run_cli("umbmark", errors, "--side", side, "--wheel-base", "0.34", "--json")
    _check(code, out, err, "umbmark")


def test_umbmark_refuses_errors_whose_estimates_disagree_beyond_the_model(run_cli, tmp_path):
    # x and y of the c.g.s give α, β estimates of ±6e198 rad that average to 0: E_d = E_b = 1
    # would be a silently wrong answer.
    errors = tmp_path / "errors.csv"
    errors.write_text("direction,x,y\ncw,-0.1,-0.1\ncw,-0.1,-0.1\nccw,1e200,1e200\nccw,1e200,1e200\n")
    code, _, err = run_cli("umbmark", errors, "--side", "4", "--wheel-base", "0.34")
    assert code == 2 and "too large for UMBmark" in err, err


def test_a_huge_decimation_keeps_the_first_row(run_cli):
    code, out, err = run_cli("track", RUNS[0], "--robot", ROBOT, "--decimate", str(10**20), "--json")
    assert code == 0, err
    assert json.loads(out)["samples"] == 1


def test_identical_runs_have_no_spread_to_fit(run_cli):
    code, _, err = run_cli("calibrate-noise", RUNS[0], RUNS[0], RUNS[0], "--robot", ROBOT)
    assert code == 2 and "no spread" in err, err
    assert len(err.strip().splitlines()) == 1
