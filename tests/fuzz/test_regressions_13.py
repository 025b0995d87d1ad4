"""Small findings of the fuzz session, fixed in the issue-13 session; each pinned by the
smallest input that showed it (errors name the flag, inapplicable flags are refused, a
figure that cannot be a number says why)."""

from __future__ import annotations

import json
import math

import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
RUN = RUNS[0]


def _one_line_error(code: int, err: str) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    return lines[0]


# --- 1. simulate names its flags, not its parameters ---------------------------------------------

_SIMULATE = {"--segment": "arc:3,1", "--wheel-base": "0.4", "--k-left": "0.001", "--k-right": "0.001",
             "--runs": "16", "--partitions": "8"}


@pytest.mark.parametrize("flag,value", [("--workers", "0"), ("--workers", "-2"), ("--max-work", "0"),
                                        ("--max-work", "nan"), ("--runs", "0"), ("--partitions", "0"),
                                        ("--chunk-runs", "0"), ("--seed", "-1")])
def test_simulate_errors_name_the_flag(run_cli, flag, value):
    args = {**_SIMULATE, flag: value}
    code, _, err = run_cli("simulate", *[s for kv in args.items() for s in kv], "--json")
    line = _one_line_error(code, err)
    assert f"{flag} must be" in line, line


@pytest.mark.parametrize("engine", ["closed", "recursion"])
@pytest.mark.parametrize("value", ["0", "-5"])
def test_predict_partitions_error_names_the_flag(run_cli, engine, value):
    code, _, err = run_cli("predict", "--segment", "arc:3,1", "--wheel-base", "0.4", "--k-left", "0.001",
                           "--k-right", "0.001", "--engine", engine, "--partitions", value, "--json")
    assert "--partitions must be" in _one_line_error(code, err)


# --- 2. demo --out '' would write into the current folder ----------------------------------------

def test_demo_refuses_an_empty_out(run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli("demo", "--out", "")
    line = _one_line_error(code, err)
    assert "--out" in line and "empty" in line, line
    assert list(tmp_path.iterdir()) == [] and out == ""


# --- 3. track: a covariance flag without a covariance -------------------------------------------

@pytest.mark.parametrize("engine", ["bogus", "transition", "recursion"])
def test_track_engine_without_covariance_is_refused(run_cli, engine):
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--engine", engine, "--no-covariance")
    line = _one_line_error(code, err)
    assert "--engine" in line and "--no-covariance" in line, line


def test_track_initial_cov_without_covariance_is_refused(run_cli):
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--initial-cov", "1e-4,1e-4,1e-3",
                           "--no-covariance")
    line = _one_line_error(code, err)
    assert "--initial-cov" in line and "--no-covariance" in line, line


def test_track_engine_with_a_robot_file_without_noise_is_refused(run_cli, tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT.read_text().split("[noise]")[0])
    code, _, err = run_cli("track", RUN, "--robot", robot, "--engine", "transition")
    line = _one_line_error(code, err)
    assert "--engine" in line and "[noise]" in line, line


def test_track_without_covariance_still_runs(run_cli):
    """The refusal is of the flag, not of --no-covariance."""
    code, out, err = run_cli("track", RUN, "--robot", ROBOT, "--no-covariance", "--json")
    assert code == 0, err
    assert json.loads(out)["cov"] is None


# --- 4. umbmark --runs with one run per direction printed "nan mm" ------------------------------

def test_umbmark_runs_with_one_run_per_direction_says_why_there_is_no_spread(run_cli):
    # run-01..03 are CW, run-04..06 CCW (the metadata's direction column)
    code, out, err = run_cli("umbmark", "--runs", RUNS[0], RUNS[3], "--robot", ROBOT, "--side", "0.75")
    assert code == 0, err
    assert "nan" not in out.lower(), out
    sem_line = next(line for line in out.splitlines() if line.startswith("SEM"))
    assert "2 or more runs" in sem_line, sem_line
    assert "odomkit: warning:" in err and "2 or more runs" in err, err


def test_umbmark_runs_json_says_why_sigma_is_null(run_cli):
    code, out, err = run_cli("umbmark", "--runs", RUNS[0], RUNS[3], RUNS[4], "--robot", ROBOT,
                             "--side", "0.75", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["sem"]["cw"] is None and data["sem"]["ccw"] is not None  # 1 CW run, 2 CCW
    assert any("CW" in w and "2 or more runs" in w for w in data["warnings"]), data.get("warnings")


def test_umbmark_runs_with_two_runs_per_direction_warns_nothing(run_cli):
    code, out, err = run_cli("umbmark", "--runs", *RUNS[:2], *RUNS[3:5], "--robot", ROBOT,
                             "--side", "0.75", "--json")
    assert code == 0 and not err.strip(), err
    assert "warnings" not in json.loads(out)


# --- 5. simulate: infinite z-scores were bare nulls in the JSON ----------------------------------

def test_simulate_infinite_z_scores_are_named_in_a_warning(run_cli):
    # No noise and no initial covariance: the predicted covariance is exactly zero, while
    # the systematic error moves every run's end by the same amount. The z-score of the mean
    # error is then ±inf (JSON null), and only a warning can say so.
    code, out, err = run_cli("simulate", "--segment", "arc:3,1", "--wheel-base", "0.4", "--k-left", "0",
                             "--k-right", "0", "--systematic", "1.01,1,1", "--runs", "16",
                             "--partitions", "8", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["z"]["mean"] == [None, None, None]
    assert all(v == 0.0 for v in data["theory"]["std"])
    assert all(abs(e) > 1e-6 for e in data["simulation"]["mean_error"])  # the independent truth
    warned = [w for w in data["warnings"] if "z" in w and "mean x" in w]
    assert len(warned) == 1, data["warnings"]
    assert "mean y" in warned[0] and "mean theta" in warned[0] and "predicted variance" in warned[0]
    assert f"odomkit: warning: {warned[0]}" in err.splitlines()


def test_simulate_finite_z_scores_warn_nothing(run_cli):
    code, out, err = run_cli("simulate", *[s for kv in _SIMULATE.items() for s in kv], "--json")
    assert code == 0 and not err.strip(), err
    data = json.loads(out)
    assert "warnings" not in data
    assert all(math.isfinite(v) for v in data["z"]["mean"])


def test_the_fuzz_property_wants_a_reason_for_a_null_z_score():
    import importlib.util
    import sys
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("odomkit_fuzz", Path(__file__).with_name("_fuzz.py"))
    assert spec is not None and spec.loader is not None
    fz = sys.modules.setdefault("odomkit_fuzz", importlib.util.module_from_spec(spec))
    if not hasattr(fz, "check_json"):
        spec.loader.exec_module(fz)
    doc = {"theory": {"std": [0.0, 1.0, 1.0]}, "z": {"mean": [None, 0.1, 0.2], "corr": {"xy": None}}}
    with pytest.raises(AssertionError, match="z.mean"):
        fz.check_json(json.dumps(doc))
    fz.check_json(json.dumps({**doc, "warnings": ["the predicted variance of x is zero ..."]}))
