"""The report of ``odomkit demo``: the whole product on built-in data, in one HTML page.

:mod:`odomkit.workflows.demo` computes (calibration, noise fit, held-out scores); this
module adds the two pictures that need no data, a closed-form prediction checked by Monte
Carlo (:func:`monte_carlo_check`) and a virtual UMBmark calibration
(:func:`virtual_umbmark_check`), and lays everything out (:func:`write_demo_report`) with
:mod:`odomkit.report`; figures come from :mod:`odomkit.plot` through
:class:`~odomkit.workflows.report.ReportFigures`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit import __version__
from odomkit.report import Cell, Code, Paragraph, Section, Table, number, render_report
from odomkit.workflows.report import ReportFigures, coverage_table, write_page

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.robot import DiffDrive
    from odomkit.track import Track

__all__ = ["DemoData", "MonteCarloCheck", "VirtualUmbmark", "monte_carlo_check", "virtual_umbmark_check",
           "write_demo_report"]

NAMES = {"guessed": "guessed (robot file)", "white": "fitted white", "white+bias": "fitted white + bias"}


@dataclass(frozen=True)
class MonteCarloCheck:
    """One planned square predicted in closed form and simulated: ``summary`` (JSON-ready:
    the prediction, the simulated statistics and the verdict of
    :func:`odomkit.simulate.stats.compare`), the predicted end pose and covariance, and
    the simulated end poses (runs, 3)."""

    summary: dict[str, Any]
    pose: NDArray[np.float64]
    cov: NDArray[np.float64]
    endpoints: NDArray[np.float64]


def monte_carlo_check(noise: NoiseModel, wheel_base: float, side: float, *, runs: int = 2000,
                      seed: int = 1) -> MonteCarloCheck:
    """Predict one clockwise square of ``side`` [m] (four legs, four right turns on the spot)
    in closed form (:func:`odomkit.propagate.predict.predict`) and simulate ``runs`` runs
    of it (:func:`odomkit.simulate.engine.simulate_runs`, seeded): the Monte Carlo check of
    the prediction."""
    from odomkit.path import Spin, Straight
    from odomkit.propagate.predict import predict
    from odomkit.simulate.engine import simulate_runs
    from odomkit.simulate.stats import compare

    square = [seg for _ in range(4) for seg in (Straight(side), Spin(-np.pi / 2))]
    prediction = predict(square, noise, wheel_base=wheel_base)
    mc = simulate_runs(square, noise, wheel_base, runs=runs, partitions=200, seed=seed, engine="numpy")
    stats = compare(mc.final, prediction.pose, prediction.cov)
    summary = {"runs": runs, "seed": seed, "verdict": stats["verdict"], "consistent": stats["consistent"],
               "predicted_std": np.sqrt(np.diag(prediction.cov)).tolist(),
               "simulated_std": stats["simulation"]["std"]}
    return MonteCarloCheck(summary, prediction.pose, prediction.cov, mc.final)


@dataclass(frozen=True)
class VirtualUmbmark:
    """A virtual robot's UMBmark before and after calibration: ``summary`` (JSON-ready) and
    the return errors (n, 2) [m] of each direction, before and after."""

    summary: dict[str, Any]
    cw: NDArray[np.float64]
    ccw: NDArray[np.float64]
    cw_after: NDArray[np.float64]
    ccw_after: NDArray[np.float64]


def virtual_umbmark_check(*, E_d: float = 1.002, E_b: float = 1.006, side: float = 4.0,  # noqa: N803
                          wheel_base: float = 0.34, runs: int = 5, seed: int = 2) -> VirtualUmbmark:
    """Borenstein–Feng's experiment on a virtual robot: a robot with unequal wheels (E_d)
    and a wrong wheel base (E_b) drives the ``side`` [m] square ``runs`` times each way with
    wheel noise (k = 1 mm/√m), is calibrated by UMBmark, and drives it again with the
    corrections (:mod:`odomkit.calibrate.virtual`)."""
    from odomkit.calibrate.umbmark import apply_corrections, e_max_syst, umbmark
    from odomkit.calibrate.virtual import SystematicErrors, run_virtual_umbmark
    from odomkit.noise import WheelNoise
    from odomkit.robot import DiffDrive

    errors = SystematicErrors(E_d, E_b)
    robot = DiffDrive(wheel_base)
    noise = WheelNoise(1e-3, 1e-3)
    before = run_virtual_umbmark(errors, robot, side, runs, noise, seed)
    result = umbmark(before.errors_cw, before.errors_ccw, side, wheel_base)
    after = run_virtual_umbmark(errors, apply_corrections(robot, result), side, runs, noise, seed + 1)
    summary = {"true": {"E_d": E_d, "E_b": E_b}, "estimated": {"E_d": result.E_d, "E_b": result.E_b},
               "side": side, "runs_per_direction": runs,
               "e_max_syst_before": e_max_syst(before.errors_cw, before.errors_ccw),
               "e_max_syst_after": e_max_syst(after.errors_cw, after.errors_ccw)}
    return VirtualUmbmark(summary, before.errors_cw, before.errors_ccw, after.errors_cw, after.errors_ccw)


@dataclass(frozen=True)
class DemoData:
    """What the demo computed that its summary does not hold: the runs and their tracks
    (robot file's noise), the robots, the two checks and the controller snippet."""

    runs: Sequence[OdometryLog]
    tracks: Sequence[tuple[str, Track, NDArray[np.float64]]]
    robot: DiffDrive
    calibrated: DiffDrive
    noise: tuple[NoiseModel, ...]
    monte_carlo: MonteCarloCheck
    virtual: VirtualUmbmark
    controller_yaml: str
    side: float  # of the squares [m]


# ------------------------------------------------------------------------------------ sections
def _dead_reckoning(data: DemoData, figures: ReportFigures) -> Section:
    from odomkit.track import dead_reckon_log
    from odomkit.windows import cumulative_travel

    (name, track, _), run = data.tracks[0], data.runs[0]
    ccw = next(((n, t, g) for (n, t, g), r in zip(data.tracks, data.runs, strict=True)
                if _direction(r) == "ccw"), data.tracks[-1])
    blocks: list[Any] = [Paragraph(
        "Six runs of a 0.75 m UMBmark square (three clockwise, three counter-clockwise) by a small "
        "differential robot, its wheel encoders logged at 20 Hz and its pose tracked by OptiTrack. "
        "Dead reckoning with the robot file's nominal geometry, and the covariance of its guessed "
        "per-wheel noise (k = 1 mm/√m).")]

    def tracks(plot: ModuleType, ax: list[Axes]) -> None:
        for a, (label, t, g) in zip(ax, (data.tracks[0], ccw), strict=True):
            plot.draw_track(a, t.poses, t.cov, truth=g, label=f"{label} odometry")

    fig = figures.draw(("draw_track",), tracks, "One clockwise and one counter-clockwise run: the "
                       "odometry (solid) with its 95 % position ellipses, and the OptiTrack truth (dashed). "
                       "The ellipses are the guessed noise's; the held-out test below shows they are far "
                       "too small.", "Two runs with their ellipses", panels=(1, 2), size=(10.0, 4.8))
    blocks += [f for f in (fig,) if f is not None]
    if track.cov is not None:
        cov = track.cov
        s = cumulative_travel(track.steps)
        fig = figures.draw(("draw_covariance_elements",), lambda plot, ax: plot.draw_covariance_elements(
            ax, s, cov, s_label="distance travelled [m]"),
            f"The six covariance elements of {name} along its path (as Kelly 2004, Fig. 3): the "
            "variances step up at each turn on the spot, where the heading uncertainty is made.",
            "Covariance elements over distance", panels=(2, 3), size=(10.0, 5.6))
        blocks += [f for f in (fig,) if f is not None]
    methods = {m: dead_reckon_log(run, data.robot, m).poses for m in ("exact", "midpoint", "euler")}
    s = cumulative_travel(track.steps)
    fig = figures.draw(("draw_method_differences",), lambda plot, ax: plot.draw_method_differences(
        ax[0], s, methods, reference="exact", s_label="distance travelled [m]"),
        f"How far the midpoint and Euler integration of {name} drift from the exact arc integration at "
        "20 Hz: far below the encoder's own error, so the method does not matter at this rate.",
        "Integration method differences", size=(7.0, 3.8))
    blocks += [f for f in (fig,) if f is not None]
    return Section("dead-reckoning", "Dead reckoning with covariance", tuple(blocks))


def _direction(run: OdometryLog) -> str:
    from odomkit.calibrate.realdata import run_direction

    return run_direction(run)


def _prediction(mc: MonteCarloCheck, side: float, figures: ReportFigures) -> Section:
    s = mc.summary
    rows: tuple[tuple[str | Cell, ...], ...] = tuple(
        (axis, number(p, unit, 3, key=f"predicted_std.{axis}"),
         number(q, unit, 3, key=f"simulated_std.{axis}"))
        for axis, unit, p, q in zip(("x", "y", "θ"), ("m", "m", "rad"), s["predicted_std"],
                                    s["simulated_std"], strict=True))
    blocks: list[Any] = [
        Paragraph(f"The error of one planned {side:g} m square (four legs, four right turns on the spot) "
                  "with the guessed wheel noise, predicted in closed form (first-order propagation, "
                  f"Chong–Kleeman) and checked against {s['runs']} simulated runs with fresh noise at every "
                  "step."),
        Table(("", "predicted σ", "simulated σ"), rows, "End of one square"),
        Paragraph(f"Verdict of the statistical checks (mean, covariance, NEES): {s['verdict']}.", "note"),
    ]
    fig = figures.draw(("draw_monte_carlo",), lambda plot, ax: plot.draw_monte_carlo(
        ax[0], mc.endpoints, mc.pose, mc.cov), "The simulated end points and the predicted 95 % ellipse: "
        "about 95 % of them fall inside when the prediction is right.", "Monte Carlo end points and ellipse",
        size=(6.0, 5.0))
    blocks += [f for f in (fig,) if f is not None]
    return Section("prediction", "A closed-form prediction checked by Monte Carlo", tuple(blocks))


def _umbmark_rows(before: float, after: float, prefix: str,
                  after_label: str = "E_max,syst after") -> list[tuple[str | Cell, ...]]:
    return [("E_max,syst before", number(before, "mm", 4, key=f"{prefix}e_max_syst_before", scale=1e3)),
            (after_label, number(after, "mm", 4, key=f"{prefix}e_max_syst_after", scale=1e3))]


def _virtual(v: VirtualUmbmark, figures: ReportFigures) -> Section:
    s = v.summary
    rows = _umbmark_rows(s["e_max_syst_before"], s["e_max_syst_after"], "virtual.")
    rows += [(f"{k} (true {s['true'][k]:g})", number(s["estimated"][k], "", 6, key=f"virtual.{k}"))
             for k in ("E_d", "E_b")]
    blocks: list[Any] = [
        Paragraph(f"Borenstein and Feng's UMBmark on a virtual robot whose right wheel is "
                  f"{s['true']['E_d']:g} times the left and whose wheel base is {s['true']['E_b']:g} times "
                  f"the nominal: {s['runs_per_direction']} runs each way round a {s['side']:g} m square, the "
                  "return errors' centres of gravity give E_d and E_b, and the corrected robot drives the "
                  "square again."),
        Table(("", "value"), tuple(rows), "Virtual UMBmark"),
    ]
    fig = figures.draw(("draw_umbmark",), lambda plot, ax: plot.draw_umbmark(
        ax[0], v.cw, v.ccw, cw_after=v.cw_after, ccw_after=v.ccw_after),
        "Return position errors of the clockwise and counter-clockwise runs, their centres of gravity and "
        "E_max,syst, before and after calibration (as Borenstein–Feng Fig. 6 and 11).",
        "Virtual UMBmark before and after", size=(9.6, 5.6))
    blocks += [f for f in (fig,) if f is not None]
    return Section("virtual-umbmark", "UMBmark calibration of a virtual robot", tuple(blocks))


def _real_calibration(summary: dict[str, Any], data: DemoData, figures: ReportFigures) -> Section:
    from odomkit.calibrate.realdata import return_errors_from_runs

    c = summary["calibration"]
    rows = _umbmark_rows(c["e_max_syst_before"], c["exact"]["e_max_syst_after"], "calibration.exact.",
                         "E_max,syst after the exact fit")
    rows.insert(1, ("E_max,syst after UMBmark", number(c["umbmark"]["e_max_syst_after"], "mm", 4,
                                                      key="calibration.umbmark.e_max_syst_after", scale=1e3)))
    rows += [(k, number(c["exact"][k], "", 6, key=f"calibration.exact.{k}")) for k in ("E_d", "E_b")]
    blocks: list[Any] = [
        Paragraph(f"The real robot calibrated on its six runs of experiment {c['experiment']}: UMBmark from "
                  "the return errors, and the exact least-squares fit of the end poses (odomkit calibrate). "
                  "OptiTrack judges both: E_max,syst is the larger distance of a direction's mean return "
                  "error from the start."),
        Table(("", "value"), tuple(rows), "Real-data calibration"),
    ]
    cw, ccw = return_errors_from_runs(data.runs, data.robot)
    cw_after, ccw_after = return_errors_from_runs(data.runs, data.calibrated)
    fig = figures.draw(("draw_umbmark",), lambda plot, ax: plot.draw_umbmark(
        ax[0], cw, ccw, cw_after=cw_after, ccw_after=ccw_after),
        "Return position errors of the six real runs with the nominal and with the calibrated (exact fit) "
        "parameters.", "Real UMBmark before and after", size=(9.6, 5.6))
    blocks += [f for f in (fig,) if f is not None]
    return Section("calibration", "Calibration on real data", tuple(blocks))


def _lengths(windows: str | Sequence[str]) -> str:
    """``"10s"`` or ``["10s", "30s"]`` -> "10 s" or "10 s and 30 s"."""
    from odomkit.windows import parse_window

    specs = [parse_window(w) for w in ([windows] if isinstance(windows, str) else windows)]
    return " and ".join(f"{s.length:g} {'s' if s.unit == 's' else 'm'}" for s in specs)


def _honesty(summary: dict[str, Any], figures: ReportFigures) -> Section:
    h = summary["noise_honesty"]
    fit, held, models = h["fit"], h["held_out"], h["models"]
    blocks: list[Any] = [Paragraph(
        f"The noise is fitted (maximum likelihood, odomkit fit-noise) on {fit['runs']} runs of three "
        f"experiments ({', '.join(fit['kinds'])}) in {_lengths(fit['window'])} windows, and scored on "
        f"{held['runs']} runs of three others ({', '.join(held['kinds'])}) it never saw: each window "
        "restarts from OptiTrack, so its end is an independent sample. Honest noise puts 50 / 90 / 95 / "
        "99 % of the ends inside its 50 / 90 / 95 / 99 % ellipses and keeps the mean NEES inside its "
        "bounds.")]
    for window in held["windows"]:
        n = models["guessed"][window]["windows"]
        blocks.append(coverage_table([(NAMES[k], models[k][window]["coverage"], f"{k}.{window}.coverage")
                                      for k in NAMES], f"{n} held-out {_lengths(window)} window ends"))
    rows: tuple[tuple[str | Cell, ...], ...] = tuple(
        (NAMES[k], *(number(models[k][w]["nees_position_mean"], "", 3, key=f"{k}.{w}.nees_position_mean")
                     for w in held["windows"]))
        for k in NAMES)
    bounds: tuple[str | Cell, ...] = ("95 % bounds for an honest noise", *(Cell(
        f"{models['guessed'][w]['nees_bounds'][0]:.2f} … {models['guessed'][w]['nees_bounds'][1]:.2f}")
        for w in held["windows"]))
    blocks.append(Table(("noise", *(f"NEES mean, {_lengths(w)} windows" for w in held["windows"])),
                        (*rows, bounds), "Mean position NEES of the window ends (ideal 2)"))

    def draw(plot: ModuleType, ax: list[Axes]) -> None:
        for a, window in zip(ax, held["windows"], strict=True):
            plot.draw_reliability(a, {NAMES[k]: models[k][window]["coverage"] for k in NAMES},
                                  n_scored=models["guessed"][window]["windows"])
            a.set_title(f"held out, {_lengths(window)} windows")

    fig = figures.draw(("draw_reliability",), draw, "Reliability diagrams of the guessed and the fitted "
                       "noise on held-out data: the fraction of window ends inside each predicted "
                       "ellipse against its probability. On the diagonal is honest; below it, overconfident.",
                       "Held-out reliability diagrams", panels=(1, len(held["windows"])), size=(11.0, 5.2))
    blocks += [f for f in (fig,) if f is not None]
    params = models["white+bias"]["parameters"]
    blocks.append(Paragraph("Fitted white + bias noise (fitted_robot.toml): " + ", ".join(
        f"{k} = {v:.3g}" for k, v in params.items()) + ".", "note"))
    return Section("honesty", "The held-out honesty test", tuple(blocks))


def _summary(summary: dict[str, Any], data: DemoData) -> Section:
    c, h = summary["calibration"], summary["noise_honesty"]["models"]
    window = summary["noise_honesty"]["held_out"]["windows"][0]
    rows: list[tuple[str | Cell, ...]] = [
        ("E_max,syst of the real robot before → after calibration",
         Cell(f"{1e3 * c['e_max_syst_before']:.3g} mm → {1e3 * c['exact']['e_max_syst_after']:.3g} mm")),
        ("virtual UMBmark: E_max,syst before → after", Cell(
            f"{1e3 * data.virtual.summary['e_max_syst_before']:.3g} mm → "
            f"{1e3 * data.virtual.summary['e_max_syst_after']:.3g} mm")),
        ("closed-form prediction against Monte Carlo", Cell(data.monte_carlo.summary["verdict"])),
        (f"held out, {_lengths(window)} windows: inside the 95 % ellipse, guessed noise (ideal 0.95)",
         number(h["guessed"][window]["coverage"]["0.95"], key=f"guessed.{window}.coverage.0.95", decimals=2)),
        (f"held out, {_lengths(window)} windows: inside the 95 % ellipse, fitted white + bias",
         number(h["white+bias"][window]["coverage"]["0.95"], key=f"white+bias.{window}.coverage.0.95",
                decimals=2)),
    ]
    return Section("summary", "At a glance", (
        Paragraph("odomkit on built-in data (six OptiOdom experiments, MIT licence): dead reckoning with an "
                  "honest covariance, checked by simulation, calibrated, and its noise fitted and tested on "
                  "data it never saw. Each section below explains one line of this table."),
        Table(("", "value"), tuple(rows)),
    ))


def write_demo_report(path: str | Path, summary: dict[str, Any], data: DemoData, *,
                      overwrite: bool = False, outputs: Sequence[str] = ()) -> dict[str, Any]:
    """Lay out the demo's results and write the page to ``path`` (checked by the caller).

    Returns ``{"report": path, "sections": [keys], "warnings": [...]}``."""
    started = time.perf_counter()
    figures = ReportFigures()
    sections = [_summary(summary, data), _dead_reckoning(data, figures),
                _prediction(data.monte_carlo, data.side, figures), _virtual(data.virtual, figures),
                _real_calibration(summary, data, figures), _honesty(summary, figures),
                Section("ros", "ROS parameters", (
                    Paragraph("The calibrated robot as ROS 2 diff_drive_controller parameters, with the "
                              "twist covariance of the fitted white noise at the runs' mean speed (what "
                              "robot_localization fuses from /odom)."),
                    Code(data.controller_yaml, "diff_drive_controller (the demo also writes it without the "
                         "twist covariance, diff_drive_controller.yaml)")))]
    if outputs:
        sections.append(Section("files", "The files the demo wrote", (
            Paragraph("Beside this page: " + ", ".join(outputs) + ". The *_track.csv files hold each run's "
                      "track with its covariance; summary.json every number above."),)))
    footer = (f"Written by odomkit {__version__} (odomkit demo) in {time.perf_counter() - started:.1f} s. "
              "One file, no network: figures are embedded SVG.")
    page = render_report("odomkit demo: the whole product on built-in data", sections,
                         subtitle=["A differential robot: OptiOdom data (MIT licence), OptiTrack truth."],
                         warnings=figures.notes, footer=footer)
    written = write_page(path, page, overwrite)
    return {"report": str(written), "sections": [s.key for s in sections], "warnings": list(figures.notes)}
