"""``odomkit report`` on a simulated differential drive against position-only truth (user
study 30's findings on real data: an F1TENTH car, a LEGO robot, a UWB-tracked robot logged in
m/s).

* The robot file's ``[truth] time_offset`` is the truth's clock for every step, the
  calibration's too: a truth 1000 s off the log's clock, its offset in the robot file, was
  calibrated from a clock offset of 0 and the calibration left out.
* Before and after calibration are compared on one footing the page names: besides the ATE
  from the truth's first fix (``odomkit evaluate``'s), the ATE with each track moved rigidly
  onto the truth (``evaluate --align se2``). A first fix several cm off the robot's start
  pose made the calibrated track's ATE from it larger than the uncalibrated one's on a real
  robot, though the calibration was right.
* ``--wheel-radius`` gives the controller snippet a robot file in metres per tick (wheel
  speeds: ``m_per_tick = 1``) cannot, as ``calibrate --ros-yaml --wheel-radius`` does.

Every number is checked against the command that owns it, run through the CLI.
"""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

COLUMNS = ("--columns", "t=t,dist_left=L,dist_right=R")
B = 0.4  # the true wheel base [m]
FIX_NOISE = 0.002  # the fixes' white noise [m per axis]


def _drive(folder: Path, *, seconds: float = 30.0, clock: float = 0.0, first_off=(0.0, 0.0),
           robot_extra: str = "", robot_geometry: str = "wheel_base = 0.41\nm_per_tick = 1\n") -> Path:
    """``log.csv`` (t, L, R wheel travel per row [m]; the left wheel reads 1 % long), ``xy.csv``
    (the true positions with :data:`FIX_NOISE`, stamped ``clock`` s late, the first fix moved
    by ``first_off`` [m]) and ``robot.toml`` (wheel base 0.41 m against the true 0.4 m, then
    ``robot_extra``); returns the folder."""
    from odomkit.integrate import dead_reckon

    rng = np.random.default_rng(4)
    dt = 0.1
    t = np.arange(0.0, seconds + dt / 2, dt)
    w = 0.4 * np.sin(0.25 * t) + 0.1
    dl, dr = (0.3 - w * B / 2) * dt, (0.3 + w * B / 2) * dt
    dl[0] = dr[0] = 0.0
    truth = dead_reckon((dl[1:] + dr[1:]) / 2, (dr[1:] - dl[1:]) / B, (1.0, 2.0, 0.5), "exact")
    np.savetxt(folder / "log.csv", np.column_stack((t, 1.01 * dl, dr)), delimiter=",", header="t,L,R",
               comments="")
    xy = truth[:, :2] + FIX_NOISE * rng.standard_normal((t.size, 2))
    xy[0] += first_off
    np.savetxt(folder / "xy.csv", np.column_stack((t + clock, xy)), delimiter=",", header="t,x,y",
               comments="")
    (folder / "robot.toml").write_text(f'[robot]\ntype = "diff"\n{robot_geometry}'
                                       f"[noise]\nk_left = 0.001\nk_right = 0.001\n{robot_extra}")
    return folder


class Page(HTMLParser):
    """The keyed numbers (``data-key`` -> ``data-value``), the text and the code blocks."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.cells: dict[str, float] = {}
        self.text: list[str] = []
        self.code: list[str] = []
        self._pre = False
        self.html = text
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "td" and a.get("data-key") and a.get("data-value") is not None:
            self.cells[a["data-key"]] = float(a["data-value"])
        if tag == "pre":
            self._pre = True
            self.code.append("")

    def handle_endtag(self, tag):
        if tag == "pre":
            self._pre = False

    def handle_data(self, data):
        self.text.append(data)
        if self._pre:
            self.code[-1] += data

    @property
    def words(self) -> str:
        return " ".join(" ".join(self.text).split())


def _report(run_cli, folder: Path, *flags, name: str = "r.html") -> tuple[dict, Page]:
    out = folder / name
    code, stdout, err = run_cli("report", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
                                "--truth", folder / "xy.csv", *flags, "--out", out, "--json")
    assert code == 0, err
    return json.loads(stdout), Page(out.read_text(encoding="utf-8"))


def _json(run_cli, *args) -> dict:
    code, stdout, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(stdout)


# ------------------------------------------------------------------------- the robot file's clock
@pytest.fixture(scope="module")
def late_clock(tmp_path_factory):
    """The report of a truth stamped 1000 s late, the offset in the robot file's [truth]."""
    from odomkit.cli import main

    folder = _drive(tmp_path_factory.mktemp("clock"), clock=1000.0,
                    robot_extra="[truth]\ntime_offset = 1000.0\n")
    import contextlib
    import io

    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        assert main(["report", str(folder / "log.csv"), *COLUMNS, "--robot", str(folder / "robot.toml"),
                     "--truth", str(folder / "xy.csv"), "--out", str(folder / "r.html"), "--json"]) == 0
    return folder, json.loads(stdout.getvalue()), Page((folder / "r.html").read_text(encoding="utf-8"))


def test_the_calibration_takes_the_truths_clock_from_the_robot_file(late_clock, run_cli):
    folder, result, page = late_clock
    assert not any("calibration left out" in w for w in result["warnings"]), result["warnings"]
    # What calibrate fits with the offset given as a flag, which a user study found to work.
    cal = _json(run_cli, "calibrate", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
                "--truth", folder / "xy.csv", "--truth-time-offset", "1000")
    assert cal["parameters"], cal
    for name, value in cal["parameters"].items():
        assert page.cells[f"calibration.{name}"] == pytest.approx(value, rel=1e-9), name
    # The simulated robot: the left wheel reads 1 % long, the file's wheel base is 0.41 m for 0.4 m.
    assert page.cells["calibration.c_left"] == pytest.approx(1 / 1.01, rel=2e-3)
    assert page.cells["calibration.c_wheel_base"] == pytest.approx(0.4 / 0.41, rel=2e-3)
    # The page says where the clock came from: held at the robot file's, not fitted.
    assert page.cells["calibration.truth_time_offset"] == 1000.0
    assert "held at the robot file's [truth] time_offset" in page.words


def test_the_scores_before_and_after_are_evaluates_on_that_clock(late_clock, run_cli, tmp_path):
    folder, _, page = late_clock
    before = _json(run_cli, "evaluate", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
                   "--truth", folder / "xy.csv", "--window", "10s")
    assert page.cells["before.ate_rmse"] == pytest.approx(before["ate_rmse"], rel=1e-9)
    calibrated = tmp_path / "cal.toml"
    _json(run_cli, "calibrate", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
          "--truth", folder / "xy.csv", "--truth-time-offset", "1000", "--out-robot", calibrated)
    after = _json(run_cli, "evaluate", folder / "log.csv", *COLUMNS, "--robot", calibrated,
                  "--truth", folder / "xy.csv", "--window", "10s")
    assert page.cells["after.ate_rmse"] == pytest.approx(after["ate_rmse"], rel=1e-9)
    assert after["ate_rmse"] < before["ate_rmse"]


# ------------------------------------------------------------------- before and after, one footing
@pytest.fixture(scope="module")
def first_fix_off(tmp_path_factory):
    """The report of a drive whose first fix is 6.4 cm off the robot's start, and the folder."""
    folder = _drive(tmp_path_factory.mktemp("footing"), first_off=(0.05, -0.04))
    return folder


def test_before_and_after_are_also_compared_aligned_as_evaluate_align_se2(first_fix_off, run_cli, tmp_path):
    folder = first_fix_off
    _, page = _report(run_cli, folder)
    calibrated = tmp_path / "cal.toml"
    _json(run_cli, "calibrate", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
          "--truth", folder / "xy.csv", "--out-robot", calibrated)
    for robot, key in ((folder / "robot.toml", "before"), (calibrated, "after")):
        aligned = _json(run_cli, "evaluate", folder / "log.csv", *COLUMNS, "--robot", robot, "--truth",
                        folder / "xy.csv", "--align", "se2")
        assert page.cells[f"{key}.aligned.ate_rmse"] == pytest.approx(aligned["ate_rmse"], rel=1e-9), key
        # the summary repeats it (one key is one number: tests/workflows/test_report.py's Page)
        assert page.html.count(f'data-key="{key}.aligned.ate_rmse"') == 2, key
    before, after = page.cells["before.aligned.ate_rmse"], page.cells["after.aligned.ate_rmse"]
    # The calibration is right (c_left 1/1.01, wheel base 0.4 m): aligned, what is left of the
    # calibrated track's error is the fixes' own white noise, √2·σ RMS in the plane.
    assert after < 2 * np.sqrt(2) * FIX_NOISE
    assert after < before / 5
    # The first fix is off: from it, the calibrated track's ATE is ten times its aligned one.
    assert page.cells["after.ate_rmse"] > 10 * after
    # The page says which footing each row stands on, and what flatters which.
    words = page.words
    for said in ("moved rigidly onto the truth", "odomkit evaluate --align se2",
                 "from the truth at the first usable row", "its own start pose"):
        assert said in words, said


def test_the_aligned_ate_is_umeyamas_by_hand(first_fix_off, run_cli, tmp_path):
    """The aligned ATE before calibration, by hand: the track ``odomkit track`` writes from
    the truth's start, moved by the rotation and translation that minimise the squared
    position errors (found here by a generic minimiser, not by Umeyama's closed form)."""
    from scipy.optimize import minimize

    folder = first_fix_off
    _, page = _report(run_cli, folder, name="again.html")
    track = tmp_path / "track.csv"
    _json(run_cli, "track", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml", "--truth",
          folder / "xy.csv", "--out", track)
    rows = np.genfromtxt(track, delimiter=",", names=True)
    fixes = np.loadtxt(folder / "xy.csv", delimiter=",", skiprows=1)
    ref = np.column_stack([np.interp(rows["t"], fixes[:, 0], fixes[:, k]) for k in (1, 2)])
    est = np.column_stack((rows["x"], rows["y"]))

    def rms(p):
        c, s = np.cos(p[0]), np.sin(p[0])
        moved = est @ np.array([[c, -s], [s, c]]).T + p[1:]
        return np.sqrt(np.mean(np.sum((moved - ref) ** 2, axis=1)))

    best = minimize(rms, np.zeros(3), method="Nelder-Mead",
                    options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000}).fun
    assert page.cells["before.aligned.ate_rmse"] == pytest.approx(best, rel=1e-4)


# ----------------------------------------------------------------------------------- --wheel-radius
@pytest.fixture(scope="module")
def per_tick(tmp_path_factory):
    """A drive logged as wheel travel in metres (``m_per_tick = 1``: no wheel size)."""
    return _drive(tmp_path_factory.mktemp("radius"))


def _yaml_numbers(text: str) -> dict[str, float]:
    return {k: float(v) for k, v in re.findall(r"^\s*(\w+):\s*([-+0-9.eE]+)\s*$", text, re.MULTILINE)}


def test_wheel_radius_gives_the_controller_snippet_calibrate_writes(per_tick, run_cli, tmp_path):
    folder = per_tick
    result, page = _report(run_cli, folder, "--wheel-radius", "0.035", name="radius.html")
    snippets = [c for c in page.code if "diff_drive_controller:" in c]
    assert len(snippets) == 1, page.code
    assert not any("no controller snippet" in n for n in page.text)
    code, _, err = run_cli("calibrate", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
                           "--truth", folder / "xy.csv", "--ros-yaml", tmp_path / "ros.yaml",
                           "--wheel-radius", "0.035")
    assert code == 0, err
    want = _yaml_numbers((tmp_path / "ros.yaml").read_text(encoding="utf-8"))
    got = _yaml_numbers(snippets[0])
    for key in ("wheel_separation", "wheel_radius", "wheel_separation_multiplier",
                "left_wheel_radius_multiplier", "right_wheel_radius_multiplier"):
        assert got[key] == pytest.approx(want[key], rel=1e-9), key
    assert got["wheel_radius"] == 0.035
    # The simulated robot: its left wheel reads 1 % long, so its multiplier is 1/1.01.
    assert got["left_wheel_radius_multiplier"] == pytest.approx(1 / 1.01, rel=2e-3)


def test_without_wheel_radius_the_note_names_the_flag(per_tick, run_cli):
    result, page = _report(run_cli, per_tick, name="none.html")
    assert not [c for c in page.code if "diff_drive_controller:" in c]
    note = [n for n in page.text if "no controller snippet" in n]
    assert note and "--wheel-radius" in note[0], page.text


@pytest.mark.parametrize(("geometry", "radius", "says"), [
    ("wheel_base = 0.41\nwheel_radius = 0.05\nencoder_resolution = 1000\n", "0.035",
     "--wheel-radius 0.035 m conflicts with the robot file's wheel size (radius 0.05 m)"),
    ("wheel_base = 0.41\nm_per_tick = 1\n", "-0.035", "--wheel-radius must be a positive number of metres"),
    ("wheel_base = 0.41\nm_per_tick = 1\n", "nan", "--wheel-radius must be a positive number of metres"),
])
def test_a_bad_wheel_radius_is_one_line_before_any_work(run_cli, tmp_path, geometry, radius, says):
    folder = _drive(tmp_path, robot_geometry=geometry)
    code, _, err = run_cli("report", folder / "log.csv", *COLUMNS, "--robot", folder / "robot.toml",
                           "--truth", folder / "xy.csv", "--wheel-radius", radius,
                           "--out", tmp_path / "r.html")
    assert code == 2 and says in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "r.html").exists()


def test_a_wheel_radius_for_a_robot_no_controller_takes_is_refused(run_cli, tmp_path):
    folder = _drive(tmp_path)
    log = np.loadtxt(folder / "log.csv", delimiter=",", skiprows=1)
    speed = (log[1:, 1] + log[1:, 2]) / 2 / 0.1
    np.savetxt(folder / "uni.csv", np.column_stack((log[1:, 0], speed, np.zeros_like(speed))), delimiter=",",
               header="t,speed,yaw_rate", comments="")
    (folder / "uni.toml").write_text('[robot]\ntype = "unicycle"\n')
    code, _, err = run_cli("report", folder / "uni.csv", "--robot", folder / "uni.toml", "--wheel-radius",
                           "0.035", "--out", tmp_path / "r.html")
    assert code == 2 and "--wheel-radius" in err and "'unicycle'" in err, err
    assert len(err.strip().splitlines()) == 1, err
