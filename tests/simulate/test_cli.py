"""``odomkit simulate`` through odomkit.cli.main."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.cli import main

BASE = ["simulate", "--model", "diff", "--wheel-base", "0.4", "--segment", "arc:3,1"]


def _json(capsys, args):
    assert main(args + ["--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_contract_and_theory_equals_predict(capsys):
    noise = ["--k-left", "0.003", "--k-right", "0.002", "--initial-cov", "1e-6,2e-6,1e-6"]
    out = _json(capsys, BASE + noise + ["--runs", "2000", "--partitions", "100", "--seed", "3"])
    assert {"theory", "simulation", "runs", "partitions", "seconds", "verdict", "checks",
            "z", "seed"} <= set(out)
    assert {"mean", "cov", "std", "corr", "se"} <= set(out["simulation"])
    assert set(out["simulation"]["corr"]) == {"xy", "xtheta", "ytheta"}
    assert (out["runs"], out["partitions"], out["seed"]) == (2000, 100, 3)
    assert out["seconds"] > 0
    # "theory (as predict)": the same numbers as odomkit predict with the same options
    pred = _json(capsys, ["predict", *BASE[1:], *noise])
    for key in ("pose", "cov", "std", "corr"):
        assert out["theory"][key] == pred[key]
    # simulated figures are internally consistent: std² = diag(cov), corr = cov/(σσ)
    cov = np.array(out["simulation"]["cov"])
    std = np.array(out["simulation"]["std"])
    np.testing.assert_allclose(std**2, np.diag(cov), rtol=1e-12)
    assert out["simulation"]["corr"]["xy"] == pytest.approx(cov[0, 1] / (std[0] * std[1]))
    # the theory's θ is wrapped for display (−5 rad -> 1.28319); the simulated mean θ is
    # continuous (DESIGN: θ continuous in every statistic)
    assert out["theory"]["pose"][2] == pytest.approx(-5 + 2 * math.pi, abs=1e-12)
    assert out["simulation"]["mean"][2] == pytest.approx(-5.0, abs=5e-3)
    assert all(-1 <= v <= 1 for v in out["simulation"]["corr"].values())


def test_zero_noise_simulation_is_the_nominal_pose(capsys):
    out = _json(capsys, BASE + ["--k-left", "0", "--k-right", "0", "--runs", "10",
                                "--partitions", "1000"])
    np.testing.assert_allclose(out["simulation"]["mean"], [-0.38357, -0.286535, -5.0], atol=6e-6)
    np.testing.assert_allclose(out["simulation"]["mean_error"], 0.0, atol=1e-12)
    assert out["verdict"] == "consistent"


def test_same_seed_same_numbers_whatever_workers_and_chunks(capsys):
    args = BASE + ["--k-left", "0.01", "--k-right", "0.02", "--runs", "600", "--partitions",
                   "50", "--seed", "8"]
    a = _json(capsys, args + ["--workers", "1"])
    b = _json(capsys, args + ["--workers", "2", "--chunk-runs", "512"])
    c = _json(capsys, [*args[:-1], "9"])
    assert a["simulation"] == b["simulation"]
    assert a["simulation"]["mean"] != c["simulation"]["mean"]


def test_rich_table(capsys):
    assert main(BASE + ["--k-left", "0.001", "--k-right", "0.001", "--runs", "1000",
                        "--partitions", "50"]) == 0
    text = capsys.readouterr().out
    for label in ("mean x (m)", "std θ (rad)", "corr xy", "theory", "simulation", "± s.e.",
                  "mean NEES", "covariance LR", "verdict: consistent"):
        assert label in text
    assert "-0.38357" in text  # the theory column


def test_gyro_and_compass_models(capsys):
    gyro = _json(capsys, ["simulate", "--model", "gyro", "--speed-noise", "1e-4", "--gyro-noise",
                          "1e-6", "--segment", "arc:0.5,0.1,20", "--runs", "2000",
                          "--partitions", "100"])
    assert gyro["verdict"] == "consistent"
    compass = _json(capsys, ["simulate", "--model", "compass", "--speed-noise", "1e-4",
                             "--heading-noise", "1e-6", "--segment", "arc:0.5,0.1,20",
                             "--runs", "2000", "--partitions", "100"])
    # the compass θ variance is one reading's σ_θθ/T (T = 0.1 s by default): all three checked
    assert compass["theory"]["std"][2] == pytest.approx(math.sqrt(1e-6 / 0.1), rel=1e-12)
    assert compass["checks"]["components"] == ["x", "y", "theta"]
    assert compass["verdict"] == "consistent"


def test_systematic_errors_option(capsys):
    """A 4 m straight line driven by a robot with E_d = 1.01 curves: the simulation
    (zero noise) ends off the nominal pose, and the verdict says the prediction misses."""
    out = _json(capsys, ["simulate", "--wheel-base", "0.34", "--k-left", "0", "--k-right", "0",
                         "--segment", "straight:4", "--systematic", "1.01,1,1", "--runs", "4",
                         "--partitions", "10"])
    dtheta = 4.0 * 2 * (1.01 - 1) / 2.01 / 0.34  # (d_R − d_L)/b with eq. 4.29–4.30
    assert out["simulation"]["mean"][2] == pytest.approx(dtheta, rel=1e-12)
    assert out["verdict"].startswith("linear model breaks down")


@pytest.mark.parametrize("args, message", [
    (["--k-left", "0.001", "--k-right", "0.001", "--runs", "0"], "runs"),
    (["--k-left", "0.001", "--k-right", "0.001", "--gyro-noise", "1"], "--gyro-noise"),
    (["--k-left", "0.001", "--k-right", "0.001", "--systematic", "1,1"], "--systematic"),
    (["--k-left", "0.001", "--k-right", "0.001", "--systematic", "1,0,1"], "E_b"),
    (["--k-left", "0.001", "--k-right", "0.001", "--alpha", "2"], "--alpha"),
    (["--k-left", "0.001", "--k-right", "0.001", "--initial-cov-matrix", "1,0,0;0,1,0;0,0,-1"],
     "initial covariance"),
    (["--k-left", "-1", "--k-right", "0.001"], "--k-left"),
])
def test_user_errors_exit_2_with_one_line(capsys, args, message):
    assert main(BASE + args) == 2
    err = capsys.readouterr().err
    assert err.startswith("odomkit: error:") and message in err
    assert err.count("\n") == 1
