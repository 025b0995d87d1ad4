"""``odomkit evaluate``: how wrong a track is, and how honest its covariance.

Two forms (docs/reference/commands/evaluate.md):

* :func:`evaluate_tracks` scores tracks written by ``odomkit track --out`` against truth
  (a truth file, or the track's own ``gt_*`` columns): every row inside the truth is an
  error sample, and its covariance is scored at every row.
* :func:`evaluate_logs` re-runs dead reckoning on logs: once from the truth at the first
  row (the whole-run figures: ATE, RPE, drift), and once per non-overlapping window from
  the truth at its start, scoring each window end against its predicted covariance (the
  honesty test: window ends are independent samples, the rows of one run are not).
* :func:`evaluate_in_memory` is the same for logs, truths and noise already in memory
  (:class:`~odomkit.log.OdometryLog`, :class:`~odomkit.truth.Truth`, noise models): the one
  scoring both use (:func:`~odomkit.workflows._score_logs.score_loaded`), so that the same
  inputs give the same dict.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from odomkit.errors import InputError
from odomkit.evaluate import NEAR_SINGULAR as NEAR_SINGULAR  # named here as before; defined in the core
from odomkit.evaluate import NO_ERROR as NO_ERROR
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.workflows._score_logs import (
    LoadedLog,
    score_by_window,
    score_loaded,
    score_logs,
    several_lengths_notes,
    white_only,
    window_specs,
)
from odomkit.workflows._scoring import FEW_WINDOW_ENDS as FEW_WINDOW_ENDS  # once defined here
from odomkit.workflows._scoring import (
    Scored,
    TrackRows,
    issue_notes,
    pooled_report,
    require_truth,
    score_rows,
    summarise,
)

if TYPE_CHECKING:
    from odomkit.io.trackio import TrackFile
    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.robot import Robot
    from odomkit.truth import Truth
    from odomkit.windows import WindowSpec
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["CONTAINMENT_NOTE", "evaluate_in_memory", "evaluate_logs", "evaluate_tracks", "score_logs",
           "Scored", "summarise", "TrackRows", "WHOLE_RUN_NOTE", "WINDOWED_NOTE"]

#: The one line every text report carries about what a single run's containment means.
CONTAINMENT_NOTE = (
    "a single run's containment fraction is one sample, not a statistic: the errors along a run are "
    "correlated (each pose inherits the error of the one before), so trust the windowed test "
    "(--robot --window), whose windows restart from truth and give independent samples")
WINDOWED_NOTE = (
    "each window restarts from truth, so window ends are independent samples of the random error (the "
    "windows of one log share its bias draw: with few logs coverage comes in lumps): this is the test to "
    "trust (coverage near 0.5/0.9/0.95/0.99 and NEES mean inside its bounds means an honest covariance)")
#: The note of ``evaluate --robot`` without ``--window``: one window per log, from its start.
WHOLE_RUN_NOTE = (
    "without --window each log is one window, scored at its end: one sample per log, too few to judge "
    "a covariance; --window 30s restarts windows from the truth and gives the test to trust")


def evaluate_tracks(
    tracks: str | Path | Sequence[str | Path],
    truth: TruthOptions | Sequence[TruthOptions] | None = None,
    *,
    align: str = "none",
    rpe_distances: Sequence[float] = (1.0,),
    min_travel: float = 0.05,
    progress: Progress = NO_PROGRESS,
    plot: str | Path | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """Score track CSVs (``odomkit track --out``) against truth.

    Parameters
    ----------
    tracks : track CSV paths (or one)
    truth : one :class:`~odomkit.workflows.truth.TruthOptions` per track, or one for every
        track; ``path`` None (and ``truth`` None) uses the track's ``gt_*`` columns.
    align : {"none", "start", "se2"}
    rpe_distances : true travel of each RPE [m]
    min_travel : a track whose truth travels less [m] is an error (nothing to score)
    progress : one stage, ``"tracks"``, a unit per track (:mod:`odomkit.progress`)
    plot, overwrite : draw the tracks against truth, the coverage diagram and the NEES of the
        rows into this .png, .svg or .pdf file (:func:`odomkit.workflows.figures.honesty_figure`;
        replaced only when ``overwrite``); adds ``outputs``

    Returns
    -------
    dict with the keys of docs/reference/commands/evaluate.md (the JSON of ``odomkit evaluate
    TRACK``), ``per_log`` and ``warnings``.
    """
    from odomkit.workflows.results import paths_given, truths_per_log

    tracks = paths_given(tracks, "track")
    truth = truths_per_log(truth, len(tracks), "track")
    _check_plot(plot, overwrite, [*tracks, *(t.path for t in truth if t.path is not None)])
    scored = []
    with stage(progress, len(tracks), "tracks"):
        for path, opts in zip(tracks, truth, strict=True):
            scored.append(_score_track(Path(path), opts, align, rpe_distances, min_travel))
            progress.advance()
    out = pooled_report(scored, rpe_distances, noun="tracks")
    issue_notes(out["warnings"])
    if plot is not None:
        out["outputs"] = {"plot": str(_honesty_plot(plot, scored, {"track rows": out["coverage"]}, None))}
    return out


def _score_track(path: Path, opts: TruthOptions, align: str, rpe_distances: Sequence[float],
                 min_travel: float) -> Scored:
    """One track file of :func:`evaluate_tracks` scored against its truth."""
    from odomkit.truth import no_overlap, truth_at

    track = _read_estimate(path)
    opts = opts.resolved()
    if opts.path is not None:
        found = require_truth(opts, None)
        samples = truth_at(found, track.t, opts.max_gap)
        ref, valid = samples.poses, samples.valid
        if np.count_nonzero(valid) < 2:
            raise InputError(no_overlap(found, track.t), source=str(path))
    elif track.truth is not None:
        ref, valid = track.truth, np.isfinite(track.truth[:, 0]) & np.isfinite(track.truth[:, 1])
    else:
        raise InputError("no truth: give --truth, or a track written with truth (gt_* columns)",
                         source=str(path))
    return score_rows(str(path), track.poses, track.cov, ref, valid, align=align,
                      truth_sigma=opts.sigma or 0.0, rpe_distances=rpe_distances,
                      min_travel=min_travel, honesty_from_rows=True, t=track.t,
                      truth_heading_sigma=opts.heading_sigma or 0.0)


def _read_estimate(path: Path) -> TrackFile:
    """A track CSV (``odomkit track --out``, found by its header), else any pose file that
    truth can be (TUM, KITTI rows with time, headerless ``t,x,y,theta``) without covariance."""
    from odomkit.io.trackio import read_pose_file

    return read_pose_file(path, "track")


def evaluate_logs(
    logs: str | Path | Sequence[str | Path],
    robot_path: str | Path,
    truth: TruthOptions | Sequence[TruthOptions] | None = None,
    *,
    log_options: LogOptions | None = None,
    window: str | Sequence[str] | None = None,
    min_travel: float = 0.05,
    align: str = "none",
    rpe_distances: Sequence[float] = (1.0,),
    method: str = "exact",
    progress: Progress = NO_PROGRESS,
    plot: str | Path | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """The honesty test: dead reckoning restarted from truth in each window, scored at its end.

    :func:`score_logs` pooled by :func:`summarise`, with each log's own figures; each window
    length on its own (windows of different lengths overlap, so their ends are not
    independent samples of one test, and the χ² bounds would not hold for them pooled).

    For logs, truths and noise already in memory: :func:`evaluate_in_memory`, which this
    calls the scoring of, log by log as each is read.

    Parameters
    ----------
    logs : log paths (or one)
    robot_path : robot file with a ``[noise]`` table (without one: the whole runs' errors
        alone, and ``--window`` is refused)
    truth : one :class:`~odomkit.workflows.truth.TruthOptions` per log, or one for every
        log; None: each log's own truth (its ``gt_*`` columns, an OptiOdom or Snowhite log's)
    log_options : how to read the logs
    window : ``"30s"`` or ``"5m"``, or several such lengths, each scored on its own; None for
        one window per log from its first row
    min_travel : windows whose odometry travels less [m] are left out and counted
    align : alignment of the whole-run track for ATE (see :func:`evaluate_tracks`)
    rpe_distances : true travel of each RPE [m]
    method : integration method
    progress : one stage, ``"logs"``, a unit per log read and scored (:mod:`odomkit.progress`)
    plot, overwrite : draw the whole runs against truth, the coverage diagram of the window
        ends (the robot file's noise and, when it has bias models, its white models alone)
        and their NEES into this .png, .svg or .pdf file
        (:func:`odomkit.workflows.figures.honesty_figure`; of the first window length); adds
        ``outputs``

    Returns
    -------
    dict with the keys of docs/reference/commands/evaluate.md (the JSON of ``odomkit evaluate
    --robot``), ``window`` (the length scored, ``"30 s"`` or ``"5 m"``; None without one),
    ``per_log`` and ``warnings``, also issued as UserWarnings. With several lengths the keys
    are the first length's (as a caller that asks for one reads them, and ``window`` names
    it), and ``by_window`` {length: the keys of that length alone}; ``warnings`` then has the
    whole runs' once and each length's own with the length before it (``"10 s windows: ..."``).
    ``nees_position_mean`` here is the mean over window ends, each restarted from the truth
    (one per log without ``window``), not over a track's rows as in ``odomkit track --json``'s
    ``ground_truth`` (:func:`odomkit.evaluate.evaluate_track`).
    """
    from odomkit.workflows.results import paths_given, truths_per_log

    logs = paths_given(logs, "log", "odomkit.workflows.evaluate.evaluate_in_memory")
    truth = truths_per_log(truth, len(logs))
    _check_plot(plot, overwrite, [*logs, robot_path, *(t.path for t in truth if t.path is not None)])
    specs = window_specs(window)
    by_spec = score_by_window(logs, robot_path, truth, specs, log_options=log_options,
                              min_travel=min_travel, align=align, rpe_distances=rpe_distances,
                              method=method, progress=progress, errors_only=True)
    out = _pooled(specs, by_spec, rpe_distances)
    if plot is not None:
        from odomkit.io.robotfile import read_robot

        robot, noise = read_robot(robot_path)

        def white_alone(white: Sequence[NoiseModel]) -> Sequence[Scored]:
            from odomkit.workflows.truth import resolved_truth

            return white_only(logs, robot, white, resolved_truth(robot_path, truth), log_options, specs[0],
                              min_travel, method)

        out["outputs"] = {"plot": str(_plotted(plot, out, by_spec[0], noise, specs[0], white_alone))}
    return out


def _plotted(plot: str | Path, out: dict[str, Any], scored: Sequence[Scored], noise: Sequence[NoiseModel],
             spec: WindowSpec | None, white_alone: Callable[[Sequence[NoiseModel]], Sequence[Scored]]
             ) -> Path:
    """The ``--plot`` of :func:`evaluate_logs` and :func:`evaluate_in_memory` alike: the runs,
    the coverage of the window ends (``out``'s, of the first window length ``spec``) with the
    ``noise`` given and, where it has bias models, with its white models alone
    (``white_alone(white models)`` scores the logs with those), and the heading's where the
    truth has one."""
    from odomkit.evaluate import coverage

    kinds = {m.kind for m in noise}
    both = " + ".join(sorted(kinds, reverse=True))
    name = "window ends" if kinds == {"white"} else f"window ends ({both})"
    covers = {name: out["coverage"]}
    if kinds > {"white"}:  # the white models alone, for comparison
        alone = white_alone([m for m in noise if m.kind == "white"])
        covers["window ends (white only)"] = coverage(np.concatenate([a.honesty_errors for a in alone]),
                                                      np.concatenate([a.honesty_cov for a in alone]))
    counts = dict.fromkeys(covers, out["windows"])
    if out.get("coverage_heading") is not None:  # the heading's intervals, where the truth has one
        covers[f"{name}, heading"] = out["coverage_heading"]
        counts[f"{name}, heading"] = sum(end["nees_heading"] is not None for one in out["per_log"]
                                         for end in one.get("window_ends", ()))
    return _honesty_plot(plot, scored, covers, counts, None if spec is None else str(spec))


def evaluate_in_memory(
    logs: OdometryLog | Sequence[OdometryLog],
    robot: Robot,
    noise: NoiseModel | Sequence[NoiseModel] | None,
    truths: Truth | Sequence[Truth | None] | None = None,
    *,
    truth_noise: Mapping[str, float] | None = None,
    window: str | Sequence[str] | None = None,
    min_travel: float = 0.05,
    max_gap: float | None = 0.5,
    align: str = "none",
    rpe_distances: Sequence[float] = (1.0,),
    method: str = "exact",
    progress: Progress = NO_PROGRESS,
    plot: str | Path | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """:func:`evaluate_logs` for logs already in memory: the honesty test, dead reckoning
    restarted from truth in each window and scored at its end, and the whole-run errors.

    The same scoring as ``odomkit evaluate LOG --robot ROBOT`` (one path: both call
    :func:`~odomkit.workflows._score_logs.score_loaded`), with the command's defaults; the
    same inputs give the same dict.

    Parameters
    ----------
    logs : OdometryLog or sequence of OdometryLog
        The logs (read by :mod:`odomkit.io` readers, or built from arrays).
    robot : Robot
    noise : NoiseModel, sequence of NoiseModel, or None
        The noise whose covariance is tested (a robot file's ``[noise]``, or
        :func:`odomkit.workflows.fit_noise.fit_noise_in_memory`'s ``noise``); None or empty:
        the whole runs' errors alone (a ``window`` is then refused).
    truths : Truth, sequence of Truth or None, or None
        One per log (None: the log's own ground truth, :func:`odomkit.truth.truth_from_log`),
        or one for every log; on the log's clock.
    truth_noise : mapping, optional
        The truth's own noise, added at every window's start and end: ``sigma`` [m],
        ``heading_sigma`` [rad], ``time_sigma`` [s], as a robot file's ``[truth]`` holds it
        (:func:`odomkit.io.robotfile.read_truth_table`, or ``fit_noise_in_memory``'s
        ``truth``); it replaces each truth's own. None: each truth's own fields (zero by
        default).
    window : ``"30s"`` or ``"5m"``, or several lengths, each scored on its own; None: one
        window per log from its first row
    min_travel : windows whose odometry travels less [m] are left out and counted
    max_gap : longest gap between the truth's fixes to interpolate across [s] (None: no limit)
    align, rpe_distances, method, progress : as :func:`evaluate_logs`
    plot, overwrite : as :func:`evaluate_logs`: the runs against truth, the coverage diagram
        of the window ends (with ``noise``'s white models alone beside it where it has bias
        models) and their NEES, into this .png, .svg or .pdf file; adds ``outputs``

    Returns
    -------
    dict
        As :func:`evaluate_logs` (the JSON of ``odomkit evaluate --robot``, with ``outputs``
        only where ``plot`` is given); ``per_log`` names each log by its ``source``. Its ``warnings`` are also
        issued as UserWarnings.

    Examples
    --------
    >>> from odomkit.data import builtin_data_path
    >>> from odomkit.io.optiodom import read_run
    >>> from odomkit.io.robotfile import read_robot
    >>> robot, noise = read_robot(builtin_data_path("optiodom_diff.toml"))
    >>> log = read_run(builtin_data_path("230620202042_run-01.csv"))
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     out = evaluate_in_memory(log, robot, noise, window="10s")
    >>> out["windows"], out["coverage_overall"]
    (9, 'optimistic')
    """
    from odomkit.workflows.results import logs_given, noise_models, truths_given

    given = logs_given(logs, "odomkit.workflows.evaluate.evaluate_logs")
    _check_plot(plot, overwrite, [])
    truth = truths_given(truths, given, truth_noise)
    models: tuple[NoiseModel, ...] = () if noise is None else noise_models(noise)
    specs = window_specs(window)

    def scored(with_models: Sequence[NoiseModel], lengths: Sequence[WindowSpec | None],
               shown: Progress = NO_PROGRESS) -> list[list[Scored]]:
        loaded = (LoadedLog(log, found, max_gap) for log, found in zip(given, truth, strict=True))
        return score_loaded(loaded, len(given), robot, tuple(with_models), lengths, min_travel=min_travel,
                            align=align, rpe_distances=rpe_distances, method=method, progress=shown,
                            errors_only=True)

    by_spec = scored(models, specs, progress)
    out = _pooled(specs, by_spec, rpe_distances)
    if plot is not None:
        def white_alone(white: Sequence[NoiseModel]) -> Sequence[Scored]:
            return scored(white, specs[:1])[0]

        out["outputs"] = {"plot": str(_plotted(plot, out, by_spec[0], models, specs[0], white_alone))}
    return out


def _pooled(specs: Sequence[WindowSpec | None], by_spec: Sequence[list[Scored]],
            rpe_distances: Sequence[float]) -> dict[str, Any]:
    """The report of :func:`evaluate_logs` and :func:`evaluate_in_memory`: each window
    length's pooled figures (the first's at the top, all in ``by_window`` with several),
    an error where no length scored a window end, and the warnings, issued."""
    reports = [pooled_report(scored, rpe_distances, None if spec is None else str(spec))
               for spec, scored in zip(specs, by_spec, strict=True)]
    _unscored_lengths(specs, by_spec, reports)
    out = dict(reports[0])
    if len(reports) > 1:
        out["warnings"] = several_lengths_notes(by_spec, reports)
        out["by_window"] = {r["window"]: r for r in reports}
    issue_notes(out["warnings"], stacklevel=4)  # the caller of evaluate_logs or evaluate_in_memory
    return out


def _unscored_lengths(specs: Sequence[Any], by_spec: Sequence[Sequence[Scored]],
                      reports: list[dict[str, Any]]) -> None:
    """An error when no window end of any ``--window`` length could be scored (every window
    left out: a test of nothing, which used to end with "this is the test to trust" and exit
    0), naming why and what to do; where other lengths were scored, a warning in each
    unscored length's report instead."""
    empty = [i for i, (spec, r) in enumerate(zip(specs, reports, strict=True))
             if spec is not None and r["windows"] == 0]
    if not empty:
        return
    from odomkit.window_errors import HEADLESS
    from odomkit.workflows._score_logs import STILL

    whys: list[str] = []
    reasons: set[str] = set()
    for i in empty:
        counts: dict[str, int] = {}
        for s in by_spec[i]:
            for what, n in s.left_out:
                counts[what] = counts.get(what, 0) + n
        reasons |= counts.keys()
        whys.append("; ".join(f"{n} {what}" for what, n in counts.items()) or "every window was left out")
    still = STILL.split("{")[0]  # its minimum travel is filled in
    advice = []
    if any(what.startswith(HEADLESS) for what in reasons):  # (the windows named after it)
        advice.append("longer windows (each must start where the fixes give a heading: the robot moving, "
                      "fixes on both sides) or truth with heading")
    if any(what.startswith(still) for what in reasons):
        advice.append("longer windows or a smaller --min-travel")
    todo = " or ".join(advice) or "longer windows"
    if len(empty) == sum(spec is not None for spec in specs):
        said = "; ".join(f"{specs[i]} windows: {w}" if len(empty) > 1 else w
                         for i, w in zip(empty, whys, strict=True))
        logs = by_spec[empty[0]]
        raise InputError(f"no window end could be scored, so there is no honesty test: {said}; use {todo}",
                         source=logs[0].label if len(logs) == 1 else None)
    for i, why in zip(empty, whys, strict=True):
        reports[i]["warnings"].append(f"no window end could be scored ({why}): this length tests nothing; "
                                      f"use {todo}")


def _check_plot(plot: str | Path | None, overwrite: bool, inputs: Sequence[str | Path]) -> None:
    if plot is not None:
        from odomkit.io.files import check_outputs
        from odomkit.plot import check_plot_file

        check_outputs({"--plot": plot}, overwrite=overwrite, inputs=inputs)
        check_plot_file(plot)


def _honesty_plot(plot: str | Path, scored: Sequence[Scored], coverages: dict[str, dict[str, float | None]],
                  windows: dict[str, int] | None, length: str | None = None) -> Path:
    """``evaluate --plot``: each run against truth, the coverage and the NEES of the scored
    samples (window ends when ``windows``, the ends behind each coverage series, is given,
    else track rows; ``length`` the window length, named in the figure's note)."""
    from odomkit.evaluate import nees
    from odomkit.workflows.figures import honesty_figure

    tracks = [(Path(s.label).name, s.rows.poses, s.rows.cov, s.rows.truth)
              for s in scored if s.rows is not None]
    values = [nees(s.honesty_errors, s.honesty_cov) if s.honesty_errors.shape[0] else np.empty(0)
              for s in scored]
    if windows is not None:
        times = [s.honesty_t for s in scored]
        note = ("window ends restart from truth: independent samples" if length is None else
                f"{length} window ends restart from truth: independent samples")
    else:
        times = [s.rows.t if s.rows is not None and s.rows.t.size == v.size
                 else np.arange(v.size, dtype=float) for s, v in zip(scored, values, strict=True)]
        note = "rows of one run are correlated: the fraction inside is one draw, not a statistic"
    if len(scored) == 1 and times[0].size:
        t, label = times[0] - times[0][0], "time since the first sample [s]"
    else:
        t, label = np.arange(sum(v.size for v in values), dtype=float), "sample (all files, in order)"
    return honesty_figure(plot, coverages=coverages, n_scored=windows or None, nees_t=t,
                          nees=np.concatenate(values) if values else np.empty(0), nees_label=label,
                          tracks=tracks, note=note)
