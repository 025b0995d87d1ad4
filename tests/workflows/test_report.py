"""``odomkit report``: one self-contained HTML page whose numbers are the other commands'.

The page is read back with :mod:`html.parser` (not with the code that wrote it): every
reference must be embedded or a same-page anchor, every figure a decodable SVG, and every
number carried by a table cell (``data-key``/``data-value``) must equal what ``odomkit
evaluate --json`` (and, after calibration, ``odomkit calibrate`` then ``evaluate``) prints
for the same input, run through the CLI as a user would.
"""

from __future__ import annotations

import base64
import json
import re
import warnings
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.plot import have_matplotlib

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")
RUN2 = builtin_data_path("230620202042_run-02.csv")
COLUMNS = ("--columns", "t=t,ticks_left=ticks_left,ticks_right=ticks_right")

# Attributes through which a page makes the browser fetch something.
_FETCHING = {"src", "href", "xlink:href", "srcset", "poster", "data", "action", "formaction", "background",
             "ping", "manifest", "cite", "longdesc", "codebase", "archive", "icon", "lowsrc", "dynsrc"}


class Page(HTMLParser):
    """Everything of a report the tests look at."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.references: list[tuple[str, str, str]] = []  # (tag, attribute, value)
        self.tags: list[str] = []
        self.images: list[dict[str, str]] = []
        self.styles: list[str] = []
        self.cells: dict[str, tuple[float, str]] = {}
        self.rows: dict[str, float] = {}  # the first keyed number of a row, by the row's first cell
        self._label: str | None = None
        self.headings: list[tuple[str, str]] = []  # (id, text) of each h2
        self.text: list[str] = []
        self._open: tuple[str, dict[str, str]] | None = None
        self._style = False
        self.feed(text)
        self.close()

    def handle_starttag(self, tag, attrs):
        a = {k: v or "" for k, v in attrs}
        self.tags.append(tag)
        self.references += [(tag, k, v) for k, v in a.items() if k in _FETCHING]
        if tag == "img":
            self.images.append(a)
        if tag == "tr":
            self._label = None
        if tag in ("td", "h2"):
            self._open = (tag, a)
            self._buffer: list[str] = []
        self._style = tag == "style"
        if "style" in a:
            self.styles.append(a["style"])

    def handle_endtag(self, tag):
        if self._open and tag == self._open[0]:
            text = "".join(self._buffer)
            attrs = self._open[1]
            if tag == "td" and "data-key" in attrs and "data-value" in attrs:
                value = float(attrs["data-value"])
                # a key names one number: shown twice (the summary repeats some), it is the same
                assert self.cells.get(attrs["data-key"], (value,))[0] == value, attrs["data-key"]
                self.cells[attrs["data-key"]] = (value, text)
                if self._label is not None:
                    self.rows.setdefault(self._label, value)
            if tag == "td" and self._label is None:
                self._label = text
            if tag == "h2":
                self.headings.append((attrs.get("id", ""), text))
            self._open = None
        self._style = False

    def handle_data(self, data):
        self.text.append(data)
        if self._open:
            self._buffer.append(data)
        if self._style:
            self.styles.append(data)


def network_references(page: Page) -> list[str]:
    """Every reference that leaves the page: not a data: URI nor a #fragment."""
    bad = [f"<{tag} {attr}={value!r}>" for tag, attr, value in page.references
           if not (value.startswith("data:") or value.startswith("#"))]
    for css in page.styles:
        bad += [f"css {m}" for m in re.findall(r"url\(\s*['\"]?([^)'\"]*)", css) if not m.startswith("data:")]
        bad += [f"css @import {m}" for m in re.findall(r"@import\s+([^;]+)", css)]
    bad += [f"<{tag}>" for tag in page.tags if tag in ("script", "link", "iframe", "object", "embed", "base")]
    return bad


def test_the_reference_check_can_fail():
    page = Page('<html><head><link rel="stylesheet" href="https://cdn.example/x.css"><style>'
                'body{background:url(http://x/y.png)}</style></head><body><img src="http://a/b.png">'
                '<a href="#ok">ok</a><img src="data:image/png;base64,AAAA"><script>1</script></body></html>')
    found = network_references(page)
    assert len(found) == 5 and not any("#ok" in f or "AAAA" in f for f in found), found


def _run_json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out)


@pytest.fixture(scope="module")
def with_truth(tmp_path_factory):
    """The report of a built-in run with its own OptiTrack truth: (json, page, folder)."""
    from odomkit.cli import main

    folder = tmp_path_factory.mktemp("report")
    out = folder / "r.html"
    import contextlib
    import io

    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        assert main(["report", str(RUN), "--robot", str(ROBOT), "--out", str(out), "--json"]) == 0
    return json.loads(stdout.getvalue()), Page(out.read_text(encoding="utf-8")), folder


def test_json_names_the_file_and_the_sections(with_truth):
    result, page, folder = with_truth
    assert set(result) == {"report", "sections", "warnings"}
    assert Path(result["report"]) == folder / "r.html"
    assert result["sections"] == ["summary", "track", "errors", "honesty", "calibration", "noise", "ros"]
    assert [h[0] for h in page.headings] == result["sections"]


def test_the_page_needs_no_network(with_truth):
    _, page, _ = with_truth
    assert network_references(page) == []


@pytest.mark.skipif(not have_matplotlib(), reason="figures need matplotlib (the plot extra)")
def test_every_figure_is_an_embedded_svg(with_truth):
    _, page, _ = with_truth
    # track, covariance elements, error band, NEES + reliability, calibration, noise reliability
    assert len(page.images) >= 6
    for image in page.images:
        prefix = "data:image/svg+xml;base64,"
        assert image["src"].startswith(prefix) and image["alt"]
        svg = ET.fromstring(base64.b64decode(image["src"][len(prefix):]))
        assert svg.tag.endswith("svg") and float(svg.get("width", "0").rstrip("pt")) > 100
        assert len(list(svg.iter("{http://www.w3.org/2000/svg}path"))) > 20  # something is drawn


def _same(cells, expected: dict, prefix: str = "") -> int:
    """Compare the page's cells with evaluate's JSON; returns how many were compared."""
    n = 0
    for key in ("final_position_error", "max_position_error", "ate_rmse", "drift_percent",
                "nees_position_mean", "nees_position_median"):
        value, text = cells[prefix + key]
        assert value == pytest.approx(expected[key], rel=1e-12), key
        shown = text.split()[0]  # the value rounded to the digits shown
        digits = len(re.sub(r"\D", "", shown.split("e")[0]).lstrip("0"))
        assert shown == format(expected[key], f"#.{digits}g").rstrip("."), (key, text)
        n += 1
    for level, fraction in expected["coverage"].items():
        assert cells[f"{prefix}coverage.{level}"][0] == pytest.approx(fraction, abs=1e-12)
        n += 1
    for distance, rmse in expected["rpe"].items():
        assert cells[f"{prefix}rpe.{distance}"][0] == pytest.approx(rmse, rel=1e-12)
        n += 1
    return n


def test_numbers_are_odomkit_evaluates(with_truth, run_cli):
    _, page, _ = with_truth
    expected = _run_json(run_cli, "evaluate", RUN, "--robot", ROBOT, "--window", "10s")
    # each number in the row that says what it is
    for label, key in (("final position error", "final_position_error"),
                       ("largest position error", "max_position_error"),
                       ("ATE (RMSE of the position error)", "ate_rmse"),
                       ("drift (final error per distance)", "drift_percent"),
                       ("NEES mean (ideal 2)", "nees_position_mean"),
                       ("NEES median (ideal 1.39)", "nees_position_median")):
        assert page.rows[label] == pytest.approx(expected[key], rel=1e-12), label
    assert page.rows["RPE over 1 m (RMSE)"] == pytest.approx(expected["rpe"]["1"], rel=1e-12)
    assert page.rows["95%"] == pytest.approx(expected["coverage"]["0.95"], abs=1e-12)
    assert _same(page.cells, expected) == 11  # 6 metrics, 4 coverages, 1 RPE
    assert page.cells["windows"][0] == expected["windows"] > 3


#: What evaluate's NEES verdict words say of the mean against its bounds, on the page.
_SIDE = {"optimistic": "above its bounds", "pessimistic": "below its bounds",
         "consistent": "within its bounds"}


def _said(page: Page) -> str:
    return " ".join(" ".join(page.text).split())


def test_heading_numbers_and_verdicts_are_odomkit_evaluates(with_truth, run_cli):
    """Where the truth has a heading (the built-in run's OptiTrack), the honesty section scores
    it beside the position: its NEES mean, bounds and median, its coverage of the intervals,
    and both verdicts, all as ``odomkit evaluate --json`` gives them; the position's verdicts
    are evaluate's keys too, not the page's own reading of the bounds."""
    _, page, _ = with_truth
    expected = _run_json(run_cli, "evaluate", RUN, "--robot", ROBOT, "--window", "10s")
    assert expected["nees_heading_mean"] is not None  # the truth has a heading
    for label, key in (("heading NEES mean (ideal 1)", "nees_heading_mean"),
                       ("heading NEES median (ideal 0.455)", "nees_heading_median")):
        assert page.rows[label] == pytest.approx(expected[key], rel=1e-12), label
        assert page.cells[key][0] == pytest.approx(expected[key], rel=1e-12), key
    for level, fraction in expected["coverage_heading"].items():
        assert page.cells[f"coverage_heading.{level}"][0] == pytest.approx(fraction, abs=1e-12), level
    lo, hi = expected["nees_heading_bounds"]
    text = _said(page)
    assert f"{lo:.3g} … {hi:.3g}" in text
    for name, mean, nees_word, cover_word in (
            ("position", "nees_position_mean", "nees_verdict", "coverage_overall"),
            ("heading", "nees_heading_mean", "nees_heading_verdict", "coverage_heading_overall")):
        assert expected[nees_word] is not None and expected[cover_word] is not None
        assert (f"The mean {name} NEES {expected[mean]:.3g} is {_SIDE[expected[nees_word]]}" in text
                and f"({expected[nees_word]})" in text), name
        assert f"The {name} coverage is {expected[cover_word]}:" in text, name
    for key in ("verdict_note", "verdict_heading_note"):  # evaluate's notes, where it has them
        assert (expected[key] is None) or expected[key][:60] in text, key
    assert ("NEES and coverage disagree" in text) == (expected["verdict_note"] is not None
                                                      or expected["verdict_heading_note"] is not None)
    # A verdict from few window ends carries evaluate's caution (a page called a covariance
    # "honest here" from 4 ends: user study).
    from odomkit.workflows._scoring import FEW_WINDOW_ENDS

    assert 0 < expected["windows"] < FEW_WINDOW_ENDS
    assert f"But only {expected['windows']} window end(s): coverage moves in steps" in text


def test_a_position_only_truth_gets_no_heading_figures(run_cli, tmp_path):
    """Truth with positions alone (t,x,y from the built-in run's gt columns): the page scores
    the position (its verdicts evaluate's) and says nothing of a heading NEES or coverage."""
    data = np.loadtxt(RUN2, delimiter=",")
    log = tmp_path / "log.csv"
    np.savetxt(log, data[:, [0, 4, 5]], delimiter=",", header="t,ticks_left,ticks_right", comments="",
               fmt=["%.17g", "%d", "%d"])
    gt = tmp_path / "gt.csv"
    np.savetxt(gt, data[:, :3], delimiter=",", header="t,x,y", comments="")
    out = tmp_path / "r.html"
    _run_json(run_cli, "report", log, *COLUMNS, "--robot", ROBOT, "--truth", gt, "--out", out)
    page = Page(out.read_text(encoding="utf-8"))
    expected = _run_json(run_cli, "evaluate", log, *COLUMNS, "--robot", ROBOT, "--truth", gt,
                         "--window", "10s")
    assert expected["nees_heading_mean"] is None and expected["coverage_heading"] is None
    assert page.cells["nees_position_mean"][0] == pytest.approx(expected["nees_position_mean"], rel=1e-12)
    text = _said(page)
    assert f"The position coverage is {expected['coverage_overall']}:" in text
    assert not [key for key in page.cells if "heading" in key]
    for phrase in ("heading NEES", "heading coverage", "heading interval", "heading variance"):
        assert phrase not in text, phrase


def test_numbers_after_calibration_are_evaluate_on_the_calibrated_robot(with_truth, run_cli, tmp_path):
    _, page, _ = with_truth
    calibrated = tmp_path / "cal.toml"
    cal = _run_json(run_cli, "calibrate", RUN, "--robot", ROBOT, "--from", "trajectory",
                    "--out-robot", calibrated)
    for name, value in cal["parameters"].items():
        assert page.cells[f"calibration.{name}"][0] == pytest.approx(value, rel=1e-12)
    after = _run_json(run_cli, "evaluate", RUN, "--robot", calibrated, "--window", "10s")
    for key in ("final_position_error", "ate_rmse", "drift_percent"):
        assert page.cells[f"after.{key}"][0] == pytest.approx(after[key], rel=1e-9)
    assert after["ate_rmse"] < page.cells["before.ate_rmse"][0]


def test_fitted_noise_is_fit_noises(with_truth, run_cli, tmp_path):
    _, page, _ = with_truth
    calibrated = tmp_path / "cal.toml"
    _run_json(run_cli, "calibrate", RUN, "--robot", ROBOT, "--from", "trajectory", "--out-robot", calibrated)
    # The report fits one log, so white noise only (a bias needs runs to vary over).
    fit = _run_json(run_cli, "fit-noise", "--robot", calibrated, "--log", RUN, "--window", "10s",
                    "--kinds", "white", "--out", tmp_path / "fit.toml")
    for key, value in fit["parameters"].items():
        assert page.cells[f"noise.fitted.{key}"][0] == pytest.approx(value, rel=1e-9)
    fitted = _run_json(run_cli, "evaluate", RUN, "--robot", tmp_path / "fit.toml", "--window", "10s")
    assert page.cells["fitted.coverage.0.5"][0] == pytest.approx(fitted["coverage"]["0.5"], abs=1e-12)
    # the heading's beside it (the truth has one), as evaluate scores the fitted noise
    for level, fraction in fitted["coverage_heading"].items():
        assert page.cells[f"fitted.coverage_heading.{level}"][0] == pytest.approx(fraction, abs=1e-12)


def test_the_ros_snippets_are_there(with_truth):
    _, page, _ = with_truth
    text = "".join(page.text)
    for needle in ("diff_drive_controller:", "twist_covariance_diagonal", "amcl:", "alpha1:",
                   "covariance: ["):
        assert needle in text, needle


def test_a_truth_file_gives_the_same_numbers_as_evaluate(run_cli, tmp_path):
    """Truth from a file on its own clock (the log without gt_* columns), as evaluate takes it."""
    data = np.loadtxt(RUN2, delimiter=",")
    log = tmp_path / "log.csv"
    np.savetxt(log, data[:, [0, 4, 5]], delimiter=",", header="t,ticks_left,ticks_right", comments="",
               fmt=["%.17g", "%d", "%d"])
    gt = tmp_path / "gt.csv"
    np.savetxt(gt, np.column_stack([data[:, 0] - 0.02, data[:, 1:4]]), delimiter=",",
               header="t,x,y,theta", comments="")
    out = tmp_path / "r.html"
    result = _run_json(run_cli, "report", log, *COLUMNS, "--robot", ROBOT, "--truth", gt, "--out", out)
    page = Page(out.read_text(encoding="utf-8"))
    expected = _run_json(run_cli, "evaluate", log, *COLUMNS, "--robot", ROBOT, "--truth", gt,
                         "--window", "10s")
    assert _same(page.cells, expected) == 11
    assert "truth" not in result["sections"] and "honesty" in result["sections"]


def test_without_truth_the_report_says_what_truth_would_add(run_cli, tmp_path):
    data = np.loadtxt(RUN, delimiter=",")
    log = tmp_path / "no_truth.csv"
    np.savetxt(log, data[:, [0, 4, 5]], delimiter=",", header="t,ticks_left,ticks_right", comments="",
               fmt=["%.17g", "%d", "%d"])
    out = tmp_path / "r.html"
    result = _run_json(run_cli, "report", log, *COLUMNS, "--robot", ROBOT, "--out", out)
    assert result["sections"] == ["summary", "track", "truth", "ros"]
    page = Page(out.read_text(encoding="utf-8"))
    text = " ".join("".join(page.text).split())
    assert "This log has no ground truth" in text and "Run it again with --truth FILE." in text
    assert "the calibration of the wheel sizes and wheel base" in text  # a diff robot's
    assert network_references(page) == []
    track = _run_json(run_cli, "track", log, *COLUMNS, "--robot", ROBOT)
    assert page.cells["path_length"][0] == pytest.approx(track["path_length"], rel=1e-12)
    assert page.cells["final_sigma_theta"][0] == pytest.approx(np.sqrt(track["cov"][2][2]), rel=1e-12)
    if have_matplotlib():
        assert len(page.images) == 2  # the track and its covariance elements; no truth to compare


def test_an_existing_out_is_refused_without_force(run_cli, tmp_path):
    out = tmp_path / "r.html"
    out.write_text("mine")
    code, stdout, err = run_cli("report", RUN, "--robot", ROBOT, "--out", out)
    assert code == 2 and stdout == ""
    assert err.count("\n") == 1 and err.startswith("odomkit: error:") and "--force" in err
    assert out.read_text() == "mine"


@pytest.mark.parametrize(("args", "says"), [
    (["--window", "ten"], "window"),
    (["--kinds", "pink"], "--kinds"),
    (["--truth", "missing.csv"], "missing.csv"),
    (["--truth-sigma", "-1"], "--truth-sigma"),
    (["--columns", "t=t"], "--columns"),
])
def test_bad_input_is_one_line(run_cli, tmp_path, args, says):
    out = tmp_path / "r.html"
    code, _, err = run_cli("report", RUN, "--robot", ROBOT, "--out", out, *args)
    assert code == 2 and err.count("\n") == 1 and err.startswith("odomkit: error:") and says in err, err
    assert not out.exists()


def test_a_missing_log_is_one_line(run_cli, tmp_path):
    code, _, err = run_cli("report", tmp_path / "nope.csv", "--robot", ROBOT, "--out", tmp_path / "r.html")
    assert code == 2 and err.count("\n") == 1 and "nope.csv" in err


def test_the_out_may_not_be_an_input(run_cli, tmp_path):
    log = tmp_path / "run.csv"
    log.write_bytes(RUN.read_bytes())
    code, _, err = run_cli("report", log, "--robot", ROBOT, "--out", log, "--force")
    assert code == 2 and "input" in err
    assert log.read_bytes() == RUN.read_bytes()


def test_without_matplotlib_the_page_says_how_to_get_figures(monkeypatch, tmp_path):
    import odomkit.plot
    from odomkit.workflows.report import run_report

    monkeypatch.setattr(odomkit.plot, "have_matplotlib", lambda: False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_report(RUN, ROBOT, tmp_path / "r.html")
    assert any("matplotlib" in str(w.message) for w in caught)  # also said on stderr
    page = Page((tmp_path / "r.html").read_text(encoding="utf-8"))
    assert page.images == [] and "pip install 'odomkit[plot]'" in "".join(page.text)
    assert any("matplotlib" in w for w in result["warnings"])


@pytest.mark.filterwarnings("ignore:the noise fit")  # 9 windows: the fit warns, rightly
def test_progress_reports_every_stage_to_its_end(tmp_path):
    """The report's progress: the track's stages, then the truth steps, each closed with
    done == total (and the page the same as without progress)."""
    from odomkit.data import builtin_data_path
    from odomkit.progress import RecordingProgress
    from odomkit.workflows.report import run_report

    seen = RecordingProgress()
    log, robot = builtin_data_path("230620202042_run-01.csv"), builtin_data_path("optiodom_diff.toml")
    with_progress = run_report(log, robot, tmp_path / "a.html", progress=seen)
    without = run_report(log, robot, tmp_path / "b.html")
    assert with_progress["sections"] == without["sections"]
    assert seen.stages and all(s.closed for s in seen.stages)
    assert all(s.done == s.total for s in seen.stages if s.total is not None)
    assert seen.stages[-1].description.startswith("report:") and seen.stages[-1].total == 4


def test_the_calibration_section_names_the_parameters_it_fitted(with_truth):
    """The calibration paragraph names the robot's own calibration parameters (a car's or a
    unicycle's are no wheel sizes), the ones in its table."""
    result, page, _ = with_truth
    text = " ".join(" ".join(page.text).split())
    fitted = [key.split(".", 1)[1] for key in page.cells if key.startswith("calibration.")
              and not key.startswith("calibration.std_error.") and key.count(".") == 1]
    assert fitted and f"The robot's systematic errors ({', '.join(fitted[:3])}" in text
    assert "unequal wheel sizes" not in text


def test_a_robot_file_without_noise_gets_its_errors_and_the_fitted_noise_tested(run_cli, tmp_path):
    """A robot file that names only the vehicle (no [noise]) predicts no covariance: the report
    still gives the errors (as evaluate without --window does), says there is nothing of the
    file's to test, and tests the noise it fits (as fit-noise and evaluate do); it stopped
    with evaluate's one-line error before."""
    robot = tmp_path / "bare.toml"
    robot.write_text("\n".join(line for line in Path(ROBOT).read_text(encoding="utf-8").split("[noise]")[0]
                               .splitlines()) + "\n")
    assert "[noise]" not in robot.read_text(encoding="utf-8")
    out = tmp_path / "bare.html"
    code, stdout, err = run_cli("report", RUN, "--robot", robot, "--out", out)
    assert code == 0, err
    page = Page(out.read_text(encoding="utf-8"))
    errors = _run_json(run_cli, "evaluate", RUN, "--robot", robot)
    assert page.cells["ate_rmse"][0] == pytest.approx(errors["ate_rmse"], rel=1e-12)
    assert "coverage.0.95" not in page.cells  # no covariance of the file's to score
    assert any("has no [noise] table" in chunk for chunk in page.text)
    assert "fitted.coverage.0.5" in page.cells



def test_the_noise_fits_warnings_are_on_the_page_once(with_truth):
    """The fit issues its warnings as UserWarnings now (user study s24, M4); the report, which
    leads each with "the noise fit: ", must not list them bare too."""
    result, _, _ = with_truth
    lead = "the noise fit: "
    fitted = [w.removeprefix(lead) for w in result["warnings"] if w.startswith(lead)]
    assert fitted
    assert not set(fitted) & set(result["warnings"])


def _spinning(folder, psd_gyro, truth=False):
    """100 s at 0.5 m/s turning at 0.1 ± 0.1 rad/s, every 0.1 s, and a unicycle whose only
    noise is the gyro's: the heading variance is psd_gyro·t exactly (by hand). With
    ``truth`` the log also has gt_x, gt_y, gt_theta columns: its poses with the speed 2 %
    more than measured."""
    from odomkit.log import OdometryLog
    from odomkit.robot import Unicycle
    from odomkit.track import dead_reckon_log

    t = np.round(0.1 * np.arange(1001), 10)
    speed, yaw_rate = np.full(t.size, 0.5), 0.1 + 0.1 * np.sin(t / 7.0)
    cols, header = [t, speed, yaw_rate], "t,speed,yaw_rate"
    if truth:
        cols += list(dead_reckon_log(OdometryLog(t, {"speed": 1.02 * speed, "yaw_rate": yaw_rate}),
                                     Unicycle()).poses.T)
        header += ",gt_x,gt_y,gt_theta"
    log = folder / ("spin_gt.csv" if truth else "spin.csv")
    np.savetxt(log, np.column_stack(cols), delimiter=",", header=header, comments="")
    robot = folder / f"spin{psd_gyro:g}.toml"
    robot.write_text(f'[robot]\ntype = "unicycle"\n\n[noise]\npsd_gyro = {psd_gyro!r}\n')
    return t, log, robot


#: The report's own phrases: the track's first-order warning and the ROS yaw variance's.
_FIRST_ORDER, _YAW = "passes the first-order limit", "meaningless"


@pytest.mark.parametrize("truth", [False, True])
def test_a_heading_past_the_first_order_limit_is_said_once(run_cli, tmp_path, truth):
    """User study s25 (MRCLAM, 887 s): the page showed a final σθ of 0.89 rad (2.7 with a
    fitted noise) and a ROS 6×6 with a yaw variance of 7 rad², beyond a heading spread
    uniformly round the circle (π²/3), without a word. With gyro noise of 0.045 rad²/s the
    heading variance is 0.045·t (by hand): σθ passes FIRST_ORDER_SIGMA_THETA (0.2 rad) at
    0.9 s (the first row past 0.04/0.045 s) and ends at √4.5 rad. The warnings list says it
    once, though the report tracks the log twice with truth (before and after calibration),
    and the ROS section's 4.5 rad² once more; the summary gives the time, keyed, and the
    track and ROS sections point to it. The numbers are unchanged (the ROS 6×6's yaw is
    0.045·100 s). A σθ of 0.173 rad at the end (0.0003 rad²/s) gets none of it."""
    from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA

    t, log, robot = _spinning(tmp_path, 0.045, truth)
    first = t[np.argmax(np.sqrt(0.045 * t) > FIRST_ORDER_SIGMA_THETA)]
    assert first == pytest.approx(0.9)
    out = tmp_path / "r.html"
    result = _run_json(run_cli, "report", log, "--robot", robot, "--out", out)
    said = [w for w in result["warnings"] if _FIRST_ORDER in w]
    assert len(said) == 1, result["warnings"]
    assert f"from {first:.4g} s into the log on" in said[0] and f"reaches {np.sqrt(4.5):.3g} rad" in said[0]
    assert "too small along the arc" in said[0]
    yaw = [w for w in result["warnings"] if _YAW in w]
    assert len(yaw) == 1 and "reaches 4.5 rad²" in yaw[0] and "robot_localization" in yaw[0], yaw
    assert len(set(result["warnings"])) == len(result["warnings"])
    html = out.read_text(encoding="utf-8")
    page = Page(html)
    assert page.cells["first_order_limit_passed"][0] == pytest.approx(first)
    assert page.cells["final_sigma_theta"][0] == pytest.approx(np.sqrt(4.5), rel=1e-9)
    matrix = re.search(r"covariance: \[([^\]]*)\]", html).group(1)
    assert float(matrix.split(",")[35]) == pytest.approx(4.5, rel=1e-3)  # shown to 4 digits
    text = " ".join("".join(page.text).split())
    assert text.count("past the first-order limit") >= 2  # the track's and the ROS section's pointers

    _, log, quiet = _spinning(tmp_path, 0.0003, truth)
    result = _run_json(run_cli, "report", log, "--robot", quiet, "--out", out, "--force")
    assert not [w for w in result["warnings"] if _FIRST_ORDER in w or _YAW in w], result["warnings"]
    assert "first_order_limit_passed" not in Page(out.read_text(encoding="utf-8")).cells


def test_the_ros_covariance_past_the_limit_is_warned_of_where_the_track_was_not():
    """The ROS section's 6×6 is the calibrated robot's last pose, which may pass the
    first-order limit where the track on the page (the robot file's) did not: then its own
    warning says what that means, once; where the track's warning has said it (``said``),
    only the yaw variance beyond π²/3 is added. Heading variance 0.05·t over 100 s (by hand:
    past 0.04 rad² from 0.9 s on, 5 rad² at the end)."""
    from odomkit.track import Track
    from odomkit.workflows.report import _ros_covariance_note
    from odomkit.workflows.track import TrackRun

    t = np.round(0.1 * np.arange(1001), 10)
    cov = np.zeros((t.size, 3, 3))
    cov[:, 2, 2] = 0.05 * t
    run = TrackRun(Track(t, np.zeros((t.size, 3)), cov, None), None)  # type: ignore[arg-type]
    for said, expected in ((False, 2), (True, 1)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            note = _ros_covariance_note(run, said)
        texts = [str(w.message) for w in caught]
        assert len(texts) == expected, texts
        assert note is not None and "σθ (2.24 rad)" in note and "robot_localization" in note
        assert "reaches 5 rad²" in texts[-1]
        if not said:
            assert "the track whose covariance the ROS section gives" in texts[0]
            assert "from 0.9 s into the log on" in texts[0]
    cov[:, 2, 2] = 0.0003 * t  # σθ 0.173 rad at the end
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert _ros_covariance_note(run, False) is None and not caught
