"""The ``--plot FILE`` figure of each command, drawn from what its workflow computed.

Each function lays out one figure with the :mod:`odomkit.plot` functions and writes it
(.png, .svg or .pdf from the suffix); the workflow has checked the path up front
(:func:`odomkit.io.files.check_outputs`, :func:`odomkit.plot.check_plot_file`). matplotlib
loads only here, when a figure is asked for.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from odomkit.calibrate.profile import Profile
    from odomkit.log import OdometryLog
    from odomkit.path import Segment
    from odomkit.propagate.plan import NoiseArg
    from odomkit.robot import Robot
    from odomkit.workflows.track import TrackRun

__all__ = ["calibration_figure", "honesty_figure", "predict_figure", "profiles_figure",
           "simulate_figure", "track_figure", "umbmark_figure"]

_ELEMENTS = [["sxx", "syy", "stt"], ["sxy", "sxt", "syt"]]
_BAND = ["ex", "ey", "et"]


def _panels(axes: Mapping[str, Axes], names: Sequence[str]) -> list[Axes]:
    return [axes[n] for n in names]


def track_figure(path: str | Path, run: TrackRun, robot: Robot) -> Path:
    """``odomkit track --plot``: the track with its 95 % ellipses against the truth, how far
    the midpoint and Euler integrations drift from the exact one, the six covariance
    elements over time and, with truth and covariance, the true error in its ±2σ band."""
    from odomkit.plot import (
        draw_covariance_elements,
        draw_error_band,
        draw_method_differences,
        draw_track,
        new_figure,
        save_figure,
    )
    from odomkit.track import dead_reckon_log

    track, log = run.track, run.log
    truth = run.truth if run.truth is not None else log.ground_truth
    t = track.t - track.t[0]
    mosaic = [["track", "track", "methods"], ["track", "track", "methods"]]
    if track.cov is not None:
        mosaic += _ELEMENTS
    if track.cov is not None and truth is not None:
        mosaic.append(_BAND)
    fig, axes = new_figure(mosaic=mosaic, size=(14.0, 3.4 * len(mosaic)))
    assert isinstance(axes, dict)
    draw_track(axes["track"], track.poses, track.cov, truth=truth)
    against = " against truth" if truth is not None else ""
    axes["track"].set_title(f"{Path(log.source).name}: dead reckoning{against}")
    others = {m: dead_reckon_log(log, robot, m, track.poses[0]).poses for m in ("exact", "midpoint", "euler")}
    draw_method_differences(axes["methods"], t, others, reference="exact", s_label="time since start [s]")
    axes["methods"].set_title("integration methods against exact arcs")
    if track.cov is not None:
        draw_covariance_elements(_panels(axes, _ELEMENTS[0] + _ELEMENTS[1]), t, track.cov,
                                 s_label="time since start [s]")
        if truth is not None:
            sigma = np.sqrt(np.clip(np.einsum("nii->ni", track.cov), 0.0, None))
            draw_error_band(_panels(axes, _BAND), t, track.poses - truth, sigma,
                            t_label="time since start [s]")
            axes["ex"].set_title("true error and the predicted ±2σ (a run's rows are correlated)", loc="left")
    return save_figure(fig, path)


def predict_figure(path: str | Path, segments: Sequence[Segment], noise: NoiseArg,
                   wheel_base: float | None, *,
                   pose0: ArrayLike, cov0: ArrayLike | None, end_pose: ArrayLike, end_cov: ArrayLike,
                   compass_period: float | None = None, partitions: int | None = None,
                   robot: Robot | None = None, sample_period: float | None = None) -> Path:
    """``odomkit predict --plot``: the planned path with its 95 % ellipses and the six
    covariance elements over the distance travelled.

    The covariance along the path is the step recursion (:func:`odomkit.propagate.recursion.track_covariance`)
    on the path cut into equal steps (:func:`odomkit.propagate.paths.path_steps`); its end
    is replaced by the prediction printed (``end_pose``, ``end_cov``), which it approaches
    as the steps shrink."""
    from odomkit.integrate import dead_reckon
    from odomkit.plot import draw_covariance_elements, draw_track, new_figure, save_figure
    from odomkit.propagate.paths import check_segments, path_model, path_steps
    from odomkit.propagate.recursion import track_covariance

    model = path_model(noise, None if robot is not None else wheel_base, compass_period=compass_period,
                       robot=robot, sample_period=sample_period)
    segs = check_segments(segments, model)
    p0 = np.asarray(pose0, dtype=float)
    c0 = np.zeros((3, 3)) if cov0 is None else np.asarray(cov0, dtype=float)
    c0 = np.diag(c0) if c0.shape == (3,) else c0
    if model.family == "classical":
        n = partitions or 1  # its answer depends on the pieces: draw the ones predicted
    else:
        n = max(1, 2000 // max(len(segs), 1))
    steps = path_steps(segs, model, n, theta0=float(p0[2]))
    poses = dead_reckon(steps.dd, steps.dtheta, p0, "exact")
    cov = track_covariance(steps, poses, model.noise, c0, "exact", "recursion")
    poses[-1], cov[-1] = end_pose, end_cov
    if "d_left" in steps.inputs:  # wheel travel: a spin on the spot moves on the axis too
        moved = 0.5 * (np.abs(steps.inputs["d_left"]) + np.abs(steps.inputs["d_right"]))
        s_label = "mean wheel travel [m]"
    else:
        moved, s_label = np.abs(steps.dd), "distance travelled [m]"
    s = np.concatenate(([0.0], np.cumsum(moved)))
    if s[-1] <= 0:
        s, s_label = np.arange(s.size, dtype=float), "step"
    fig, axes = new_figure(mosaic=[["path", "path", "path"], ["path", "path", "path"]] + _ELEMENTS,
                           size=(13.0, 13.0))
    assert isinstance(axes, dict)
    draw_track(axes["path"], poses, cov, label="planned path", n_ellipses=max(len(segs), 12))
    axes["path"].set_title(f"{model.family} model: predicted 95 % position ellipses along the path")
    draw_covariance_elements(_panels(axes, _ELEMENTS[0] + _ELEMENTS[1]), s, cov, s_label=s_label)
    return save_figure(fig, path)


def simulate_figure(path: str | Path, endpoints: ArrayLike, mean: ArrayLike, cov: ArrayLike, *,
                    runs: int, seed: int) -> Path:
    """``odomkit simulate --plot``: the runs' end poses with the predicted 95 % ellipse in
    the x–y, x–θ and y–θ planes (the Monte Carlo validation picture)."""
    from odomkit.plot import draw_monte_carlo, new_figure, save_figure

    e = np.asarray(endpoints, dtype=float)
    fig, axes = new_figure(1, 3, size=(15.0, 5.6))
    assert isinstance(axes, list)
    for ax, comps in zip(axes, ((0, 1), (0, 2), (1, 2)), strict=True):
        draw_monte_carlo(ax, e, mean, cov, components=comps)
    shown = "" if e.shape[0] == runs else f" (the first {e.shape[0]} of {runs} runs, same seed)"
    fig.suptitle(f"Monte Carlo end poses against the predicted covariance{shown}, seed {seed}")
    return save_figure(fig, path)


def umbmark_figure(path: str | Path, cw: ArrayLike, ccw: ArrayLike, *, cw_after: ArrayLike | None = None,
                   ccw_after: ArrayLike | None = None, title: str = "UMBmark return position errors") -> Path:
    """``odomkit umbmark --plot``: the return errors, centres of gravity and E_max,syst,
    before and (from logged runs) after calibration."""
    from odomkit.plot import draw_umbmark, new_figure, save_figure

    fig, axes = new_figure(size=(9.0, 6.0))
    assert isinstance(axes, list)
    draw_umbmark(axes[0], cw, ccw, cw_after=cw_after, ccw_after=ccw_after)
    axes[0].set_title(title)
    return save_figure(fig, path)


def calibration_figure(path: str | Path, runs: Sequence[OdometryLog], truths: Sequence[NDArray[np.float64]],
                       starts: Sequence[ArrayLike] | None, before: Robot, after: Robot | Sequence[Robot], *,
                       umbmark: tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike] | None = None,
                       fix_times: Sequence[NDArray[np.float64]] | None = None) -> Path:
    """``odomkit calibrate --plot``: every run dead-reckoned with the robot file's
    parameters and with the calibrated ones, against the truth; with square runs
    (``--side``) UMBmark's return errors before and after.

    ``truths`` holds each run's truth positions (K, 2 or 3) [m]. Without ``fix_times``,
    ``starts`` holds each run's start pose (3,) [m, m, rad] (the truth's at the log's first
    row). With ``fix_times`` (each run's (K,) fix times [s] on the log's clock, inside its
    span), the truth is position fixes (``calibrate --truth``, GPS) and ``starts`` is not
    used: as :func:`odomkit.calibrate.positions.calibrate_positions` does, each run's start
    pose is the least-squares fit to the fixes, here for each parameter set (an SE(2)
    alignment of the track at the fixes, :func:`odomkit.evaluate.umeyama_se2`); the fixes
    are drawn as points and a panel below shows each track's distance from every fix."""
    from odomkit.calibrate.stability import track_fitted_to_fixes
    from odomkit.plot import draw_track, draw_umbmark, new_figure, save_figure
    from odomkit.plot.spatial import legend
    from odomkit.track import dead_reckon_log

    afters = list(after) if isinstance(after, Sequence) else [after] * len(runs)
    top = ["before", "after"] + (["umbmark"] if umbmark is not None else [])
    mosaic = [top] + ([["error"] * len(top)] if fix_times is not None else [])
    if fix_times is None and starts is None:
        raise ValueError("calibration_figure needs the runs' start poses or the truth's fix times")
    fig, axes = new_figure(mosaic=mosaic, size=(6.0 * len(top), 6.0 + 3.4 * (len(mosaic) - 1)))
    assert isinstance(axes, dict)
    for i, (log, truth, robot) in enumerate(zip(runs, truths, afters, strict=True)):
        name, colour = Path(log.source).stem, f"C{i % 10}"
        for key, rob in (("before", before), ("after", robot)):
            if fix_times is None:
                assert starts is not None
                poses = dead_reckon_log(log, rob, "exact", starts[i]).poses
                draw_track(axes[key], poses, truth=truth, label=name, color=colour)
                continue
            poses, error = track_fitted_to_fixes(log, rob, fix_times[i], truth)
            draw_track(axes[key], poses, truth=truth, label=name, color=colour, truth_label="truth fixes",
                       truth_points=True)
            _draw_fix_errors(axes["error"], fix_times[i] - log.t[0], error, colour=colour,
                             label=f"{name}, {'robot file' if key == 'before' else 'calibrated'}",
                             style="--" if key == "before" else "-")
    fitted = "\n(each run's start pose fitted to the truth fixes)" if fix_times is not None else ""
    for key, text in (("before", "robot file's parameters"), ("after", "calibrated parameters")):
        axes[key].set_title(f"dead reckoning with the {text}{fitted}")
        legend(axes[key], loc="upper left", bbox_to_anchor=(0.0, -0.1), ncols=2)
    if fix_times is not None:
        axes["error"].set_xlabel("time since the run's start [s]")
        axes["error"].set_ylabel("distance from the truth fix [m]")
        axes["error"].grid(True, lw=0.4, alpha=0.5)
        axes["error"].set_title("each track's distance from the truth's fixes (dashed: robot file's "
                                "parameters, solid: calibrated)", loc="left")
        legend(axes["error"], loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    if umbmark is not None:
        cw, ccw, cw_after, ccw_after = umbmark
        draw_umbmark(axes["umbmark"], cw, ccw, cw_after=cw_after, ccw_after=ccw_after)
        axes["umbmark"].set_title("UMBmark return errors")
        legend(axes["umbmark"], loc="upper left", bbox_to_anchor=(0.0, -0.1), ncols=2)
    return save_figure(fig, path)


def _draw_fix_errors(ax: Axes, t: NDArray[np.float64], error: NDArray[np.float64], *, colour: str, label: str,
                     style: str) -> None:
    """The distance |odometry − fix| [m] at each fix over time ``t`` [s], its RMS in the label."""
    from odomkit.plot.figure import thin

    d = np.hypot(error[:, 0], error[:, 1])
    rows = thin(d.size)
    ax.plot(t[rows], d[rows], style, color=colour, lw=1.1,
            label=f"{label} (RMS {float(np.sqrt(np.mean(d ** 2))):.3g} m)")


def honesty_figure(path: str | Path, *, coverages: Mapping[str, Mapping[str, float | None]],
                   n_scored: int | Mapping[str, int] | None, nees_t: ArrayLike, nees: ArrayLike,
                   nees_label: str,
                   tracks: Sequence[tuple[str, NDArray[np.float64], NDArray[np.float64] | None,
                                          NDArray[np.float64]]] = (),
                   note: str = "") -> Path:
    """``odomkit evaluate --plot``: the tracks against truth (when given: label, poses
    (N, 3), covariance (N, 3, 3) or None, truth (N, 3)), the coverage (reliability)
    diagram and the NEES of every scored sample."""
    from odomkit.plot import draw_nees, draw_reliability, draw_track, new_figure, save_figure
    from odomkit.plot.spatial import legend

    top = (["track", "track"] if tracks else []) + ["reliability"]
    mosaic = [top, top, ["nees"] * len(top)]
    fig, axes = new_figure(mosaic=mosaic, size=(5.0 * len(top), 11.0))
    assert isinstance(axes, dict)
    for i, (label, poses, cov, truth) in enumerate(tracks):
        draw_track(axes["track"], poses, cov, truth=truth, label=label, color=f"C{i % 10}")
    if tracks:
        axes["track"].set_title("whole runs against truth")
        if len(tracks) > 1:  # below the axes: a legend of many runs hides their ellipses
            legend(axes["track"], loc="upper center", bbox_to_anchor=(0.5, -0.08), ncols=3)
    draw_reliability(axes["reliability"], coverages, n_scored=n_scored)
    axes["reliability"].set_title("coverage of the predicted ellipses")
    draw_nees(axes["nees"], nees_t, nees, t_label=nees_label)
    if note:
        axes["nees"].set_title(note, fontsize="small", loc="left")
    return save_figure(fig, path)


def profiles_figure(path: str | Path, profiles: Sequence[Profile], *, units: Mapping[str, str] | None = None,
                    coverages: Mapping[str, Mapping[str, float | None]] | None = None,
                    n_scored: int | None = None, title: str = "") -> Path:
    """``odomkit fit-noise --plot`` and ``fit-amcl --plot``: each fitted parameter's profile
    likelihood with its interval, and (fit-noise) the in-sample coverage diagram."""
    from odomkit.plot import draw_profile, draw_reliability, new_figure, save_figure

    count = len(profiles) + (coverages is not None)
    cols = 2 if count == 4 else min(3, max(count, 1))
    rows = -(-count // cols)
    fig, axes = new_figure(rows, cols, size=(5.0 * cols, 4.6 * rows))
    assert isinstance(axes, list)
    for ax, prof in zip(axes, profiles, strict=False):
        draw_profile(ax, prof.values, prof.log_likelihood, interval=prof.interval, name=prof.name,
                     unit=(units or {}).get(prof.name, ""), estimate=prof.estimate, maximum=prof.maximum,
                     level=prof.level)
    if coverages is not None:
        draw_reliability(axes[len(profiles)], coverages, n_scored=n_scored)
        axes[len(profiles)].set_title("in-sample coverage of the window ends")
    for ax in axes[count:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    return save_figure(fig, path)
