"""``odomkit calibrate --truth GPS.csv --plot``: position-only truth on its own clock.

The figure used to start every run from the truth's pose at the log's first row; a truth
without heading (GPS) has none to give, so every run was left out and two empty panels were
written with "wrote plot". Here a car is simulated against a 1 Hz GPS with 1 m noise on a
clock 0.3 s late, so the true path is known, and the figure's data (not its pixels) is
checked against it and against the calibration's own fit.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

LAG, SIGMA, START = 0.3, 1.0, (100.0, -50.0, 0.7)


def _drive(folder: Path, seed: int = 3, n: int = 3000, dt: float = 0.1):
    """A car log (t, speed, steer) read with a nominal robot file whose speed scale, steering
    offset and wheel base are off, the true positions at every log row, and a GPS file
    (t, x, y): a fix a second, σ = 1 m, stamped ``LAG`` late."""
    from odomkit.io.robotfile import read_robot
    from odomkit.log import OdometryLog
    from odomkit.track import dead_reckon_log

    robot_file = folder / "car.toml"
    robot_file.write_text('[robot]\ntype = "car"\nwheel_base = 2.7\n')
    nominal, _ = read_robot(robot_file)
    true_car = replace(nominal, wheel_base=2.75, steering_offset=0.01, c_scale=1.02)
    rng = np.random.default_rng(seed)
    t = dt * np.arange(n)
    knots = rng.uniform(-0.25, 0.25, n // 100 + 2)
    steer = np.interp(t, np.arange(knots.size) * 100 * dt, knots)
    speed = 8.0 + 2.0 * np.sin(t / 37.0)
    log = OdometryLog(t, {"speed": speed, "steer": steer}, source="car")
    true = dead_reckon_log(log, true_car, pose0=START).poses
    log_file = folder / "car.csv"
    np.savetxt(log_file, np.column_stack([t, speed, steer]), delimiter=",", header="t,speed,steer",
               comments="", fmt="%.10g")
    stamps = np.arange(LAG, t[-1] + LAG, 1.0)  # the fix stamped s is the car at log time s - LAG
    xy = np.column_stack([np.interp(stamps - LAG, t, true[:, 0]), np.interp(stamps - LAG, t, true[:, 1])])
    gps = folder / "gps.csv"
    np.savetxt(gps, np.column_stack([stamps, xy + rng.normal(0, SIGMA, xy.shape)]), delimiter=",",
               header="t,x,y", comments="", fmt="%.6f")
    return robot_file, log_file, gps, t, true


@pytest.fixture()
def saved_figures(monkeypatch):
    """Every figure written, kept for its data (the file is still written)."""
    import odomkit.plot

    kept = []
    original = odomkit.plot.save_figure

    def keep(fig, path):
        kept.append(fig)
        return original(fig, path)

    monkeypatch.setattr(odomkit.plot, "save_figure", keep)
    return kept


def _title(ax):
    return " ".join(ax.get_title(loc=loc) for loc in ("left", "center", "right"))


def _panel(fig, name):
    """The panel of the figure's mosaic named ``name``."""
    found = [ax for ax in fig.axes if ax.get_label() == name]
    assert len(found) == 1, [ax.get_label() for ax in fig.axes]
    return found[0]


def _lines(ax):
    return {line.get_label(): np.asarray(line.get_xydata(), dtype=float) for line in ax.get_lines()}


@pytest.mark.parametrize("clock", ["fitted", "given"])
def test_gps_truth_draws_the_fixes_both_tracks_and_their_errors(run_cli, tmp_path, saved_figures, clock):
    robot, log, gps, t, true = _drive(tmp_path)
    target = tmp_path / "cal.png"
    given = ["--truth-time-offset", str(LAG)] if clock == "given" else []
    code, out, err = run_cli("calibrate", log, "--robot", robot, "--truth", gps, *given, "--plot", target,
                             "--json")
    assert code == 0, err
    result = json.loads(out)
    assert result["outputs"]["plot"] == str(target) and target.read_bytes().startswith(b"\x89PNG")
    offset = result["truth_time_offset"]["value"]
    assert offset == pytest.approx(LAG, abs=0.1)

    (fig,) = saved_figures
    before, after = _panel(fig, "before"), _panel(fig, "after")
    assert "robot file's" in _title(before) and "calibrated" in _title(after)
    # The fixes the calibration compared: stamps inside the log (2 s inside it when the
    # clock offset is fitted), each the car at log time stamp - offset.
    stamps = np.loadtxt(gps, delimiter=",", skiprows=1)[:, 0]
    margin = 2.0 if clock == "fitted" else 0.0
    own = stamps if clock == "fitted" else stamps - offset
    n_fixes = int(np.count_nonzero((own >= t[0] + margin) & (own <= t[-1] - margin)))
    tracks = {}
    for name, ax in (("before", before), ("after", after)):
        lines = _lines(ax)
        assert set(lines) == {"car", "truth fixes"}
        assert lines["truth fixes"].shape == (n_fixes, 2) and np.all(np.isfinite(lines["truth fixes"]))
        assert lines["car"].shape == (t.size, 2) and np.all(np.isfinite(lines["car"]))
        tracks[name] = lines["car"]
    # Against the true path (known here): the calibrated track well within the GPS's σ, the
    # nominal one (2 % short, steering 0.01 rad off) more than ten metres away.
    rms = {k: float(np.sqrt(np.mean(np.sum((v - true[:, :2]) ** 2, axis=1)))) for k, v in tracks.items()}
    assert rms["after"] < 0.5 and rms["before"] > 10.0, rms
    # Each track starts where calibrate fitted it: the calibrated one at the start pose the
    # calibration printed (4 significant digits), from its own least squares.
    note = next(n for n in result["notes"] if "start pose fitted at" in n)
    x0, y0 = (float(v) for v in re.findall(r"\(([-\d.e+]+) m, ([-\d.e+]+) m", note)[0])
    assert tracks["after"][0] == pytest.approx([x0, y0], rel=1e-3, abs=1e-3)
    # The error panel: each track's distance from every fix compared; the calibrated one's
    # RMS is √2 × the calibration's residual RMS per coordinate (its last horizon's note).
    errors = _lines(_panel(fig, "error"))
    assert len(errors) == 2
    assert all(v.shape == (n_fixes, 2) and np.all(np.isfinite(v)) for v in errors.values())
    (calibrated,) = (v for k, v in errors.items() if "calibrated" in k)
    per_axis = float(re.findall(r"horizon 1 of each run: \d+ fixes, residual rms ([\d.e+-]+) m",
                                " ".join(result["notes"]))[0])
    assert np.sqrt(np.mean(calibrated[:, 1] ** 2)) == pytest.approx(np.sqrt(2) * per_axis, rel=2e-3)
    assert not [ax for ax in fig.axes if "heading" in _title(ax) or "θ" in ax.get_ylabel()]


def test_a_plot_with_nothing_to_draw_is_not_written_and_says_why(tmp_path):
    """No fix inside the log's span: a warning, no file, no path returned."""
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.calibration import _calibration_plot
    from odomkit.workflows.logs import LogOptions, load_log
    from odomkit.workflows.truth import TruthOptions

    robot_file, log_file, gps, _, _ = _drive(tmp_path, n=600)
    late = tmp_path / "late.csv"
    rows = np.loadtxt(gps, delimiter=",", skiprows=1)
    rows[:, 0] += 1000.0
    np.savetxt(late, rows, delimiter=",", header="t,x,y", comments="")
    robot, _ = read_robot(robot_file)
    log = load_log(log_file, robot, LogOptions())
    target = tmp_path / "empty.png"
    with pytest.warns(UserWarning, match=r"--plot .*empty\.png not written: .*fewer than 2 truth fixes"):
        drawn = _calibration_plot(target, [log], [TruthOptions(path=late)], robot, robot, None)
    assert drawn is None and not target.exists()
