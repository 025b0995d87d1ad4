"""`odomkit umbmark ERRORS.csv ...`: JSON contract, text output, and one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import odomkit.workflows.umbmark as umbmark_workflow
from odomkit.cli import main

HAND_CSV = """direction,x,y
cw,-0.30,-0.32
cw,-0.34,-0.28
ccw,0.05,0.21
ccw,0.07,0.19
"""


def write(tmp_path: Path, text: str, name: str = "errors.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def run_json(capsys, *args: str) -> dict:
    assert main(["umbmark", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_contract_and_hand_values(tmp_path, capsys) -> None:
    out = run_json(capsys, str(write(tmp_path, HAND_CSV)), "--side", "4", "--wheel-base", "0.34")
    for key in ("cg", "e_max_syst", "alpha", "beta", "radius", "E_d", "E_b", "c_left",
                "c_right", "wheel_base", "second_compensation_advised", "alpha_x", "alpha_y",
                "sem", "chong_kleeman"):
        assert key in out
    assert out["cg"]["cw"] == pytest.approx([-0.32, -0.30], abs=1e-15)
    assert out["cg"]["ccw"] == pytest.approx([0.06, 0.20], abs=1e-15)
    assert out["e_max_syst"] == pytest.approx(math.sqrt(0.1924), rel=1e-14)
    # α = mean((−0.26)/−16, (−0.50)/−16), β = mean((−0.38)/−16, (−0.10)/−16).
    alpha, beta = 0.02375, 0.015
    assert out["alpha"] == pytest.approx(alpha, abs=1e-15)
    assert out["beta"] == pytest.approx(beta, abs=1e-15)
    R = 2.0 / math.sin(beta / 2)
    assert out["radius"] == pytest.approx(R, rel=1e-12)
    E_d = (R + 0.17) / (R - 0.17)
    assert out["E_d"] == pytest.approx(E_d, rel=1e-12)
    E_b = 90 / (90 - math.degrees(alpha))
    assert out["E_b"] == pytest.approx(E_b, rel=1e-12)
    assert out["wheel_base"] == pytest.approx(0.34 * E_b, rel=1e-12)
    assert out["c_left"] == pytest.approx(2 / (E_d + 1), rel=1e-12)
    assert out["c_right"] == pytest.approx(2 / (1 / E_d + 1), rel=1e-12)
    assert out["second_compensation_advised"] is True
    assert out["chong_kleeman"]["c_b"] == pytest.approx(math.pi / (math.pi - alpha), rel=1e-12)


def test_radius_null_when_beta_zero_and_header_order_free(tmp_path, capsys) -> None:
    # Pure Type A: CW (−a, −a), CCW (−a, +a); columns reordered, extra column, CRLF, caps.
    text = ("run,y,direction,x\r\n1,-0.1,CW,-0.1\r\n2,-0.1,cw,-0.1\r\n"
            "3,0.1,CCW,-0.1\r\n4,0.1,ccw,-0.1\r\n")
    out = run_json(capsys, str(write(tmp_path, text)), "--side", "4", "--wheel-base", "0.34")
    assert out["radius"] is None
    assert out["beta"] == 0.0 and out["E_d"] == 1.0 and out["c_left"] == 1.0
    assert out["alpha"] == pytest.approx(0.0125)


def test_wheel_base_from_robot_file(tmp_path, capsys) -> None:
    robot = write(tmp_path, '[robot]\ntype = "diff"\nwheel_base = 0.3\nm_per_tick = 1.0\n'
                  "c_wheel_base = 1.1\n", "robot.toml")
    csv = str(write(tmp_path, HAND_CSV))
    a = run_json(capsys, csv, "--side", "4", "--robot", str(robot))
    b = run_json(capsys, csv, "--side", "4", "--wheel-base", str(0.3 * 1.1))
    assert a["wheel_base_nominal"] == pytest.approx(0.33)
    assert a["E_d"] == pytest.approx(b["E_d"], rel=1e-14)


def test_text_output(tmp_path, capsys) -> None:
    assert main(["umbmark", str(write(tmp_path, HAND_CSV)), "--side", "4",
                 "--wheel-base", "0.34"]) == 0
    text = capsys.readouterr().out
    assert "E_max,syst" in text and f"{math.sqrt(0.1924) * 1000:9.2f} mm" in text


@pytest.mark.parametrize("text, needle", [
    ("dir,x,y\ncw,0,0\n", "lacks column(s) direction"),
    ("direction,x\ncw,0\n", "lacks column(s) y"),
    ("", "empty file"),
    (HAND_CSV + "left,0.1,0.1\n", "line 6: field 'direction' must be 'cw' or 'ccw'"),
    (HAND_CSV + "cw,abc,0.1\n", "line 6: field 'x' must be a finite number"),
    (HAND_CSV + "cw,0.1,nan\n", "line 6: field 'y' must be a finite number"),
    (HAND_CSV + "cw,inf,0.1\n", "line 6: field 'x'"),
    (HAND_CSV + "cw,0.1\n", "line 6: expected 3 fields"),
    ("direction,x,y\ncw,0,0\ncw,0,0\n", "0 ccw run(s)"),
    ("direction,x,y\ncw,0,0\ncw,0,0\nccw,0,0\n", "1 ccw run(s); UMBmark needs at least 2"),
])
def test_bad_csv_one_line_error(tmp_path, capsys, text, needle) -> None:
    p = write(tmp_path, text)
    assert main(["umbmark", str(p), "--side", "4", "--wheel-base", "0.34"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("odomkit: error: ")
    assert str(p) in err and needle in err


@pytest.mark.parametrize("args, needle", [
    (["missing.csv", "--side", "4", "--wheel-base", "0.34"], "missing.csv: file not found"),
    (["CSV", "--side", "0", "--wheel-base", "0.34"], "--side must be a positive"),
    (["CSV", "--side", "-4", "--wheel-base", "0.34"], "--side must be a positive"),
    (["CSV", "--side", "nan", "--wheel-base", "0.34"], "--side must be a positive"),
    (["CSV", "--side", "4", "--wheel-base", "-1"], "--wheel-base must be a positive"),
    (["CSV", "--side", "4"], "--wheel-base (or --robot ROBOT.toml) is required"),
    (["--side", "4", "--wheel-base", "0.34"], "give exactly one ERRORS.csv"),
    (["CSV", "--wheel-base", "0.34"], "--side must be a positive length in metres, got nan"),
    (["--runs", "a.csv", "--side", "0.75"], "--runs needs --robot"),
])
def test_bad_arguments_exit_2(tmp_path, capsys, args, needle) -> None:
    csv = str(write(tmp_path, HAND_CSV))
    args = [csv if a == "CSV" else a for a in args]
    assert main(["umbmark", *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err


def test_runs_form_passes_every_run_to_the_workflow(tmp_path, capsys, monkeypatch) -> None:
    calls = []

    class Fake:
        def to_dict(self):
            return {"e_max_syst": 0.5}

    def fake(runs, robot, side, log_options, **_):  # plot, overwrite: not asked here
        calls.append((runs, robot, side, log_options))
        return Fake()

    monkeypatch.setattr(umbmark_workflow, "umbmark_from_files", fake)
    assert main(["umbmark", "--runs", "a.csv", "b.csv", "--runs", "c.csv", "--robot", "r.toml",
                 "--side", "0.75", "--decimate", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {"e_max_syst": 0.5}
    (runs, robot, side, options), = calls
    assert sorted(p.name for p in runs) == ["a.csv", "b.csv", "c.csv"]
    assert robot.name == "r.toml" and side == 0.75 and options.decimate == 2
