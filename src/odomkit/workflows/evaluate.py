"""``odomkit evaluate``: how wrong a track is, and how honest its covariance.

Two forms (DESIGN.md, "``odomkit evaluate``"):

* :func:`evaluate_tracks` scores tracks written by ``odomkit track --out`` against truth
  (a truth file, or the track's own ``gt_*`` columns): every row inside the truth is an
  error sample, and its covariance is scored at every row.
* :func:`evaluate_logs` re-runs dead reckoning on logs: once from the truth at the first
  row (the whole-run figures: ATE, RPE, drift), and once per non-overlapping window from
  the truth at its start, scoring each window end against its predicted covariance (the
  honesty test: window ends are independent samples, the rows of one run are not).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError
from odomkit.progress import NO_PROGRESS, Progress, stage

if TYPE_CHECKING:
    from odomkit.io.trackio import TrackFile
    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.propagate.plan import NoiseArg
    from odomkit.robot import Robot
    from odomkit.truth import Truth, TruthSamples
    from odomkit.windows import WindowSpec
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["CONTAINMENT_NOTE", "evaluate_logs", "evaluate_tracks", "score_logs", "Scored", "summarise",
           "TrackRows", "WHOLE_RUN_NOTE", "WINDOWED_NOTE"]

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


@dataclass(frozen=True)
class Scored:
    """One track's or log's raw figures, kept for pooling over several."""

    label: str
    rows_evaluated: int
    rows_skipped: int
    position_errors: NDArray[np.float64]  # (n,) [m] at the evaluated rows, in time order
    path_length: float  # true travel over the evaluated rows [m]
    rpe: dict[str, NDArray[np.float64] | None]  # distance key -> pair error norms [m]
    honesty_errors: NDArray[np.float64]  # (m, 2) position errors scored against a covariance
    honesty_cov: NDArray[np.float64]  # (m, 2, 2)
    windows: int = 0
    warnings: list[str] = field(default_factory=list)
    # (m,) log time of each window end [s], for figures over time; empty when the honesty
    # samples are track rows
    honesty_t: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
    # (m,) log time of each window's start [s] (empty as honesty_t)
    honesty_t0: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
    # The evaluated rows themselves (the whole run of a log), for figures
    rows: TrackRows | None = None
    # Why a log asked for windows has none (None: it has some, or none were asked for)
    no_windows: str | None = None
    # Those of ``warnings`` about its windows (the others are about the whole run, alike for
    # every window length)
    window_notes: tuple[str, ...] = ()
    # Windows left out and why, (what, count): its warning reads "{label}: {count} {what}",
    # and several logs' are pooled into one line (:func:`_pooled_notes`)
    left_out: tuple[tuple[str, int], ...] = ()


@dataclass(frozen=True)
class TrackRows:
    """The evaluated rows of a track: time ``t`` (n,) [s], the estimate after alignment and
    the truth (n, 3) [m, m, rad; truth θ NaN if unknown], the estimate's covariance
    (n, 3, 3) or None."""

    t: NDArray[np.float64]
    poses: NDArray[np.float64]
    truth: NDArray[np.float64]
    cov: NDArray[np.float64] | None


def _rpe_key(distance: float) -> str:
    return f"{distance:g}"


def _score_rows(label: str, poses: NDArray[np.float64], cov: NDArray[np.float64] | None,
                truth: NDArray[np.float64], valid: NDArray[np.bool_], *, align: str,
                truth_sigma: float, rpe_distances: Sequence[float], min_travel: float,
                honesty_from_rows: bool, t: NDArray[np.float64] | None = None) -> Scored:
    """Score the rows of one track where ``valid``; ``truth`` (N, 3), θ NaN if unknown;
    ``t`` (N,) the rows' times, kept with them (:class:`TrackRows`) when given."""
    from odomkit.evaluate import align_track, relative_pose_errors

    notes: list[str] = []
    n = poses.shape[0]
    rows = np.flatnonzero(valid)
    if rows.size == 0:
        raise InputError("no row of the track has truth (its gt_* columns are empty)", source=label)
    est, ref = poses[rows], truth[rows]
    P = None if cov is None else cov[rows]
    path = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    if path < min_travel:
        raise InputError(f"the truth moves {path:.4g} m over the evaluated rows, less than --min-travel "
                         f"{min_travel:g} m: a robot standing still says nothing about odometry",
                         source=label)
    if align == "start" and not np.isfinite(ref[0, 2]):
        notes.append(f"{label}: the truth has no heading, so --align start only translates the track")
    if align == "se2" and P is not None and honesty_from_rows:
        notes.append(f"{label}: --align se2 fits the track to the truth, so its NEES and coverage do not "
                     "test the covariance; use --align none or start")
    est, P = align_track(est, ref, align, P)
    err = np.hypot(*(est[:, :2] - ref[:, :2]).T)
    rpe: dict[str, NDArray[np.float64] | None] = {}
    for d in rpe_distances:
        if not np.all(np.isfinite(ref[:, 2])):
            rpe[_rpe_key(d)] = None
            continue
        e = relative_pose_errors(est, ref, d, pairs="consecutive")
        rpe[_rpe_key(d)] = np.hypot(e[:, 0], e[:, 1]) if e.shape[0] else None
    if any(v is None for v in rpe.values()):
        why = ("the truth has no heading" if not np.all(np.isfinite(ref[:, 2]))
               else "the truth travels less than the distance")
        notes.append(f"{label}: no RPE over {', '.join(k for k, v in rpe.items() if v is None)} m ({why})")
    if honesty_from_rows and P is not None:
        he, hc = est[:, :2] - ref[:, :2], P[:, :2, :2] + truth_sigma**2 * np.eye(2)
        note = _singular_note(he, hc)
        if note:
            notes.append(f"{label}: {note}")
    else:
        he, hc = np.empty((0, 2)), np.empty((0, 2, 2))
        if honesty_from_rows:
            notes.append(f"{label}: the track has no covariance, so there is no NEES or coverage")
    kept = None if t is None else TrackRows(np.asarray(t, dtype=float)[rows], est, ref, P)
    return Scored(label, int(rows.size), int(n - rows.size), err, path, rpe, he, hc, 0, notes, rows=kept)


#: A scored covariance whose smallest eigenvalue is below this fraction of its largest
#: (standard deviations 1000× apart) is nearly singular (:func:`_singular_note`).
NEAR_SINGULAR = 1e-6
#: A position error [m] below this counts as none (a track started at the truth pose it is
#: compared with), so a singular covariance there loses nothing.
NO_ERROR = 1e-9


def _singular_note(errors: NDArray[np.float64], cov: NDArray[np.float64]) -> str | None:
    """One line on scored rows whose covariance (n, 2, 2) is singular or nearly so, where
    they matter, else None.

    A singular covariance has no NEES (:func:`odomkit.evaluate.nees` leaves the row out of
    the NEES and coverage): none is lost where the error is zero too (below
    :data:`NO_ERROR`: a track compared with the truth pose it started from), but a nonzero
    error's NEES would be infinite, and those rows are counted. A nearly singular one
    (:data:`NEAR_SINGULAR`) is kept: its NEES is well defined and true, but where the
    covariance comes from a pose known exactly (a track started at a truth pose with zero
    covariance) the error is mostly the truth's own noise, which the covariance lacks, and
    a few such rows make the whole mean; they are counted where they make more than half
    of the NEES summed over the rows.
    """
    from odomkit.evaluate import nees

    if cov.shape[0] == 0:
        return None
    values = nees(errors, cov)
    singular = ~np.isfinite(values)
    lam = np.linalg.eigvalsh(cov)  # ascending, per row
    near = ~singular & (lam[:, 0] < NEAR_SINGULAR * lam[:, 1])
    off = singular & (np.hypot(errors[:, 0], errors[:, 1]) > NO_ERROR)
    total = float(np.sum(values[~singular]))
    share = float(np.sum(values[near])) / total if total > 0 else 0.0
    parts = []
    if off.any():
        parts.append(f"{int(off.sum())} of {values.size} rows have a singular covariance but an error (an "
                     "infinite NEES) and are left out of the NEES and coverage")
    if share > 0.5:
        parts.append(f"{100 * share:.4g} % of the summed NEES comes from {int(near.sum())} of {values.size} "
                     "rows whose covariance is nearly singular (standard deviations over 1000x apart)")
    if not parts:
        return None
    return ("; ".join(parts) + ", as at the start of a track started from a truth pose with zero "
            "covariance: the truth's own noise alone falls far outside their ellipse, so their NEES "
            "judges the truth, not the covariance; give the truth's noise with --truth-sigma, or start "
            "the track with --initial-cov")


def summarise(scored: Sequence[Scored], rpe_distances: Sequence[float]) -> dict[str, Any]:
    """The output keys of DESIGN.md pooled over ``scored`` (without ``per_log``).

    Pooled: ``ate_rmse`` and each ``rpe`` are the RMS over every sample of every log,
    ``max_position_error`` the largest, ``final_position_error`` the mean of the logs'
    final errors, ``drift_percent`` 100 × Σ final errors / Σ true travel, and the NEES
    and coverage figures use every scored pose (window ends, or track rows).
    """
    from odomkit.evaluate import coverage, nees_summary

    err = np.concatenate([s.position_errors for s in scored])
    finals = np.array([s.position_errors[-1] for s in scored])
    travel = sum(s.path_length for s in scored)
    rpe: dict[str, float | None] = {}
    for d in rpe_distances:
        parts = [s.rpe[_rpe_key(d)] for s in scored]
        got = [p for p in parts if p is not None]
        rpe[_rpe_key(d)] = float(np.sqrt(np.mean(np.concatenate(got) ** 2))) if got else None
    he = np.concatenate([s.honesty_errors for s in scored])
    hc = np.concatenate([s.honesty_cov for s in scored])
    nees = nees_summary(he, hc) if he.shape[0] else {"mean": None, "median": None, "bounds": None}
    cover = coverage(he, hc) if he.shape[0] else {"0.5": None, "0.9": None, "0.95": None, "0.99": None}
    return {
        "rows_evaluated": int(sum(s.rows_evaluated for s in scored)),
        "rows_skipped": int(sum(s.rows_skipped for s in scored)),
        "final_position_error": float(finals.mean()),
        "max_position_error": float(err.max()),
        "ate_rmse": float(np.sqrt(np.mean(err**2))),
        "rpe": rpe,
        "drift_percent": float(100.0 * finals.sum() / travel) if travel > 0 else None,
        "windows": int(sum(s.windows for s in scored)),
        "nees_position_mean": nees["mean"],
        "nees_position_median": nees["median"],
        "nees_bounds": nees["bounds"],
        "coverage": cover,
        "inside_95_fraction": cover["0.95"],
    }


def _window_ends(s: Scored) -> dict[str, Any]:
    """``window_ends`` of a log scored in windows: each window's ``start`` and ``end`` [s, log
    time], its end's position ``error`` [m] (truth − odometry, x and y) and ``nees``, so that
    an outlier can be found and looked at; nothing for a whole-track score."""
    if not s.honesty_t0.size:
        return {}
    from odomkit.evaluate import nees

    q = nees(s.honesty_errors, s.honesty_cov)
    rows = zip(s.honesty_t0, s.honesty_t, s.honesty_errors, q, strict=True)
    return {"window_ends": [{"start": float(a), "end": float(b), "error": [float(e[0]), float(e[1])],
                             "nees": float(n)} for a, b, e, n in rows]}


def _report(scored: list[Scored], rpe_distances: Sequence[float], window: str | None = None,
            noun: str = "logs") -> dict[str, Any]:
    """The pooled figures, ``window`` (the length scored: ``"30 s"``, None for none or one
    window per log), ``per_log`` (each with its own ``warnings``), and ``warnings``: every
    log's, those that say the same of several logs in one line (:func:`_pooled_notes`)."""
    out: dict[str, Any] = {"window": window, **summarise(scored, rpe_distances)}
    out["per_log"] = [{"log": s.label, **summarise([s], rpe_distances), **_window_ends(s),
                       "warnings": list(s.warnings)} for s in scored]
    out["warnings"] = _pooled_notes(scored, noun)
    few = _few_ends_note(out["windows"])
    if few:
        out["warnings"].append(few)
    return out


def _pooled_notes(scored: Sequence[Scored], noun: str = "logs") -> list[str]:
    """The logs' warnings once each, where several logs left windows out for one reason (with
    their own counts) are one line with the total, and those that say the same of several
    logs are one line naming three (:func:`odomkit.workflows.results.grouped_warnings`)."""
    from odomkit.workflows.results import grouped_warnings, listed, short_names

    notes = list(dict.fromkeys(w for s in scored for w in s.warnings))
    counts: dict[str, list[tuple[str, int]]] = {}
    for s in scored:
        for what, n in s.left_out:
            counts.setdefault(what, []).append((s.label, n))
    for what, per_log in counts.items():
        if len(per_log) < 2:
            continue
        own = {f"{label}: {n} {what}" for label, n in per_log}
        at = min(notes.index(t) for t in own)
        labels = [label for label, _ in per_log]
        names = dict(zip(labels, short_names(labels, [s.label for s in scored]), strict=True))
        most = sorted(per_log, key=lambda item: -item[1])  # stable: the logs' order among equals
        each = listed([f"{names[label]}: {n}" for label, n in most])
        pooled = (f"{sum(n for _, n in per_log)} window(s) of {len(per_log)} {noun} "
                  f"{what.removeprefix('window(s) ')} ({each})")
        notes = [pooled if i == at else t for i, t in enumerate(notes) if i == at or t not in own]
    return grouped_warnings(notes, noun, [s.label for s in scored])


def _issue(notes: Sequence[str]) -> None:
    """Raise each of ``notes`` as a UserWarning, which the CLI prints on stderr."""
    for text in notes:
        warnings.warn(text, stacklevel=3)


#: Fewer window ends than this make a coverage figure too coarse to judge a model by.
FEW_WINDOW_ENDS = 20


def _few_ends_note(ends: int) -> str | None:
    """The warning for a windowed test of fewer than :data:`FEW_WINDOW_ENDS` ends: how far
    an honest model's 95 % coverage then scatters (its binomial 2.5 and 97.5 % points)."""
    if not 0 < ends < FEW_WINDOW_ENDS:
        return None
    from scipy.stats import binom

    low, high = (float(binom.ppf(q, ends, 0.95)) / ends for q in (0.025, 0.975))
    return (f"only {ends} window end(s): coverage moves in steps of 1/{ends}, and an honest model's "
            f"95 % figure falls anywhere in {low:.2f}..{high:.2f} in 95 % of such tests; score more "
            "windows (more or longer logs, shorter windows) before judging the model")


def evaluate_tracks(
    tracks: Sequence[str | Path],
    truth: Sequence[TruthOptions],
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
    tracks : track CSV paths
    truth : one :class:`~odomkit.workflows.truth.TruthOptions` per track; ``path`` None
        uses the track's ``gt_*`` columns.
    align : {"none", "start", "se2"}
    rpe_distances : true travel of each RPE [m]
    min_travel : a track whose truth travels less [m] is an error (nothing to score)
    progress : one stage, ``"tracks"``, a unit per track (:mod:`odomkit.progress`)
    plot, overwrite : draw the tracks against truth, the coverage diagram and the NEES of the
        rows into this .png, .svg or .pdf file (:func:`odomkit.workflows.figures.honesty_figure`;
        replaced only when ``overwrite``); adds ``outputs``

    Returns
    -------
    dict with the keys of DESIGN.md, ``per_log`` and ``warnings``.
    """
    _check_plot(plot, overwrite, [*tracks, *(t.path for t in truth if t.path is not None)])
    scored = []
    with stage(progress, len(tracks), "tracks"):
        for path, opts in zip(tracks, truth, strict=True):
            scored.append(_score_track(Path(path), opts, align, rpe_distances, min_travel))
            progress.advance()
    out = _report(scored, rpe_distances, noun="tracks")
    _issue(out["warnings"])
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
        found = _load(opts, None)
        samples = truth_at(found, track.t, opts.max_gap)
        ref, valid = samples.poses, samples.valid
        if np.count_nonzero(valid) < 2:
            raise InputError(no_overlap(found, track.t), source=str(path))
    elif track.truth is not None:
        ref, valid = track.truth, np.isfinite(track.truth[:, 0]) & np.isfinite(track.truth[:, 1])
    else:
        raise InputError("no truth: give --truth, or a track written with truth (gt_* columns)",
                         source=str(path))
    return _score_rows(str(path), track.poses, track.cov, ref, valid, align=align,
                       truth_sigma=opts.sigma or 0.0, rpe_distances=rpe_distances,
                       min_travel=min_travel, honesty_from_rows=True, t=track.t)


def _read_estimate(path: Path) -> TrackFile:
    """A track CSV (``odomkit track --out``, found by its header), else any pose file that
    truth can be (TUM, KITTI rows with time, headerless ``t,x,y,theta``) without covariance."""
    from odomkit.io.trackio import read_pose_file

    return read_pose_file(path, "track")


def _load(opts: TruthOptions, log: OdometryLog | None) -> Truth:
    from odomkit.workflows.truth import load_truth

    found = load_truth(opts, log)
    if found is None:
        source = getattr(log, "source", None)
        raise InputError("no truth: give --truth, or a log with ground truth (gt_* columns, OptiOdom, "
                         "Snowhite)", source=source)
    return found


def evaluate_logs(
    logs: Sequence[str | Path],
    robot_path: str | Path,
    truth: Sequence[TruthOptions],
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

    Parameters
    ----------
    logs : log paths
    robot_path : robot file with a ``[noise]`` table (without one: the whole runs' errors
        alone, and ``--window`` is refused)
    truth : one :class:`~odomkit.workflows.truth.TruthOptions` per log
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
    dict with the keys of DESIGN.md, ``window`` (the length scored, ``"30 s"`` or ``"5 m"``;
    None without one), ``per_log`` and ``warnings``. With several lengths the keys are the
    first length's (as a caller that asks for one reads them, and ``window`` names it), and
    ``by_window`` {length: the keys of that length alone}; ``warnings`` then has the whole
    runs' once and each length's own with the length before it (``"10 s windows: ..."``).
    """
    _check_plot(plot, overwrite, [*logs, robot_path, *(t.path for t in truth if t.path is not None)])
    specs = _window_specs(window)
    by_spec = _score_by_window(logs, robot_path, truth, specs, log_options=log_options,
                               min_travel=min_travel, align=align, rpe_distances=rpe_distances,
                               method=method, progress=progress, errors_only=True)
    reports = [_report(scored, rpe_distances, None if spec is None else str(spec))
               for spec, scored in zip(specs, by_spec, strict=True)]
    out = dict(reports[0])
    if len(reports) > 1:
        out["warnings"] = _several_lengths_notes(by_spec, reports)
        out["by_window"] = {r["window"]: r for r in reports}
    _issue(out["warnings"])
    scored = by_spec[0]
    window = None if specs[0] is None else str(specs[0])
    if plot is not None:
        from odomkit.evaluate import coverage
        from odomkit.io.robotfile import read_robot

        robot, noise = read_robot(robot_path)
        kinds = {m.kind for m in noise}
        both = " + ".join(sorted(kinds, reverse=True))
        name = "window ends" if kinds == {"white"} else f"window ends ({both})"
        covers = {name: out["coverage"]}
        if kinds > {"white"}:  # the white models alone, for comparison
            from odomkit.workflows.truth import resolved_truth

            white = [m for m in noise if m.kind == "white"]
            alone = _white_only(logs, robot, white, resolved_truth(robot_path, truth), log_options, specs[0],
                                min_travel, method)
            covers["window ends (white only)"] = coverage(np.concatenate([a.honesty_errors for a in alone]),
                                                          np.concatenate([a.honesty_cov for a in alone]))
        out["outputs"] = {"plot": str(_honesty_plot(plot, scored, covers, out["windows"], window))}
    return out


def _window_specs(window: str | Sequence[str] | None) -> list[WindowSpec | None]:
    """The window lengths asked for, in order (``[None]``: one window per log;
    :func:`odomkit.windows.parse_windows`)."""
    from odomkit.windows import parse_windows

    return list(parse_windows(window))


def _several_lengths_notes(by_spec: Sequence[Sequence[Scored]],
                           reports: Sequence[dict[str, Any]]) -> list[str]:
    """The ``warnings`` of several window lengths: the whole runs' once (alike for every
    length), then each length's own, after its length (``"10 s windows: ..."``)."""
    from odomkit.workflows.results import grouped_warnings

    whole = grouped_warnings(list(dict.fromkeys(w for s in by_spec[0] for w in s.warnings
                                                if w not in s.window_notes)),
                             among=[s.label for s in by_spec[0]])
    own = [f"{r['window']} windows: {w}" for r in reports for w in r["warnings"] if w not in whole]
    return whole + own


def _check_plot(plot: str | Path | None, overwrite: bool, inputs: Sequence[str | Path]) -> None:
    if plot is not None:
        from odomkit.io.files import check_outputs
        from odomkit.plot import check_plot_file

        check_outputs({"--plot": plot}, overwrite=overwrite, inputs=inputs)
        check_plot_file(plot)


def _white_only(logs: Sequence[str | Path], robot: Robot, white: Sequence[NoiseModel],
                truth: Sequence[TruthOptions], log_options: LogOptions | None, spec: WindowSpec | None,
                min_travel: float, method: str) -> list[Scored]:
    """The window ends scored with the white noise models alone (for ``--plot``)."""
    from odomkit.workflows.logs import LogOptions, load_log

    if not white:
        return []
    out = []
    for path, opts in zip(logs, truth, strict=True):
        log = load_log(path, robot, log_options or LogOptions())
        noise = list(white) if len(white) > 1 else white[0]
        out.append(_score_log(log, robot, noise, _load(opts, log), opts, [spec], min_travel=min_travel,
                              align="none", rpe_distances=(), method=method)[0])
    return out


def _honesty_plot(plot: str | Path, scored: Sequence[Scored], coverages: dict[str, dict[str, float | None]],
                  windows: int | None, length: str | None = None) -> Path:
    """``evaluate --plot``: each run against truth, the coverage and the NEES of the scored
    samples (window ends when ``windows`` is given, else track rows; ``length`` the window
    length, named in the figure's note)."""
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


def score_logs(
    logs: Sequence[str | Path],
    robot_path: str | Path,
    truth: Sequence[TruthOptions],
    *,
    log_options: LogOptions | None = None,
    window: str | None = None,
    min_travel: float = 0.05,
    align: str = "none",
    rpe_distances: Sequence[float] = (1.0,),
    method: str = "exact",
    progress: Progress = NO_PROGRESS,
    errors_only: bool = False,
) -> list[Scored]:
    """Each log's raw figures of :func:`evaluate_logs` (same parameters, one window length),
    before pooling: its position errors, and its window-end errors, covariances and times
    (for figures). Its notes are in each :class:`Scored`'s ``warnings``, not yet issued.

    ``errors_only``: a robot file without ``[noise]`` gives the whole runs' errors alone
    (no window ends, NEES or coverage; a windowed test is still refused) instead of an error.
    """
    return _score_by_window(logs, robot_path, truth, _window_specs(window), log_options=log_options,
                            min_travel=min_travel, align=align, rpe_distances=rpe_distances, method=method,
                            progress=progress, errors_only=errors_only)[0]


def _score_by_window(
    logs: Sequence[str | Path],
    robot_path: str | Path,
    truth: Sequence[TruthOptions],
    specs: Sequence[WindowSpec | None],
    *,
    log_options: LogOptions | None,
    min_travel: float,
    align: str,
    rpe_distances: Sequence[float],
    method: str,
    progress: Progress,
    errors_only: bool,
) -> list[list[Scored]]:
    """:func:`score_logs` for each window length of ``specs``: each log is read and its whole
    run dead-reckoned once, then cut into the windows of each length."""
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.logs import LogOptions, load_log
    from odomkit.workflows.truth import resolved_truth

    robot, noise = read_robot(robot_path)
    if not noise and (specs != [None] or not errors_only):
        raise InputError("the robot file has no [noise] table: the windowed test scores a predicted "
                         "covariance (add one: fit-noise writes it); without --window evaluate gives the "
                         "errors alone", source=str(robot_path))
    truth = resolved_truth(robot_path, truth)
    noise_arg = None if not noise else noise if len(noise) > 1 else noise[0]
    per_log = []
    with stage(progress, len(logs), "logs"):
        for path, opts in zip(logs, truth, strict=True):
            log = load_log(path, robot, log_options or LogOptions())
            found = _load(opts, log)
            per_log.append(_score_log(log, robot, noise_arg, found, opts, specs, min_travel=min_travel,
                                      align=align, rpe_distances=rpe_distances, method=method))
            progress.advance()
    by_spec = [[one[i] for one in per_log] for i in range(len(specs))]
    if noise_arg is None:
        note = (f"{robot_path}: the robot file has no [noise] table: the errors alone, no NEES or coverage "
                "(fit-noise writes one)")
        return [[replace(scored[0], warnings=[note, *scored[0].warnings]), *scored[1:]] for scored in by_spec]
    return [_windowless_left_out(scored) for scored in by_spec]


def _windowless_left_out(scored: list[Scored]) -> list[Scored]:
    """The logs with windows, each without one named in a warning; an error when none has
    one (the first log's reason)."""
    from odomkit.workflows.results import short_names

    empty = [s for s in scored if s.no_windows is not None]
    if not empty:
        return scored
    if len(empty) == len(scored):
        raise InputError(empty[0].no_windows or "no windows", source=empty[0].label)
    first = scored[0]
    names = short_names([s.label for s in empty], [s.label for s in scored])
    named = "; ".join(f"{name}: {s.no_windows}" for name, s in zip(names[:3], empty, strict=False))
    more = f"; and {len(empty) - 3} more" if len(empty) > 3 else ""
    note = f"{len(empty)} of {len(scored)} logs left out of the windowed test: {named}{more}"
    return [replace(first, warnings=[*first.warnings, note], window_notes=(*first.window_notes, note)),
            *scored[1:]]


#: Why windows are left out, after their count in a log's warning (:func:`_pooled_notes`).
_STILL = "window(s) travelled less than {:g} m (standing still or turning on the spot) and were left out"
_HEADLESS = "window(s) left out: no start heading could be fitted to the position-only truth"


def _score_log(log: OdometryLog, robot: Robot, noise: NoiseArg | None, truth: Truth, opts: TruthOptions,
               specs: Sequence[WindowSpec | None], *, min_travel: float, align: str,
               rpe_distances: Sequence[float], method: str) -> list[Scored]:
    """Whole-run figures from truth at the first row, and the window ends of one log, for
    each window length of ``specs`` (the whole run once)."""
    from odomkit.integrate import dead_reckon
    from odomkit.kinematics import body_steps
    from odomkit.track import dead_reckon_log
    from odomkit.truth import no_overlap, truth_at
    from odomkit.windows import cumulative_travel, run_start

    samples = truth_at(truth, log.t, opts.max_gap)
    rows = np.flatnonzero(samples.valid)
    if rows.size < 2:
        raise InputError(no_overlap(truth, log.t), source=log.source)
    steps = body_steps(robot, log)
    travel = cumulative_travel(steps)  # odometry travel at each row [m], reversing counted
    # Without truth heading the start heading aligns the odometry's own path to the fixes.
    odometry = (None if truth.has_heading
                else dead_reckon(steps.dd, steps.dtheta, np.zeros(3), method))  # type: ignore[arg-type]
    first, pose0, cov0 = run_start(log.t, truth, samples.valid, odometry, opts.max_gap)
    # The whole run, dead-reckoned from the truth at its first usable row.
    track = dead_reckon_log(log.from_row(first), robot, method, pose0, noise=noise, cov0=cov0)  # type: ignore[arg-type]
    whole = _score_rows(log.source, track.poses, track.cov, samples.poses[first:], samples.valid[first:],
                         align=align, truth_sigma=opts.sigma or 0.0, rpe_distances=rpe_distances,
                         min_travel=0.0, honesty_from_rows=False, t=track.t)
    whole = replace(whole, rows_skipped=whole.rows_skipped + first)
    if noise is None:  # the errors alone (score_logs' errors_only)
        return [whole for _ in specs]
    return [_score_windows(log, robot, noise, truth, samples, whole, spec, first=first,
                           first_valid=int(rows[0]), travel=travel, min_travel=min_travel, method=method)
            for spec in specs]


def _score_windows(log: OdometryLog, robot: Robot, noise: NoiseArg, truth: Truth, samples: TruthSamples,
                   whole: Scored, spec: WindowSpec | None, *, first: int, first_valid: int,
                   travel: NDArray[np.float64], min_travel: float, method: str) -> Scored:
    """``whole`` (one log's whole-run figures) with the window ends of one length: the
    honesty test, one window per span of the log, restarted from truth; the whole-log
    window (no ``spec``) starts with the whole run (as fit-noise's:
    :func:`odomkit.window_errors.log_window_basis`)."""
    from odomkit.calibrate.fit_noise import first_order_note
    from odomkit.window_errors import window_errors
    from odomkit.windows import late_start_note, split_windows, why_no_windows

    notes = list(whole.warnings)
    valid = samples.valid
    if spec is None:
        valid = valid.copy()
        valid[:first] = False
    if first != first_valid:
        what = "the whole-run track" + (" (and its window)" if spec is None else "")
        notes.append(late_start_note(log.source, what, log.t, first, first_valid))
    windows, skipped = split_windows(log.t, travel, spec, min_travel, valid=valid)
    if not windows:
        reason = why_no_windows(log.t, travel, valid, spec, min_travel, skipped)
        return replace(whole, honesty_errors=np.empty((0, 2)), honesty_cov=np.empty((0, 2, 2)), windows=0,
                       warnings=notes, no_windows=reason)
    own: list[str] = []
    left_out: list[tuple[str, int]] = []
    if skipped:
        left_out.append((_STILL.format(min_travel), skipped))
    found = window_errors(log, robot, noise, samples.poses, valid, windows, truth=truth, method=method)
    if found.dropped:
        left_out.append((_HEADLESS, found.dropped))
    own += [f"{log.source}: {n} {what}" for what, n in left_out]
    note = first_order_note(found.cov[:, 2, 2])
    if note:
        own.append(f"{log.source}: {note}")
    # found.cov holds the truth's noise at both window ends already (odomkit.window_errors).
    return replace(whole, honesty_errors=found.error[:, :2], honesty_cov=found.cov[:, :2, :2],
                   windows=len(found.windows), warnings=notes + own, window_notes=tuple(own),
                   left_out=tuple(left_out), honesty_t=log.t[found.end_rows],
                   honesty_t0=log.t[np.array([w.start for w in found.windows], dtype=np.int64)])
