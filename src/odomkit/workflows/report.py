"""``odomkit report``: one self-contained HTML page about one log.

The page gathers what the other commands compute, by running their workflows on the log:
the track with its covariance (:mod:`~odomkit.workflows.track`); with ground truth also the
error metrics and the windowed honesty test (:func:`~odomkit.workflows.evaluate.score_logs`
pooled by :func:`~odomkit.workflows.evaluate.summarise`, exactly what ``odomkit evaluate``
prints), the calibration (:func:`~odomkit.workflows.calibration.calibrate_files`) and the
metrics after it, the fitted noise (:func:`~odomkit.workflows.fit_noise.fit_noise_files`) with
its own honesty test, nav2 AMCL's α's (:func:`~odomkit.workflows.fit_amcl.fit_amcl_files`) and
the ROS parameter snippets (:mod:`odomkit.io.ros`). Nothing is computed another way here.
Figures come from :mod:`odomkit.plot` (the optional ``plot`` extra; without it the page has
the numbers and says how to get the figures); the page itself is :mod:`odomkit.report`.
"""

from __future__ import annotations

import tempfile
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from odomkit import __version__
from odomkit.errors import InputError, OdomkitError
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.report import Cell, Code, Figure, Paragraph, Section, Table, number, render_report, svg_figure
from odomkit.workflows.results import collected_warnings
from odomkit.workflows.truth import TruthOptions

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from odomkit.truth import Truth
    from odomkit.workflows.evaluate import Scored
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.track import TrackRun

__all__ = ["DEFAULT_WINDOW", "LEVELS", "ReportFigures", "coverage_table",
           "run_report", "write_page"]

#: Window of the honesty test when none is given, if the log has three of them with truth.
DEFAULT_WINDOW = "10s"
#: The probabilities of the coverage tables (keys of the evaluate workflow's ``coverage``).
LEVELS = ("0.5", "0.9", "0.95", "0.99")
#: Updates a ROS 2 diff_drive_controller averages its velocity over (its default
#: ``velocity_rolling_window_size``), for the twist covariance of the snippet.
VELOCITY_WINDOW = 10

DrawFunction = Callable[[ModuleType, list["Axes"]], object]


class ReportFigures:
    """Draws figures with :mod:`odomkit.plot` and embeds them as SVG.

    Without matplotlib, or when a drawing function is missing from :mod:`odomkit.plot`,
    :meth:`draw` returns None and :attr:`notes` says why (once).
    """

    def __init__(self) -> None:
        from odomkit.plot import have_matplotlib

        self.enabled = have_matplotlib()
        self.notes: list[str] = []
        self.drawn = 0
        if not self.enabled:
            self.notes.append("the figures need matplotlib: pip install 'odomkit[plot]' and run again")

    def draw(self, needs: Sequence[str], build: DrawFunction, caption: str, alt: str, *,
             panels: tuple[int, int] = (1, 1), size: tuple[float, float] | None = None) -> Figure | None:
        """A figure of ``panels`` (rows, columns) axes drawn by ``build(plot, axes)``.

        Parameters
        ----------
        needs : names of the :mod:`odomkit.plot` functions ``build`` calls
        build : draws on the axes (a list, row by row)
        caption, alt : the text under the figure, and the text that stands for it
        size : (width, height) [inches]; default from :func:`odomkit.plot.new_figure`
        """
        if not self.enabled:
            return None
        from odomkit import plot

        missing = [name for name in (*needs, "new_figure", "figure_svg") if not hasattr(plot, name)]
        if missing:
            self.notes.append(f"odomkit.plot has no {', '.join(missing)}: a figure was left out")
            return None
        fig, axes = plot.new_figure(*panels, size=size)
        assert isinstance(axes, list)
        build(plot, axes)
        self.drawn += 1
        return svg_figure(plot.figure_svg(fig), caption, alt)


def write_page(path: str | Path, page: str, overwrite: bool) -> Path:
    """Write the page (the caller has checked ``path`` with :func:`odomkit.io.files.check_outputs`)."""
    from odomkit.io.files import write_new_text

    return write_new_text(path, page, overwrite)


def coverage_table(rows: Sequence[tuple[str, dict[str, Any], str]], scored: str,
                   inside: str = "the predicted position ellipse") -> Table:
    """Predicted probability against the observed fraction inside, one column per noise
    (and per position or heading).

    ``rows`` holds (label, coverage dict of the evaluate workflow, key): each cell's key is
    ``f"{key}.{level}"`` (``"coverage"``, ``"fitted.coverage_heading"``, as evaluate's JSON
    names the figure); ``scored`` names what was counted (e.g. "9 window ends"), ``inside``
    what it was counted inside."""
    header = ("predicted probability", *(f"inside, {label}" for label, _, _ in rows))
    body: tuple[tuple[str | Cell, ...], ...] = tuple(
        (f"{float(level):.0%}",
         *(number(cov[level], key=f"{key}.{level}", decimals=2) for _, cov, key in rows))
        for level in LEVELS)
    return Table(header, body, f"Fraction of {scored} inside {inside}")


# ----------------------------------------------------------------------------------- the steps
def _auto_window(run: TrackRun) -> tuple[str | None, str | None]:
    """:data:`DEFAULT_WINDOW` when the log has three such windows with truth, else one
    window for the whole log, with a note saying so."""
    from odomkit.windows import parse_window

    assert run.truth is not None
    t = run.log.t[np.isfinite(run.truth[:, 0])]
    span = float(t[-1] - t[0]) if t.size else 0.0
    if span >= 3 * parse_window(DEFAULT_WINDOW).length:
        return DEFAULT_WINDOW, None
    return None, (f"the log has {span:.3g} s with truth, too short for three {_window_text(DEFAULT_WINDOW)}: "
                  "the honesty test scores the whole log as one window, a single sample; give a longer "
                  "log or --window")


def _scored(log: Path, robot: Path, options: TruthOptions, log_options: LogOptions | None,
            window: str | None, method: str, who: str = "", said: Sequence[Scored] = (),
            start_said: bool = True) -> tuple[list[Scored], dict[str, Any]]:
    """The evaluate workflow's figures: each log's raw scores and the JSON keys ``odomkit
    evaluate`` prints for them, verdicts included (the same function makes both). Their
    warnings join the page's, each led by ``who`` (``"after calibration: "``), except those
    an earlier scoring of the same log (``said``) gave word for word and, where the track
    started from the truth as the scoring does (``start_said``: no ``pose0`` given), the late
    start of the whole run, which the track's own warning has said already."""
    from odomkit.windows import is_late_start_note, parse_window
    from odomkit.workflows._scoring import pooled_report
    from odomkit.workflows.evaluate import score_logs

    # A robot file without [noise] is scored for its errors alone (window None then).
    scored = score_logs([log], robot, [options], log_options=log_options, window=window, method=method,
                        errors_only=True)
    known = {w for s in said for w in s.warnings}
    for note in dict.fromkeys(w for s in scored for w in s.warnings):
        if not (start_said and is_late_start_note(note)) and note not in known:
            warnings.warn(f"{who}{note}", stacklevel=2)
    return scored, pooled_report(scored, (1.0,), None if window is None else str(parse_window(window)))


#: calibrate's advice for a car whose halves disagree names its flag, which report lacks.
_CUBIC_FROM_REPORT = ("try odomkit calibrate --fit-steering-cubic --out-robot FILE (a steering ratio that "
                      "varies with the angle, which report's own calibration does not fit), then report with "
                      "--robot FILE")


def _attempt(what: str, step: Callable[[], Any], problems: list[str]) -> Any:
    """Run one optional step; a refusal (bad or unsuitable data) becomes a note, not a failure
    of the whole report."""
    try:
        return step()
    except OdomkitError as exc:
        problems.append(f"{what}: {exc}")
        warnings.warn(f"{what} left out: {exc}", stacklevel=2)
        return None


# ---------------------------------------------------------------------------------- the sections
def _robot_file(name: str) -> str:
    """How the page names the robot file's own parameters: ``"the robot file (rav4.toml)"``
    (``"the robot file"`` where ``name`` is empty)."""
    return f"the robot file ({name})" if name else "the robot file"


def _robot_used(name: str, calibrated: bool) -> str:
    """Which robot the steps after the calibration use (the noise fit, nav2 AMCL's α's, the ROS
    snippets): the calibrated one, or, where the calibration failed, the robot file's as it is
    (a user study's RAV4: "No calibration" above a noise "fitted with the calibrated robot")."""
    if calibrated:
        return "the calibrated robot (the parameters fitted under 'Calibration before and after')"
    return (f"{_robot_file(name)} uncalibrated, its parameters as they are: the calibration failed (see "
            "'Calibration before and after')")


def _track_section(run: TrackRun, figures: ReportFigures, summary: dict[str, Any],
                   robot_name: str) -> Section:
    from odomkit.windows import cumulative_travel

    track = run.track
    cov = track.cov
    blocks: list[Any] = [Paragraph(
        "Dead reckoning integrates the wheel (or speed and yaw-rate) increments of the log with the "
        f"geometry of {_robot_file(robot_name)}. The covariance grows with its [noise]: the "
        "ellipses hold the true position with 95 % probability if that noise model is right.")]
    s = cumulative_travel(track.steps)
    fig = figures.draw(("draw_track",), lambda plot, ax: plot.draw_track(
        ax[0], track.poses, cov, truth=run.truth, label="odometry"),
        "The dead-reckoned track (solid) with its 95 % position ellipses (χ² with 2 degrees of freedom, "
        "5.99), and the ground truth (dashed) where there is one.", "Track of the log with ellipses",
        size=(7.0, 5.6))
    blocks += [f for f in (fig,) if f is not None]
    x, y, th = summary["pose"]
    rows: list[tuple[str | Cell, ...]] = [
        ("poses", Cell(str(summary["samples"]), "samples", float(summary["samples"]))),
        ("duration", number(summary["duration"], "s", key="duration")),
        ("path length", number(summary["path_length"], "m", key="path_length")),
        ("final pose x, y", Cell(f"{x:.4g} m, {y:.4g} m")),
        ("final heading θ", number(th, "rad", key="final_theta")),
    ]
    if cov is not None:
        rows += [("final σx, σy", Cell(f"{np.sqrt(cov[-1, 0, 0]):.3g} m, {np.sqrt(cov[-1, 1, 1]):.3g} m")),
                 ("final σθ", number(float(np.sqrt(cov[-1, 2, 2])), "rad", 3, key="final_sigma_theta"))]
        fig = figures.draw(("draw_covariance_elements",), lambda plot, ax: plot.draw_covariance_elements(
            ax, s, cov, s_label="distance travelled [m]"),
            "The six elements of the pose covariance along the path: variances grow with distance, and "
            "the correlations (x–θ, y–θ) show how a heading error turns into a position error.",
            "Covariance elements over distance", panels=(2, 3), size=(10.0, 5.6))
        blocks += [f for f in (fig,) if f is not None]
    blocks.insert(1, Table(("", "value"), tuple(rows), "The track"))
    passed = _first_order_from(run)
    if passed is not None:
        from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA, first_order_track_note

        assert cov is not None
        said = first_order_track_note(track.t, cov[:, 2, 2],
                                      "the track's covariance (its ellipses and final σ's on this page)",
                                      _windowed_test(run))
        warnings.warn(str(said), stacklevel=2)
        shown = "the ellipses" + (", the ±2σ band" if run.truth is not None else "") + " and the final σ's"
        blocks.insert(2, Paragraph(
            f"From {passed:.4g} s into the log on, σθ is past the first-order limit "
            f"({FIRST_ORDER_SIGMA_THETA} rad): {shown} are then no Gaussian claim about the pose (see the "
            "warnings at the top).", "warning"))
    if run.truth is not None and cov is not None:
        err = track.poses - run.truth  # θ wrapped by draw_error_band
        sigma = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
        fig = figures.draw(("draw_error_band",), lambda plot, ax: plot.draw_error_band(
            ax, track.t, err, sigma),
            "The true error (odometry − truth) in x, y and θ with the ±2σ band of the predicted standard "
            "deviation. Along one run the errors are correlated, so the fraction inside is one sample, "
            "not a test: the windowed honesty test below is.", "True error against predicted band",
            panels=(3, 1), size=(8.0, 6.6))
        blocks += [f for f in (fig,) if f is not None]
    return Section("track", "The track and its uncertainty", tuple(blocks))


def _metric_rows(ev: dict[str, Any], prefix: str = "") -> list[tuple[str | Cell, ...]]:
    rows: list[tuple[str | Cell, ...]] = [
        (label, number(ev[key], unit, digits, key=prefix + key)) for label, key, unit, digits in (
            ("final position error", "final_position_error", "m", 4),
            ("largest position error", "max_position_error", "m", 4),
            ("ATE (RMSE of the position error)", "ate_rmse", "m", 4),
            ("drift (final error per distance)", "drift_percent", "%", 3))]
    rows += [(f"RPE over {d} m (RMSE)", number(v, "m", key=f"{prefix}rpe.{d}")) for d, v in ev["rpe"].items()]
    return rows


def _errors_section(ev: dict[str, Any], robot_name: str) -> Section:
    rows = _metric_rows(ev) + [("rows scored / left out (no truth there)",
                                Cell(f"{ev['rows_evaluated']} / {ev['rows_skipped']}"))]
    return Section("errors", "How wrong: error metrics", (
        Paragraph(f"The track dead-reckoned with {_robot_file(robot_name)} from the truth at its first "
                  "usable row, compared with the truth row by row (no alignment). ATE is the RMS position "
                  "error over the run; RPE the error of the motion over each stretch of 1 m of true travel, "
                  "which does not grow with the run; drift the final error as a share of the distance "
                  "travelled."),
        Table(("metric", "value"), tuple(rows), "Against ground truth (odomkit evaluate)"),
    ))


def _window_text(window: str | None) -> str:
    """``"10s"`` -> "10 s windows"."""
    if window is None:
        return "one window, the whole log"
    from odomkit.windows import parse_window

    spec = parse_window(window)
    return f"{spec.length:g} {'s' if spec.unit == 's' else 'm of travel'} windows"


#: evaluate's NEES verdicts (``nees_verdict``, ``nees_heading_verdict``) in words: where the
#: mean stands against its bounds, and what that says of the ``{what}``.
_NEES_SAYS = {"consistent": "within its bounds: the {what} is honest here",
              "optimistic": "above its bounds: the {what} is too small (optimistic)",
              "pessimistic": "below its bounds: the {what} is too large (pessimistic)"}
#: evaluate's coverage verdicts (``coverage_overall``, ``coverage_heading_overall``) in words.
_COVERAGE_SAYS = {
    "consistent": "at every level the fraction inside lies where an honest {what}'s falls",
    "optimistic": "fewer window ends fall inside than an honest {what}'s would at some level (more at none), "
                  "so the {what} is too small",
    "pessimistic": "more window ends fall inside than an honest {what}'s would at some level (fewer at "
                   "none), so the {what} is too large",
    "mixed": "fewer window ends fall inside than an honest {what}'s would at some levels and more at others: "
             "heavy tails, which no scaling of the {what} mends"}


def _has_heading(ev: dict[str, Any] | None) -> bool:
    """Whether evaluate scored the heading (the truth has one; its keys are None otherwise)."""
    return ev is not None and ev.get("nees_heading_mean") is not None


def _verdicts(ev: dict[str, Any], who: str = "") -> list[Paragraph]:
    """evaluate's verdicts of the position and (where scored) the heading as sentences: the
    NEES mean against its bounds and the coverage, each as evaluate's keys say (None for no
    verdict: one window, no independent samples), and ``verdict_note`` (``verdict_heading_note``)
    where they differ.
    ``who`` starts each sentence (e.g. "With the fitted noise (in-sample), "). Fewer window
    ends than :data:`odomkit.workflows._scoring.FEW_WINDOW_ENDS` add evaluate's caution."""
    from odomkit.workflows._scoring import few_ends_note

    out = []
    for name, what, mean_key, nees_key, cover_key, note_key in (
            ("position", "covariance", "nees_position_mean", "nees_verdict", "coverage_overall",
             "verdict_note"),
            ("heading", "heading variance", "nees_heading_mean", "nees_heading_verdict",
             "coverage_heading_overall", "verdict_heading_note")):
        said = []
        if ev.get(nees_key) is not None:
            said.append(f"{who}the mean {name} NEES {ev[mean_key]:.3g} is "
                        f"{_NEES_SAYS[ev[nees_key]].format(what=what)}.")
        if ev.get(cover_key) is not None:
            said.append(f"The {name} coverage is {ev[cover_key]}: "
                        f"{_COVERAGE_SAYS[ev[cover_key]].format(what=what)}.")
        if ev.get(note_key):
            said.append(f"NEES and coverage disagree (odomkit evaluate's note): {ev[note_key]}.")
        if said and (few := few_ends_note(int(ev.get("windows") or 0))):
            # "honest here" from 4 window ends said nothing of the kind (user study).
            said.append(f"But {few}.")
        if said:
            text = " ".join(said)
            out.append(Paragraph(text[:1].upper() + text[1:], "note"))
    return out


def _coverage_rows(ev: dict[str, Any], label: str, key: str = "") -> list[tuple[str, dict[str, Any], str]]:
    """The position's and (where scored) the heading's coverage columns of one noise, keyed
    ``{key}coverage`` and ``{key}coverage_heading`` as evaluate's JSON names them."""
    rows = [(label, ev["coverage"], f"{key}coverage")]
    if _has_heading(ev):
        rows.append((f"{label}, heading", ev["coverage_heading"], f"{key}coverage_heading"))
    return rows


#: What the coverage tables count inside: the position's ellipse, and with heading columns also
#: the heading's interval.
_INSIDE_POSITION = "the predicted position ellipse"
_INSIDE_BOTH = f"{_INSIDE_POSITION} (heading columns: the predicted heading interval)"


def _honesty_section(scored: list[Scored], ev: dict[str, Any], window: str | None,
                     figures: ReportFigures, robot_name: str) -> Section:
    from odomkit.evaluate import nees

    n = ev["windows"]
    heading = _has_heading(ev)
    blocks: list[Any] = [Paragraph(
        f"The log is cut into {_window_text(window)}; each is dead-reckoned with {_robot_file(robot_name)} "
        "(its geometry and its [noise]) again from the truth at its start and scored at its end, so the "
        "window ends are independent samples. An honest covariance puts about 50 / 90 / 95 / 99 % of them "
        "inside its 50 / 90 / 95 / 99 % ellipses, and its mean NEES (normalised error squared, 2 for a "
        "position) inside the bounds."
        + (" The truth has a heading, so the heading is scored alike: its error against the predicted "
           "heading variance, an interval instead of an ellipse and a mean NEES of 1 (one degree of "
           "freedom)." if heading else ""))]
    lo_hi = ev["nees_bounds"]
    rows: list[tuple[str | Cell, ...]] = [
        ("windows scored", Cell(str(n), "windows", float(n))),
        ("NEES mean (ideal 2)", number(ev["nees_position_mean"], "", 3, key="nees_position_mean")),
        ("95 % bounds of the mean", Cell("n/a" if lo_hi is None else f"{lo_hi[0]:.3g} … {lo_hi[1]:.3g}")),
        ("NEES median (ideal 1.39)", number(ev["nees_position_median"], "", 3, key="nees_position_median")),
    ]
    blocks.append(Table(("", "value"), tuple(rows), "Position NEES of the window ends"))
    if heading:
        h_lo_hi = ev["nees_heading_bounds"]
        blocks.append(Table(("", "value"), (
            ("heading NEES mean (ideal 1)", number(ev["nees_heading_mean"], "", 3, key="nees_heading_mean")),
            ("95 % bounds of the heading mean",
             Cell("n/a" if h_lo_hi is None else f"{h_lo_hi[0]:.3g} … {h_lo_hi[1]:.3g}")),
            ("heading NEES median (ideal 0.455)",
             number(ev["nees_heading_median"], "", 3, key="nees_heading_median"))),
            "Heading NEES of the window ends (χ² with 1 degree of freedom)"))
    blocks.append(coverage_table(_coverage_rows(ev, "robot file's noise"), f"{n} window ends",
                                 _INSIDE_BOTH if heading else _INSIDE_POSITION))
    blocks += _verdicts(ev)
    t = np.concatenate([s.honesty_t for s in scored])
    e = np.concatenate([s.honesty_errors for s in scored])
    c = np.concatenate([s.honesty_cov for s in scored])
    if t.size == e.shape[0] and t.size:
        covers = {label: cover for label, cover, _ in _coverage_rows(ev, "robot file's noise")}
        fig = figures.draw(("draw_nees", "draw_reliability"), lambda plot, ax: (
            plot.draw_nees(ax[0], t, nees(e, c)),
            plot.draw_reliability(ax[1], covers, n_scored=n)),
            "Left: the position NEES of each window end against the band that holds 95 % of them for an "
            "honest covariance. Right: predicted probability against the observed fraction inside (on the "
            "diagonal when honest; below it when overconfident)"
            + (", for the position's ellipses and the heading's intervals." if heading else "."),
            "NEES per window and reliability diagram", panels=(1, 2), size=(10.5, 5.0))
        blocks += [f for f in (fig,) if f is not None]
    return Section("honesty", "How honest: the windowed test of the covariance", tuple(blocks))


def _calibrated_in_windows(cal: dict[str, Any] | None, problems: list[str],
                           again: Callable[[], dict[str, Any]]) -> tuple[dict[str, Any] | None, str | None]:
    """The calibration the page shows, and why it was fitted in windows (else None).

    A whole-run fit from the truth's positions that the odometry's own drift dominates is
    biased (``calibrate`` warns and names ``--window``, which a report's reader cannot pass:
    a real 15-minute MRCLAM run's speed scale came out 0.74 whole, 0.90 in windows), or runs
    to the edge of its range; the report then calibrates ``again`` in windows of
    :data:`odomkit.calibrate.positions.DRIFT_WINDOW` and says so."""
    from odomkit.calibrate.positions import DRIFT_GIST, DRIFT_WINDOW

    failed = cal is None and bool(problems) and DRIFT_GIST in problems[-1]
    if not (failed or (cal is not None and cal.get("drift_dominated"))):
        return cal, None
    windowed = _attempt("the calibration in windows", again, problems)
    if windowed is None:
        return cal, None
    if failed:
        problems.pop()  # the whole-run failure is answered by the windowed fit
    length = windowed.get("windows", {}).get("length", DRIFT_WINDOW)
    return windowed, (
        "The whole-run calibration was dominated by the odometry's own drift (its track wanders from the "
        "truth by more than a tenth of how far the truth spreads), which biases a fit of the whole run: it "
        f"shrinks the track. So it was calibrated again in windows of {length}, each from its own start pose "
        f"(odomkit calibrate --window {DRIFT_WINDOW}), with standard errors from the windows' spread.")


def _calibration_section(cal: dict[str, Any] | None, problem: str | None, before: dict[str, Any],
                         after: dict[str, Any] | None, run: TrackRun, run_after: TrackRun | None,
                         figures: ReportFigures, windowed: str | None = None,
                         robot_name: str = "", *, aligned: tuple[float | None, float | None] = (None, None),
                         clock: tuple[float, str] | None = None) -> Section:
    """``aligned``: the ATE [m] before and after with each track moved rigidly onto the truth
    (:func:`_aligned_ate`); ``clock``: the truth's clock offset [s] the calibration held, and
    where it came from (:func:`_clock_held`), None where it fitted it or there is none."""
    names = ", ".join((cal or {}).get("parameters", {})) or "its calibration parameters"
    blocks: list[Any] = [Paragraph(
        f"The robot's systematic errors ({names}) are fitted to this log's truth (odomkit "
        f"calibrate), starting from {_robot_file(robot_name)}; the metrics are then computed again with the "
        "corrected robot. On the log it was fitted to, 'after' is optimistic: check it on another log.")]
    if windowed is not None:
        blocks.append(Paragraph(windowed))
    if cal is None or after is None:
        # _attempt leads the problem with "the calibration: ", which the paragraph says already.
        said = (problem or "").removeprefix("the calibration: ")
        blocks.append(Paragraph(f"No calibration: {said}. The sections below use {_robot_file(robot_name)} "
                                "uncalibrated, its parameters as they are.", "warning"))
        return Section("calibration", "Calibration before and after", tuple(blocks))
    params = cal.get("parameters", {})
    errors = cal.get("std_errors", {})
    # Several runs, or windows: the standard errors from their spread, beside the fit's own.
    between = cal.get("std_errors_between_runs") or {}
    clusters = "windows" if cal.get("windows") else "runs"
    rows: list[tuple[str | Cell, ...]] = [
        (name, number(value, "", 6, key=f"calibration.{name}"),
         number(errors.get(name), "", 2, key=f"calibration.std_error.{name}"),
         *([number(between.get(name), "", 2, key=f"calibration.std_error_between.{name}")]
           if between else []))
        for name, value in params.items()]
    for name in ("E_d", "E_b"):
        if name in cal:
            rows.append((name, number(cal[name], "", 6, key=f"calibration.{name}"), Cell(""),
                         *((Cell(""),) if between else ())))
    held, clock = clock, cal.get("truth_time_offset")
    if isinstance(clock, dict) and clock.get("fitted"):
        # The truth's clock, fitted with the robot: every command that reads the calibrated
        # robot file's [truth] time_offset moves the truth by it (a user study missed it here).
        rows.append(("truth clock offset [s]",
                     number(clock["value"], "", 4, key="calibration.truth_time_offset"),
                     number(clock.get("std_error"), "", 2, key="calibration.std_error.truth_time_offset"),
                     *([number(clock.get("std_error_between_runs"), "", 2,
                               key="calibration.std_error_between.truth_time_offset")] if between else [])))
    elif held is not None:  # not fitted: the page says whose it is (a user study's 8328 s clock)
        rows.append((f"truth clock offset [s], {held[1]}",
                     number(held[0], "", 6, key="calibration.truth_time_offset"), Cell(""),
                     *((Cell(""),) if between else ())))
    header = (("parameter", "fitted", "standard error, the fit's own", f"standard error between {clusters}")
              if between else ("parameter", "fitted", "standard error"))
    if between:
        n = (cal.get("windows") or {}).get("fitted") if clusters == "windows" else cal.get("n_runs")
        blocks.append(Paragraph(_which_to_quote(errors, between, clusters, n), "note"))
    blocks.append(Table(header, tuple(rows),
                        f"Calibration ({cal.get('method', 'exact')}, from {cal.get('source', 'truth')})"))
    pairs = zip(_metric_rows(before, "before."), _metric_rows(after, "after."), strict=True)
    compared: list[tuple[str | Cell, ...]] = [(b[0], b[1], a[1]) for b, a in pairs]
    compared.append((f"{_ALIGNED_ATE} (odomkit evaluate --align se2)",
                     number(aligned[0], "m", 4, key="before.aligned.ate_rmse"),
                     number(aligned[1], "m", 4, key="after.aligned.ate_rmse")))
    blocks.append(Paragraph(_FOOTING))
    blocks.append(Table(("metric", "before", "after"), tuple(compared),
                        "Error metrics with the robot file's parameters and with the calibrated ones"))
    if (swapped := _footings_disagree(before["ate_rmse"], after["ate_rmse"], *aligned)) is not None:
        blocks.append(Paragraph(swapped, "note"))
    if run_after is not None:
        def draw(plot: ModuleType, ax: list[Axes]) -> None:
            plot.draw_track(ax[0], run.track.poses, truth=run.truth, label="before calibration")
            plot.draw_track(ax[0], run_after.track.poses, label="after calibration")

        fig = figures.draw(("draw_track",), draw, "The track with the robot file's parameters and with the "
                           "calibrated ones, both from the same start pose (the first track's), against the "
                           "ground truth.", "Tracks before and after calibration", size=(7.0, 5.6))
        blocks += [f for f in (fig,) if f is not None]
    return Section("calibration", "Calibration before and after", tuple(blocks))


#: The label of the ATE with each track moved rigidly onto the truth.
_ALIGNED_ATE = "ATE, each track moved rigidly onto the truth (SE(2))"
#: What the footings of the before-and-after table are, and what flatters which.
_FOOTING = (
    "Both columns stand on the same footing, row by row. Each row but the last starts both tracks from the "
    "truth at the first usable row, as odomkit evaluate does: where the truth has positions only, the "
    "heading there is fitted to the fixes around it, so a first fix a few cm off the robot, or that "
    "heading's own uncertainty, turns and shifts each whole track, by amounts that differ between the "
    "columns. The last row moves each track rigidly onto the truth first (the rotation and translation "
    "that fit it best, odomkit evaluate --align se2), which is the same as starting each from the start "
    "pose that fits it best: neither track's start counts, only its shape. That flatters both columns "
    "alike (three numbers fitted to the truth). The calibration fitted the robot's parameters with its own "
    "start pose to this same truth, so 'after' is in-sample on either footing.")


def _aligned_ate(scored: Sequence[Scored]) -> float | None:
    """The ATE [m] of ``scored``'s whole runs (their evaluated rows,
    :class:`~odomkit.workflows.evaluate.Scored` ``rows``) with each track moved rigidly onto the truth by
    :func:`odomkit.evaluate.align_track` ``"se2"``, pooled over the runs as ``ate_rmse`` is: what
    ``odomkit evaluate --align se2`` prints for them. None where a run kept no rows or has
    too few to align."""
    from odomkit.errors import ModelError
    from odomkit.evaluate import align_track

    errors = []
    for s in scored:
        if s.rows is None or s.rows.poses.shape[0] < 2:
            return None
        try:
            est, _ = align_track(s.rows.poses, s.rows.truth, "se2")
        except ModelError:  # the truth does not spread (the robot stands still)
            return None
        errors.append(np.hypot(*(est[:, :2] - s.rows.truth[:, :2]).T))
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2))) if errors else None


def _footings_disagree(before: float, after: float, aligned_before: float | None,
                       aligned_after: float | None) -> str | None:
    """What the page says where the ATE from the truth's first row and the aligned ATE
    disagree on whether the calibration helped (a user study's LEGO robot: 0.058 m before,
    0.084 m after from the first fix; 0.054 m and 0.019 m aligned), else None."""
    if aligned_before is None or aligned_after is None:
        return None
    if (after > before) == (aligned_after > aligned_before):
        return None
    larger, smaller = ("larger", "smaller") if after > before else ("smaller", "larger")
    return (f"The two footings disagree: from the truth at the first usable row the calibrated track's ATE "
            f"is the {larger} ({after:.3g} m against {before:.3g} m), moved onto the truth the {smaller} "
            f"({aligned_after:.3g} m against {aligned_before:.3g} m). What differs between the rows is where "
            "each track starts, not the robot's parameters: the aligned row judges those.")


def _clock_held(robot: Path, given: TruthOptions, own_fixes: bool) -> tuple[float, str] | None:
    """The truth's clock offset [s] that every step of the report holds rather than fits, and
    whose it is, for a truth on its own clock (a truth file; ``own_fixes``, a bag's GPS topic):
    ``--truth-time-offset`` (``given.time_offset``), else the robot file's ``[truth]
    time_offset``; None where neither gives one (the calibration fits it) or the truth is the
    log's own gt_* columns (on the log's clock)."""
    from odomkit.io.robotfile import read_truth_table

    if given.path is None and not own_fixes:
        return None
    if given.time_offset is not None:
        return given.time_offset, "as given by --truth-time-offset"
    table = read_truth_table(robot)
    if "time_offset" not in table:
        return None
    return float(table["time_offset"]), "held at the robot file's [truth] time_offset"


def _robot_file_clock(robot: Path, options: TruthOptions) -> TruthOptions:
    """``options`` with the truth's clock offset, where none is given, the robot file's
    ``[truth] time_offset`` (:func:`~odomkit.workflows.truth.clock_from_robot`, as every other
    command takes it), for every step of the report, the calibration too (which fits the
    clock only where neither gives one: a user study's truth 8328 s off was fitted from 0, and
    the calibration left out); as they are where the robot file has none."""
    from odomkit.io.robotfile import read_truth_table
    from odomkit.workflows.truth import clock_from_robot

    if options.time_offset is not None or "time_offset" not in read_truth_table(robot):
        return options
    return clock_from_robot(robot, [options])[0]


def _which_to_quote(own: dict[str, float], between: dict[str, float], clusters: str, n: int | None) -> str:
    """Which standard errors of a calibration to quote: the between-``clusters`` ones (from
    ``n`` windows or runs) where they exceed the fit's own by more than
    :data:`odomkit.calibrate.exact.BETWEEN_RUNS_FACTOR` (calibrate's warning then says so
    too), else the larger of the two."""
    from odomkit.calibrate.exact import BETWEEN_RUNS_FACTOR

    one = clusters[:-1]
    spread = f"the {n} {clusters}' spread" if n else f"the {clusters}' spread"
    ratios = {name: b / own[name] for name, b in between.items() if own.get(name)}
    if any(r > BETWEEN_RUNS_FACTOR for r in ratios.values()):
        listed = ", ".join(f"{name} {r:.0f}×" for name, r in ratios.items())
        return (f"Quote the between-{one} standard errors (from {spread}): the fit's own take the residuals "
                f"along a {one} as independent, but the odometry's drift is correlated along each {one}, and "
                f"here the between-{one} ones are larger ({listed}).")
    return (f"The between-{one} standard errors (from {spread}) agree with the fit's own within "
            f"{BETWEEN_RUNS_FACTOR:g}×: quote the larger of the two.")


def _noise_section(fit: dict[str, Any] | None, problem: str | None, guessed: dict[str, float],
                   ev: dict[str, Any], ev_fit: dict[str, Any] | None, figures: ReportFigures,
                   unscored: str | None = None, used: str = "the calibrated robot") -> Section:
    """``used`` names the robot the noise was fitted with (:func:`_robot_used`)."""
    blocks: list[Any] = [Paragraph(
        "The noise variances that make the window ends most likely (maximum likelihood, odomkit "
        f"fit-noise), with their 95 % profile-likelihood intervals, fitted with {used}. "
        "The honesty test with the fitted noise is in-sample here (fitted and scored on the same windows): "
        "score it on another log (odomkit evaluate) before trusting it.")]
    if fit is None:
        blocks.append(Paragraph(f"No noise fit: {problem}", "warning"))
        return Section("noise", "The fitted noise", tuple(blocks))

    def interval(key: str) -> Cell:
        ends = fit["interval95"].get(key)
        return Cell("n/a" if ends is None else " … ".join(
            "∞" if v is None or not np.isfinite(v) else f"{v:.3g}" for v in ends))

    rows = tuple((key, number(guessed.get(key), "", 4, key=f"noise.file.{key}"),
                  number(value, "", 4, key=f"noise.fitted.{key}"), interval(key))
                 for key, value in fit["parameters"].items())
    blocks.append(Table(("parameter", "robot file", "fitted", "95 % interval"), rows,
                        f"Fitted on {fit['windows']} windows (in the robot file's units: k_* m^½, "
                        "sigma_* as named)"))
    if ev_fit is None:
        blocks.append(Paragraph(f"The fitted noise could not be scored: {unscored}", "warning"))
        return Section("noise", "The fitted noise", tuple(blocks))
    n = ev_fit["windows"]
    # The robot file's noise beside the fitted, where it has one (ev's coverage null, or no window
    # end scored: a robot file without [noise], scored for its errors alone).
    guess = ([] if ev.get("coverage") is None or not ev.get("windows") else
             _coverage_rows(ev, "robot file's noise"))
    fitted = _coverage_rows(ev_fit, "fitted noise (in-sample)", "fitted.")
    # The two noises may score different ends: a position-only truth's fitted noise can leave
    # out starts whose heading its fixes no longer support (odomkit.truth.MAX_HEADING_SIGMA).
    scored = (f"{n} window ends" if not guess or ev["windows"] == n else
              f"the window ends ({ev['windows']} with the robot file's noise, {n} with the fitted noise: "
              "a start heading the truth's fitted noise cannot support is left out)")
    # The position's columns first, then the heading's (where the truth has one).
    columns = [*guess[:1], *fitted[:1], *guess[1:], *fitted[1:]]
    heading = len(guess) > 1 or len(fitted) > 1
    blocks.append(coverage_table(columns, scored, _INSIDE_BOTH if heading else _INSIDE_POSITION))
    if n == 0:  # nothing to draw a fraction of
        blocks.append(Paragraph("The fitted noise scores no window end: the truth's fitted noise is too "
                                "large for its fixes to give any window a start heading, so this log cannot "
                                "test it.", "warning"))
        return Section("noise", "The fitted noise", tuple(blocks))
    blocks += _verdicts(ev_fit, "with the fitted noise (in-sample), ")
    which = "the robot file's and the fitted noise" if guess else "the fitted noise"
    fig = figures.draw(("draw_reliability",), lambda plot, ax: plot.draw_reliability(
        ax[0], {label: cover for label, cover, _ in columns},
        n_scored=n), f"Reliability diagram of {which}: predicted probability against the observed fraction "
        "of window ends inside.",
        "Reliability diagram, guessed and fitted noise", size=(5.6, 4.6))
    blocks += [f for f in (fig,) if f is not None]
    return Section("noise", "The fitted noise", tuple(blocks))


def _ros_section(snippets: list[Code], notes: list[str], what: str) -> Section:
    """``what`` names the robot and the noise the snippets come from."""
    blocks: list[Any] = [Paragraph(
        f"Parameter snippets for ROS 2, from {what}. "
        "Paste them into the node's parameter file; the comments say where each number holds.")]
    blocks += snippets
    blocks += [Paragraph(n, "note") for n in notes]
    return Section("ros", "ROS parameters", tuple(blocks))


#: What calibrate fits, by vehicle, in the words of a report without truth.
_CALIBRATED = {"diff": "the wheel sizes and wheel base", "tricycle": "the speed scale, steering offset and "
               "wheel-to-axle distance", "car": "the speed scale, steering offset and wheel base",
               "unicycle": "the speed scale and the yaw rate's bias and scale",
               "gyro": "the wheel size and the gyro's bias and scale"}


def _without_truth_section(robot_type: str = "diff", bag: bool = False) -> Section:
    calibrated = _CALIBRATED.get(robot_type)
    return Section("truth", "What ground truth would add", (Paragraph(
        "This log has no ground truth (no --truth file and no gt_* columns), so the report shows the track "
        "and the covariance the robot file's noise predicts, and cannot say whether either is right. With "
        "truth (motion capture, a total station, RTK GPS; position only is enough) it would add: the error "
        "metrics (ATE, RPE, drift, final and largest error); the honesty test, which checks the predicted "
        "covariance against the true errors; "
        + (f"the calibration of {calibrated}, before and after; " if calibrated else "")
        + "the noise fitted to the data; and nav2 AMCL's α's. Run it again with --truth FILE"
        + (" (or --truth-topic TOPIC, a pose or GPS topic of the bag)." if bag else ".")),))


def _snippets(run: TrackRun, robot_path: Path, robot_file: Path | None, what: str,
              amcl_yaml: str | None, notes: list[str], said: bool = False, geometry: str = "",
              radius: float | None = None) -> list[Code]:
    """The controller YAML (with the twist covariance of the noise), nav2 AMCL's α's and the
    final pose covariance in ROS's 6×6 layout (robot_localization reads it from odometry).

    ``robot_file`` (default ``robot_path``) gives the geometry and the noise, which ``what``
    names ("the calibrated robot and the fitted noise"); ``radius`` [m] is the controller's
    nominal wheel radius (:func:`odomkit.calibrate.export.controller_radius`: ``--wheel-radius``
    or ``robot_path``'s own; None: no controller snippet, and a note naming the flag).
    ``geometry`` names the robot nav2 AMCL's α's were fitted with.
    A pose covariance past the first-order limit gets a note (:func:`_ros_covariance_note`;
    ``said``: the track's own warning has said what that means)."""
    from odomkit.calibrate.export import twist_covariance
    from odomkit.io.robotfile import read_robot
    from odomkit.io.ros import ros2_controller_yaml, ros_pose_covariance
    from odomkit.robot import DiffDrive, Tricycle

    out = []
    robot, noise = read_robot(robot_file or robot_path)
    if not isinstance(robot, DiffDrive | Tricycle):
        notes.append(f"no controller snippet: ROS 2's diff_drive and tricycle controllers take a diff or "
                     f"tricycle robot, this is a {robot.type_name!r} one")
    elif radius is None:
        notes.append("no controller snippet: the robot file gives metres per tick, not the wheel size "
                     "(wheel_radius or wheel_diameter) the controller needs: give it with --wheel-radius R "
                     "(the controller's nominal radius, m), as calibrate --ros-yaml takes it")
    else:
        twist = None
        dt = np.diff(run.log.t)
        speed = run.track.path_length / run.track.duration if run.track.duration > 0 else 0.0
        if any(getattr(m, "kind", None) == "white" for m in noise) and dt.size:
            twist = _attempt("the twist covariance", lambda: twist_covariance(
                robot, noise, speed, float(np.median(dt)), window=VELOCITY_WINDOW), notes)
        caption = f"ROS 2 controller, from {what}: wheel separation and radius multipliers"
        if twist is not None:
            caption += (", and the twist covariance robot_localization fuses from /odom (at this log's mean "
                        "speed)")
        out.append(Code(ros2_controller_yaml(robot, radius, twist=twist), caption))
    if amcl_yaml is not None:
        out.append(Code(amcl_yaml, "nav2 AMCL: the motion-model α's fitted to this log"
                        + (f" with {geometry}" if geometry else "") + " (odomkit fit-amcl)"))
    if run.track.cov is not None:
        cov = ros_pose_covariance(run.track.cov[-1])
        rows = "\n".join("  " + ", ".join(f"{v:11.4g}" for v in cov[i:i + 6]) + ("," if i < 30 else "")
                         for i in range(0, 36, 6))
        out.append(Code(f"pose:\n  covariance: [\n{rows}]\n",
                        "nav_msgs/Odometry pose covariance at the end of the log (x, y, z, roll, pitch, "
                        "yaw; 1e6 on the axes planar odometry does not observe), as odomkit track --bag-out "
                        "writes it"))
        notes += [n for n in (_ros_covariance_note(run, said),) if n is not None]
    return out


def _first_order_from(run: TrackRun) -> float | None:
    """When [s into the log] the track's σθ first passes the first-order limit
    (:func:`odomkit.calibrate.fit_noise.first_order_horizon`); None if it never does or
    there is no covariance."""
    from odomkit.calibrate.fit_noise import first_order_horizon

    cov = run.track.cov
    return None if cov is None else first_order_horizon(run.track.t, cov[:, 2, 2])


def _ros_covariance_note(run: TrackRun, said: bool) -> str | None:
    """The ROS section's note on its 6×6 (``run``'s last pose) where its σθ is past the
    first-order limit, or None. The warnings list gets the yaw variance beyond π²/3
    (:func:`odomkit.io.ros.yaw_variance_note`) and, unless the track's warning has said it
    (``said``), what the limit means (this track's, the calibrated robot's, may pass where
    the track's did not)."""
    from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA, first_order_track_note
    from odomkit.io.ros import yaw_variance_note

    assert run.track.cov is not None
    var = float(run.track.cov[-1, 2, 2])
    if not var > FIRST_ORDER_SIGMA_THETA**2:
        return None
    yaw = yaw_variance_note(var, "the ROS pose covariance under 'ROS parameters' (the last pose's 6×6)")
    if not said:
        whole = first_order_track_note(run.track.t, run.track.cov[:, 2, 2],
                                       "the track whose covariance the ROS section gives",
                                       _windowed_test(run))
        warnings.warn(str(whole), stacklevel=2)
    if yaw is not None:
        warnings.warn(yaw, stacklevel=2)
    said_yaw = (": its yaw variance is beyond π²/3, a heading spread uniformly around the circle, so a "
                "consumer such as robot_localization should not be given it.") if yaw is not None else "."
    return (f"This pose covariance is first-order, and its σθ ({np.sqrt(var):.3g} rad) is past the "
            f"first-order limit ({FIRST_ORDER_SIGMA_THETA} rad): no Gaussian claim about the pose (see the "
            f"warnings at the top){said_yaw}")


def _windowed_test(run: TrackRun) -> str:
    """Where the report sends a reader whose whole-log covariance is past the first-order limit."""
    return ("the honesty section's, whose windows restart from the truth" if run.truth is not None else
            "odomkit evaluate --window 10s, on a log with ground truth")


# ---------------------------------------------------------------------------------- the workflow
#: Steps of the report that need truth: scoring, calibration, noise fit, AMCL.
_TRUTH_STEPS = 4


def run_report(
    log_path: str | Path,
    robot_path: str | Path,
    out: str | Path,
    *,
    truth: TruthOptions | None = None,
    log_options: LogOptions | None = None,
    window: str | None = None,
    kinds: Sequence[str] = ("white",),
    method: str = "exact",
    pose0: tuple[float, float, float] | None = None,
    wheel_radius: float | None = None,
    overwrite: bool = False,
    progress: Progress = NO_PROGRESS,
) -> dict[str, Any]:
    """Write the HTML report of one log to ``out``.

    Parameters
    ----------
    log_path, robot_path : the log and its robot file
    out : the HTML file (never replaced unless ``overwrite``, never one of the inputs)
    truth : :class:`~odomkit.workflows.truth.TruthOptions`; default the log's own ``gt_*`` columns
    log_options : how to read the log
    window : honesty-test windows (``"30s"``, ``"5m"``); default :data:`DEFAULT_WINDOW` when
        the log has three of them with truth, else the whole log as one window
    kinds : the noise kinds fitted ("white", "bias")
    method : integration method
    pose0 : start of the track (x, y, θ) [m, m, rad]; default the truth pose at the first
        row, else the origin (as ``odomkit track``). The error metrics start from the truth
        as ``odomkit evaluate`` does, whatever ``pose0``.
    wheel_radius : the nominal wheel radius [m] of the ROS 2 controller snippet
        (``--wheel-radius``, as ``calibrate --ros-yaml`` takes it); default the robot file's
        own (``wheel_radius``/``wheel_diameter``), and an error where it differs, or where the
        robot is none that ROS 2's diff_drive or tricycle controller takes. A file in metres
        per tick (wheel speeds logged with ``m_per_tick = 1``) gets the snippet only with it.
    progress : :class:`~odomkit.progress.Progress`; the track's stages (reading, dead
        reckoning, covariance), then one stage of the steps that need truth (scoring,
        calibration, noise fit, AMCL).

    Returns
    -------
    dict
        ``report`` (the path written), ``sections`` (their keys, in order), ``warnings``.
    """
    from odomkit.io.files import check_outputs
    from odomkit.windows import parse_window
    from odomkit.workflows.track import run_track

    started = time.perf_counter()
    given = truth or TruthOptions()
    log_path, robot_path = Path(log_path), Path(robot_path)
    check_outputs({"--out": out}, overwrite=overwrite,
                  inputs=[p for p in (log_path, robot_path, given.path) if p is not None])
    options = _robot_file_clock(robot_path, given)
    radius = _wheel_radius(robot_path, wheel_radius)  # a bad one is one line before any work
    if window is not None:
        parse_window(window)  # a bad value is one line before any work
    figures = ReportFigures()
    with collected_warnings() as notes:
        run = run_track(log_path, robot_path, method=method, log_options=log_options,  # type: ignore[arg-type]
                        truth=options, pose0=pose0, progress=progress, note_first_order=False)
        # Without the note on its ground_truth block's NEES over the track's rows
        # (odomkit.evaluate.evaluate_track), which the page does not show: its honesty
        # section scores window ends.
        summary = run.summary(note_nees=False)
        sections = [_track_section(run, figures, summary, robot_path.name)]
        if run.truth is None:
            ros_notes: list[str] = []
            what = f"{_robot_file(robot_path.name)} and its noise"
            snippets = _snippets(run, robot_path, None, what, None, ros_notes,
                                 said=_first_order_from(run) is not None, radius=radius)
            kind, bag = run.track.steps.robot.type_name, run.log.meta.get("format") == "bag"
            sections += [_without_truth_section(kind, bag), _ros_section(snippets, ros_notes, what)]
            sections.insert(0, _summary_section(run, None, None, None, None, None, robot_path.name))
        else:
            with stage(progress, _TRUTH_STEPS, "report: scoring, calibration, noise fit, AMCL") as step:
                summary_section, *rest = _with_truth(
                    run, log_path, robot_path, options, log_options, window, kinds, method, figures, step,
                    start_said=pose0 is None, radius=radius,
                    clock=_clock_held(robot_path, given, _own_fixes(run) is not None))
            sections = [summary_section, *sections, *rest]
        notes += [n for n in figures.notes if n not in notes]
    title = f"odomkit report: {log_path.name}"
    fixes = _own_fixes(run)
    truth_text = (options.path or (fixes.source if fixes is not None else None)
                  or ("the log's own gt_* columns" if run.truth is not None else "none"))
    subtitle = [f"Log: {log_path} · robot: {robot_path} · truth: {truth_text}",
                f"{summary['samples']} poses over {summary['duration']:.4g} s, "
                f"{summary['path_length']:.4g} m travelled"]
    footer = (f"Written by odomkit {__version__} in {time.perf_counter() - started:.1f} s. One file, no "
              "network: figures are embedded SVG.")
    page = render_report(title, sections, subtitle=subtitle, warnings=notes, footer=footer)
    written = write_page(out, page, overwrite)
    for text in notes:
        warnings.warn(text, stacklevel=2)
    return {"report": str(written), "sections": [s.key for s in sections], "warnings": list(notes)}


def _wheel_radius(robot_path: Path, given: float | None) -> float | None:
    """The controller snippet's nominal wheel radius [m]: ``given`` or the robot file's own
    (:func:`odomkit.calibrate.export.controller_radius`, calibrate's rule), None for neither; a
    radius given for a robot no ROS 2 controller here takes is an InputError."""
    from odomkit.calibrate.export import controller_radius
    from odomkit.io.robotfile import read_robot
    from odomkit.robot import DiffDrive, Tricycle
    from odomkit.workflows.calibration import file_wheel_radius

    if given is not None:
        robot = read_robot(robot_path)[0]
        if not isinstance(robot, DiffDrive | Tricycle):
            raise InputError(f"--wheel-radius is the nominal wheel radius of ROS 2's diff_drive or "
                             f"tricycle controller; the robot file describes a {robot.type_name!r} robot, "
                             "which neither takes: leave --wheel-radius out", source=str(robot_path))
    return controller_radius(given, file_wheel_radius(robot_path), str(robot_path))


def _own_fixes(run: TrackRun) -> Truth | None:
    """The log's own position-only truth on its own clock (a ROS bag's GPS topic,
    ``--truth-topic /fix``), which is compared fix by fix, not row by row; else None."""
    from odomkit.truth import Truth

    own = run.log.meta.get("truth")
    return own if isinstance(own, Truth) else None


def _with_truth(run: TrackRun, log: Path, robot: Path, options: TruthOptions,
                log_options: LogOptions | None, window: str | None, kinds: Sequence[str], method: str,
                figures: ReportFigures, step: Progress = NO_PROGRESS,
                start_said: bool = True, clock: tuple[float, str] | None = None,
                radius: float | None = None) -> list[Section]:
    """The sections that need ground truth: the summary, errors, honesty, calibration, noise, ROS
    (``step`` advances once per step, :data:`_TRUTH_STEPS` in all; the workflows called
    report no progress of their own, so that stages do not nest). ``start_said``: the track
    started from the truth and said where (:func:`_scored`). ``clock``: the truth's clock
    offset every step holds, and whose it is (:func:`_clock_held`); ``radius``: the controller's
    nominal wheel radius [m] (:func:`_snippets`)."""
    from odomkit.calibrate.positions import DRIFT_WINDOW
    from odomkit.io.robotfile import TRUTH_SIGMAS, read_robot, read_truth_table
    from odomkit.workflows.calibration import calibrate_files
    from odomkit.workflows.fit_amcl import fit_amcl_files
    from odomkit.workflows.fit_noise import fit_noise_files
    from odomkit.workflows.track import run_track

    if window is None:
        window, note = _auto_window(run)
        if note:
            warnings.warn(note, stacklevel=2)
    # A robot file without [noise] predicts no covariance: its errors alone, and the honesty
    # test of the noise fitted below.
    file_models = read_robot(robot)[1]
    file_noise = bool(file_models)
    scored, ev = _scored(log, robot, options, log_options, window if file_noise else None, method,
                         start_said=start_said)
    name = robot.name
    sections = [_errors_section(ev, name), _honesty_section(scored, ev, window, figures, name)
                if file_noise else
                Section("honesty", "How honest: the windowed test of the covariance", (Paragraph(
                    f"The robot file ({name}) has no [noise] table, so it predicts no covariance to test; "
                    "the noise fitted to this log is tested under 'The fitted noise' (in-sample).",
                    "warning"),))]
    step.advance()
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="odomkit-report-") as tmp:
        folder = Path(tmp)
        cal_path, fit_path = folder / "calibrated.toml", folder / "fitted.toml"
        # With the log's own truth (with heading) every pose is compared (exact, trajectory); a
        # truth file, or a bag's GPS topic, is compared position by position on its own clock.
        how: dict[str, Any] = ({"truth": [options]} if options.path is not None else
                               {"own_truth": options} if _own_fixes(run) is not None else
                               {"source": "trajectory"})
        with warnings.catch_warnings(record=True) as whole_said:
            warnings.simplefilter("always")
            cal = _attempt("the calibration", lambda: calibrate_files(
                [log], robot, out_robot=cal_path, log_options=log_options, cubic_hint=_CUBIC_FROM_REPORT,
                **how), problems)
        # The log's own truth is compared position by position in windows (no --from there).
        in_windows = {k: v for k, v in how.items() if k != "source"}
        cal, windowed = _calibrated_in_windows(cal, problems, lambda: calibrate_files(
            [log], robot, out_robot=cal_path, overwrite=True, log_options=log_options,
            cubic_hint=_CUBIC_FROM_REPORT, window=DRIFT_WINDOW, **in_windows))
        for w in whole_said:  # what the whole-run fit said, named as such where windows replaced it
            # What it said of the truth file itself (its spikes, its units) holds for every fit.
            of_truth = options.path is not None and str(w.message).startswith(f"{options.path}:")
            message = w.message if windowed is None or of_truth else type(w.message)(
                f"the whole-run calibration, replaced by the one in windows: {w.message}")
            warnings.warn_explicit(message, w.category, w.filename, w.lineno)
        after = run_after = None
        aligned: tuple[float | None, float | None] = (_aligned_ate(scored), None)
        if cal is not None:
            scored_after, after = _scored(log, cal_path, options, log_options, window if file_noise else None,
                                          method, "after calibration: ", scored)
            aligned = (aligned[0], _aligned_ate(scored_after))
            start = run.track.poses[0]  # where the track before calibration started
            run_after = run_track(log, cal_path, method=method, log_options=log_options,  # type: ignore[arg-type]
                                  truth=options, pose0=(float(start[0]), float(start[1]), float(start[2])),
                                  note_first_order=False)
        sections.append(_calibration_section(cal, problems[-1] if problems else None, ev, after, run,
                                             run_after, figures, windowed, name, aligned=aligned,
                                             clock=clock))
        used = _robot_used(name, cal is not None)
        step.advance()
        base = cal_path if cal is not None else robot
        before = len(problems)
        # The fit issues its warnings itself; here they join the page's led by "the noise fit: "
        # (below), so they are caught, and the rest raised while it ran are passed on as they are.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fit = _attempt("the noise fit", lambda: fit_noise_files(
                base, [log], [options], fit_path, window=window, kinds=kinds, log_options=log_options,
                method=method), problems)
        own = set() if fit is None else set(fit["warnings"])
        for item in caught:
            if str(item.message) not in own:
                warnings.warn_explicit(item.message, item.category, item.filename, item.lineno)
        # The fitted noise scored like the file's; a fit whose truth noise leaves no start
        # heading (a car fitted 19 m of GPS noise) is a note, as a failed fit is.
        fit_problem = problems[-1] if len(problems) > before else None
        scored_fit = None if fit is None else _attempt("the fitted noise's honesty test", lambda: _scored(
            log, fit_path, options, log_options, window, method, "with the fitted noise: ", scored), problems)
        ev_fit = None if scored_fit is None else scored_fit[1]
        for note in [] if fit is None else fit["warnings"]:  # the CLI prints them; here they join the page's
            warnings.warn(f"the noise fit: {note}", stacklevel=2)
        guessed = {k: float(v) for m in file_models for k, v in vars(m).items()
                   if fit is not None and k in fit["parameters"]}
        # The truth's own noise is no noise model: the robot file keeps it in [truth] (sigma,
        # heading_sigma, time_sigma), which fit-noise fits as truth_sigma, ... and writes back there.
        guessed.update({f"truth_{k}": v for k, v in read_truth_table(robot).items() if k in TRUTH_SIGMAS})
        unscored = problems[-1] if fit is not None and scored_fit is None and problems else None
        sections.append(_noise_section(fit, fit_problem, guessed, ev, ev_fit, figures, unscored, used))
        step.advance()
        amcl = _attempt("nav2 AMCL's α's", lambda: fit_amcl_files(
            [log], [options], robot_path=base, log_options=log_options, method=method,
            yaml_out=folder / "amcl.yaml"), problems)
        amcl_yaml = None if amcl is None else (folder / "amcl.yaml").read_text(encoding="utf-8")
        step.advance()
        notes: list[str] = []
        source, noise = (fit_path, "the fitted noise") if fit else (base, "the robot file's noise")
        what = f"{used}, and {noise}"
        snippets = _snippets(run_after or run, robot, source, what, amcl_yaml, notes,
                             said=_first_order_from(run) is not None, geometry=used, radius=radius)
    sections.append(_ros_section(snippets, notes, what))
    sections.insert(0, _summary_section(run, ev, cal, after, fit, ev_fit, name, aligned))
    return sections


def _summary_section(run: TrackRun, ev: dict[str, Any] | None, cal: dict[str, Any] | None,
                     after: dict[str, Any] | None, fit: dict[str, Any] | None,
                     ev_fit: dict[str, Any] | None, robot_name: str,
                     aligned: tuple[float | None, float | None] = (None, None)) -> Section:
    """``aligned``: the ATE [m] before and after calibration with each track moved rigidly onto
    the truth (:func:`_aligned_ate`), None where not scored."""
    cov = run.track.cov
    rows: list[tuple[str | Cell, ...]] = [("distance travelled", number(run.track.path_length, "m"))]
    if cov is not None:
        rows.append(("predicted σ of the final position (x, y)",
                     Cell(f"{np.sqrt(cov[-1, 0, 0]):.3g} m, {np.sqrt(cov[-1, 1, 1]):.3g} m")))
        passed = _first_order_from(run)
        if passed is not None:  # the σ above is then no Gaussian claim: the warnings say why
            from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA

            rows.append((f"σθ past the first-order limit ({FIRST_ORDER_SIGMA_THETA} rad) from",
                         number(passed, "s into the log", key="first_order_limit_passed")))
    if ev is not None:
        rows += [
            ("final position error", number(ev["final_position_error"], "m", key="final_position_error")),
            ("ATE", number(ev["ate_rmse"], "m", key="ate_rmse"))]
        if ev.get("coverage") is not None:
            rows.append(("inside the 95 % ellipse (robot file's noise; ideal 0.95)",
                         number(ev["coverage"]["0.95"], key="coverage.0.95", decimals=2)))
        if _has_heading(ev):
            rows.append(("heading inside its 95 % interval (robot file's noise; ideal 0.95)",
                         number(ev["coverage_heading"]["0.95"], key="coverage_heading.0.95", decimals=2)))
    if cal is not None and after is not None:
        rows.append(("ATE after calibration", number(after["ate_rmse"], "m", key="after.ate_rmse")))
        # Both moved onto the truth: neither track's start counts (see 'Calibration before and after').
        rows += [(f"ATE {when} calibration, each track moved rigidly onto the truth (SE(2))",
                  number(value, "m", key=f"{key}.aligned.ate_rmse"))
                 for when, key, value in (("before", "before", aligned[0]), ("after", "after", aligned[1]))
                 if value is not None]
    if fit is not None and ev_fit is not None:
        rows.append(("inside the 95 % ellipse, fitted noise (in-sample)",
                     number(ev_fit["coverage"]["0.95"], key="fitted.coverage.0.95", decimals=2)))
        if _has_heading(ev_fit):
            rows.append(("heading inside its 95 % interval, fitted noise (in-sample)",
                         number(ev_fit["coverage_heading"]["0.95"], key="fitted.coverage_heading.0.95",
                                decimals=2)))
    which = (f"Everything here uses {_robot_file(robot_name)}." if ev is None else
             f"The track, the error metrics and the honesty test use {_robot_file(robot_name)}; the fitted "
             f"noise, nav2 AMCL's α's and the ROS parameters use {_robot_used(robot_name, cal is not None)}.")
    return Section("summary", "At a glance", (
        Paragraph("The headline numbers; each section below explains one of them and shows where it comes "
                  f"from. {which}"),
        Table(("", "value"), tuple(rows)),
    ))
