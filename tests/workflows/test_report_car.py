"""``odomkit report`` on a car against GPS (a real car's user study, finding 7).

A simulated car (L = 2.7 m, speed and road-wheel steering, 1 Hz GPS with 1 m noise) whose
steering offset changes at the middle of the drive (0.002 rad, then 0.008 rad), so that the
report's calibration does not hold along the drive and says so. The report must then point
to what the user can do from ``report`` (which has no ``--fit-steering-cubic``: that is
``odomkit calibrate``'s), and not at all where the robot file has a steering_cubic already;
and its fitted-noise table must show the robot file's ``[truth]`` noise in its "robot file"
column, read here from the file written by the test.
"""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

L = 2.7
#: The truth noise the robot files below give in their [truth] table [m].
FILE_TRUTH_SIGMA = 0.7


def drive(folder: Path, simulate) -> tuple[Path, Path]:
    """``car.csv`` (t, speed, steer) and ``gps.csv`` (t, x, y) of the shared simulated car
    (tests/conftest.py): the steering measured 0.002 rad off the road wheel's angle in the
    first half, 0.008 rad in the second."""
    found, fixes, _ = simulate((0.002, 0.008))
    log, gps = folder / "car.csv", folder / "gps.csv"
    np.savetxt(log, np.column_stack((found.t, found.channels["speed"], found.channels["steer"])),
               delimiter=",", header="t,speed,steer", comments="")
    np.savetxt(gps, np.column_stack((fixes.t, fixes.xy)), delimiter=",", header="t,x,y", comments="")
    return log, gps


def robot(folder: Path, name: str, extra: str = "") -> Path:
    path = folder / name
    path.write_text(f'[robot]\ntype = "car"\nwheel_base = {L}\n{extra}'
                    '[noise]\nsigma_speed = 0.1\nsigma_steer = 0.002\n\n'
                    f'[truth]\nsigma = {FILE_TRUTH_SIGMA}\n')
    return path


class Cells(HTMLParser):
    """The keyed numbers of a report page (``data-key`` -> ``data-value``)."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.cells: dict[str, float] = {}
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "td" and a.get("data-key") and a.get("data-value") is not None:
            self.cells[a["data-key"]] = float(a["data-value"])


@pytest.fixture(scope="module")
def car(tmp_path_factory, car_gps_drive):
    folder = tmp_path_factory.mktemp("car")
    return folder, *drive(folder, car_gps_drive)


def _report(run_cli, folder: Path, log: Path, gps: Path, robot_path: Path, name: str):
    out = folder / name
    code, stdout, err = run_cli("report", log, "--robot", robot_path, "--truth", gps, "--out", out, "--json")
    assert code == 0, err
    return json.loads(stdout)["warnings"], Cells(out.read_text(encoding="utf-8")).cells


def test_a_car_without_a_cubic_is_pointed_to_calibrate_not_to_a_flag_report_lacks(run_cli, car):
    folder, log, gps = car
    said, _ = _report(run_cli, folder, log, gps, robot(folder, "car.toml"), "plain.html")
    halves = [w for w in said if "does not hold along this drive" in w]
    assert halves, said
    # report has no --fit-steering-cubic: the hint names the command that has it
    assert "odomkit calibrate" in halves[0] and "--fit-steering-cubic" in halves[0]
    assert "try --fit-steering-cubic" not in halves[0]
    import inspect

    from odomkit.cli.report import report

    assert "fit_steering_cubic" not in inspect.signature(report).parameters


def test_a_car_with_a_cubic_gets_no_cubic_hint(run_cli, car):
    folder, log, gps = car
    said, _ = _report(run_cli, folder, log, gps, robot(folder, "cubic.toml", "steering_cubic = 5.0\n"),
                      "cubic.html")
    assert not any("fit-steering-cubic" in w for w in said), said


def test_the_noise_table_shows_the_robot_files_truth_noise(run_cli, car):
    folder, log, gps = car
    _, cells = _report(run_cli, folder, log, gps, robot(folder, "truth.toml"), "truth.html")
    assert "noise.fitted.truth_sigma" in cells  # the report fitted the truth's noise
    assert cells["noise.file.truth_sigma"] == FILE_TRUTH_SIGMA
