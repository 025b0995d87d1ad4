"""The log form of ``odomkit evaluate`` scored: each log dead-reckoned once from the truth
at its first row (the whole-run figures), then cut into windows of each length asked for,
each restarted from the truth and scored at its end (the honesty test).

Internal to :mod:`odomkit.workflows` (:func:`score_logs` is re-exported by
:mod:`odomkit.workflows.evaluate`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError
from odomkit.log import clock_text
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.workflows._scoring import Scored, require_truth, score_rows

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.propagate.plan import NoiseArg
    from odomkit.robot import Robot
    from odomkit.truth import Truth, TruthSamples
    from odomkit.windows import WindowSpec
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["LoadedLog", "score_by_window", "score_loaded", "score_logs", "several_lengths_notes",
           "START_HEADING_SHARE", "start_heading_note", "STILL", "white_only", "window_specs"]


@dataclass(frozen=True)
class LoadedLog:
    """One log to score, in memory: the log, its truth (its own noise, ``sigma``,
    ``heading_sigma`` and ``time_sigma``, is what the window ends are scored with) and the
    longest gap between the truth's fixes to interpolate across [s] (None: no limit)."""

    log: OdometryLog
    truth: Truth
    max_gap: float | None = 0.5


def score_logs(
    logs: str | Path | Sequence[str | Path],
    robot_path: str | Path,
    truth: TruthOptions | Sequence[TruthOptions] | None = None,
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
    """Each log's raw figures of :func:`~odomkit.workflows.evaluate.evaluate_logs` (same
    parameters, one window length), before pooling: its position errors, and its window-end
    errors, covariances and times (for figures). Its notes are in each :class:`Scored`'s
    ``warnings``, not yet issued.

    ``errors_only``: a robot file without ``[noise]`` gives the whole runs' errors alone
    (no window ends, NEES or coverage; a windowed test is still refused) instead of an error.
    ``logs`` may be one path; ``truth`` one :class:`TruthOptions` for every log, or None for
    each log's own truth (:func:`odomkit.workflows.results.truths_per_log`).
    """
    from odomkit.workflows.results import paths_given, truths_per_log

    files = paths_given(logs, "log", "odomkit.workflows.evaluate.evaluate_in_memory")
    return score_by_window(files, robot_path, truths_per_log(truth, len(files)), window_specs(window),
                           log_options=log_options,
                           min_travel=min_travel, align=align, rpe_distances=rpe_distances, method=method,
                           progress=progress, errors_only=errors_only)[0]


def score_by_window(
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
    run dead-reckoned once, then cut into the windows of each length (:func:`score_loaded`,
    one log read at a time)."""
    from odomkit.io.robotfile import read_robot
    from odomkit.workflows.logs import LogOptions, load_log
    from odomkit.workflows.truth import resolved_truth

    robot, noise = read_robot(robot_path)
    _need_noise(noise, specs, errors_only, str(robot_path))
    options = resolved_truth(robot_path, truth)

    def loaded() -> Iterator[LoadedLog]:
        for path, opts in zip(logs, options, strict=True):
            log = load_log(path, robot, log_options or LogOptions())
            yield LoadedLog(log, require_truth(opts, log), opts.max_gap)

    return score_loaded(loaded(), len(logs), robot, noise, specs, min_travel=min_travel, align=align,
                        rpe_distances=rpe_distances, method=method, progress=progress,
                        errors_only=errors_only, robot_path=str(robot_path))


def _need_noise(noise: Sequence[NoiseModel], specs: Sequence[WindowSpec | None], errors_only: bool,
                robot_path: str | None) -> None:
    """The error where there is no noise model but a covariance is to be scored (windows, or
    not ``errors_only``): of the robot file ``robot_path``, or of the noise given in memory."""
    if noise or (list(specs) == [None] and errors_only):
        return
    if robot_path is not None:
        raise InputError("the robot file has no [noise] table: the windowed test scores a predicted "
                         "covariance (add one: fit-noise writes it); without --window evaluate gives the "
                         "errors alone", source=robot_path)
    raise InputError("no noise model given: the windowed test scores a predicted covariance (give the "
                     "noise, e.g. fit_noise_in_memory's); without a window evaluate gives the errors alone")


def score_loaded(
    logs: Iterable[LoadedLog],
    count: int,
    robot: Robot,
    noise: Sequence[NoiseModel],
    specs: Sequence[WindowSpec | None],
    *,
    min_travel: float,
    align: str,
    rpe_distances: Sequence[float],
    method: str,
    progress: Progress,
    errors_only: bool,
    robot_path: str | None = None,
) -> list[list[Scored]]:
    """:func:`score_by_window` of logs in memory, one :class:`Scored` per log for each length
    of ``specs``: the one scoring both ``odomkit evaluate`` (logs read from files, one at a
    time, ``count`` of them) and :func:`odomkit.workflows.evaluate.evaluate_in_memory` use.

    ``noise`` empty: the whole runs' errors alone where ``errors_only`` and no window is
    asked for (a warning says so, naming ``robot_path``, the robot file, where given), else
    an error."""
    _need_noise(noise, specs, errors_only, robot_path)
    noise_arg = None if not noise else tuple(noise) if len(noise) > 1 else noise[0]
    per_log = []
    with stage(progress, count, "logs"):
        for one in logs:
            per_log.append(_score_log(one.log, robot, noise_arg, one.truth, one.max_gap, specs,
                                      min_travel=min_travel, align=align, rpe_distances=rpe_distances,
                                      method=method))
            progress.advance()
    by_spec = [[one[i] for one in per_log] for i in range(len(specs))]
    if noise_arg is None:
        note = ("no noise model given: the errors alone, no NEES or coverage" if robot_path is None else
                f"{robot_path}: the robot file has no [noise] table: the errors alone, no NEES or coverage "
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


#: Why windows are left out, after their count in a log's warning (``_scoring._pooled_notes``);
#: for want of a start heading: :func:`odomkit.window_errors.headless_note`.
STILL = "window(s) travelled less than {:g} m (standing still or turning on the spot) and were left out"


def _score_log(log: OdometryLog, robot: Robot, noise: NoiseArg | None, truth: Truth, max_gap: float | None,
               specs: Sequence[WindowSpec | None], *, min_travel: float, align: str,
               rpe_distances: Sequence[float], method: str) -> list[Scored]:
    """Whole-run figures from truth at the first row, and the window ends of one log, for
    each window length of ``specs`` (the whole run once); ``max_gap`` [s] as
    :func:`odomkit.truth.truth_at` takes it."""
    from odomkit.integrate import dead_reckon
    from odomkit.kinematics import body_steps
    from odomkit.track import dead_reckon_log
    from odomkit.truth import no_overlap, truth_at
    from odomkit.windows import cumulative_travel, run_start

    samples = truth_at(truth, log.t, max_gap)
    rows = np.flatnonzero(samples.valid)
    if rows.size < 2:
        raise InputError(no_overlap(truth, log.t, log.meta.get("time")), source=log.source)
    steps = body_steps(robot, log)
    travel = cumulative_travel(steps)  # odometry travel at each row [m], reversing counted
    # Without truth heading the start heading aligns the odometry's own path to the fixes.
    odometry = (None if truth.has_heading
                else dead_reckon(steps.dd, steps.dtheta, np.zeros(3), method))  # type: ignore[arg-type]
    first, pose0, cov0 = run_start(log.t, truth, samples.valid, odometry, max_gap)
    # The whole run, dead-reckoned from the truth at its first usable row.
    track = dead_reckon_log(log.from_row(first), robot, method, pose0, noise=noise, cov0=cov0)  # type: ignore[arg-type]
    whole = score_rows(log.source, track.poses, track.cov, samples.poses[first:], samples.valid[first:],
                        align=align, truth_sigma=truth.sigma, rpe_distances=rpe_distances,
                        min_travel=0.0, honesty_from_rows=False, t=track.t)
    fitted = not truth.has_heading
    whole = replace(whole, rows_skipped=whole.rows_skipped + first, start_time=float(log.t[first]),
                    start_heading=float(pose0[2]), start_heading_sigma=float(np.sqrt(max(cov0[2, 2], 0.0))),
                    start_heading_fitted=fitted)
    if fitted and align != "se2":
        note = start_heading_note(whole, samples.poses[first:][samples.valid[first:]], pose0,
                                  windowed=any(spec is not None for spec in specs))
        if note:
            whole = replace(whole, warnings=[*whole.warnings, f"{log.source}: {note}"])
    if noise is None:  # the errors alone (score_logs' errors_only)
        return [whole for _ in specs]
    if any(spec is not None for spec in specs):  # once per log, whatever the lengths
        from odomkit.calibrate.check_ratios import follows_note
        from odomkit.truth_knots import interpolated_note

        for said in (interpolated_note(truth), follows_note(log, robot, truth, max_gap)):
            if said:
                whole = replace(whole, warnings=[*whole.warnings, f"{log.source}: {said}"])
    return [_score_windows(log, robot, noise, truth, samples, whole, spec, first=first,
                           first_valid=int(rows[0]), travel=travel, min_travel=min_travel, method=method)
            for spec in specs]


#: The start heading's own σ is worth a warning where the end it moves (2 σθ times the run's
#: distance from its start: the 95 % figure) passes this share of the final error, or the
#: track it moves (2 σθ times the RMS distance) this share of the ATE: the whole-run figures
#: then measure the start heading fitted to the fixes as much as the odometry. (One σ was
#: too little: of two truths of one car drive 0.36 m apart, the one whose heading came out
#: 2.4 σ off, ending 41 m off instead of 12 m, moved its end by only 0.6 of its error at 1 σ.)
START_HEADING_SHARE = 0.5


def start_heading_note(whole: Scored, truth_xy: NDArray[np.float64],
                       pose0: NDArray[np.float64], windowed: bool = False) -> str | None:
    """The warning where a whole run's final error or ATE hangs on the start heading fitted
    to position-only truth (:data:`START_HEADING_SHARE`), or None.

    A start heading off by δθ turns the whole track about its start: the pose at distance D
    from the start moves by δθ·D. So 2σθ·D at the last scored row is what the heading's own
    uncertainty alone moves the end by (95 %), and 2σθ·RMS(D) the track.

    Parameters
    ----------
    whole : the whole run scored (its ``position_errors`` (n,) [m] and ``start_heading*``)
    truth_xy : the truth at the scored rows, shape (n, 2+) [m]
    pose0 : the start pose (3,) [m, m, rad]
    windowed : the windowed test is run too (then it is not advised)
    """
    sigma, start = whole.start_heading_sigma, whole.start_time
    if (sigma is None or sigma <= 0 or start is None or truth_xy.shape[0] == 0
            or whole.position_errors.size == 0):
        return None
    distance = np.hypot(truth_xy[:, 0] - pose0[0], truth_xy[:, 1] - pose0[1])
    end, rms = 2 * sigma * float(distance[-1]), 2 * sigma * float(np.sqrt(np.mean(distance**2)))
    final = float(whole.position_errors[-1])
    ate = float(np.sqrt(np.mean(whole.position_errors**2)))
    if end <= START_HEADING_SHARE * final and rms <= START_HEADING_SHARE * ate:
        return None
    return (f"the whole run starts from a heading fitted to the position-only truth, "
            f"{whole.start_heading:.4g} ± {sigma:.2g} rad at {clock_text(start)} s, and that "
            f"heading's own uncertainty alone moves the end by ±{end:.3g} m (2σ; final error {final:.3g} m) "
            f"and the track by ±{rms:.3g} m RMS (ATE {ate:.3g} m): the final error and ATE measure the start "
            "heading as much as the odometry; use --align se2, or truth with heading"
            + ("" if windowed else ", or --window for the honesty test"))


def _score_windows(log: OdometryLog, robot: Robot, noise: NoiseArg, truth: Truth, samples: TruthSamples,
                   whole: Scored, spec: WindowSpec | None, *, first: int, first_valid: int,
                   travel: NDArray[np.float64], min_travel: float, method: str) -> Scored:
    """``whole`` (one log's whole-run figures) with the window ends of one length: the
    honesty test, one window per span of the log, restarted from truth; the whole-log
    window (no ``spec``) starts with the whole run (as fit-noise's:
    :func:`odomkit.window_errors.log_window_basis`)."""
    from odomkit.calibrate.fit_noise import first_order_note
    from odomkit.window_errors import headless_note, window_errors
    from odomkit.windows import late_start_note, rows_at_fixes, split_windows, why_no_windows

    notes = list(whole.warnings)
    valid = samples.valid
    ends = rows_at_fixes(log.t, truth.t, valid)  # a sparse truth: ends only next to its fixes
    if spec is None:
        ends = ends.copy()
        ends[:first] = False
    if first != first_valid:
        what = "the whole-run track" + (" (and its window)" if spec is None else "")
        notes.append(late_start_note(log.source, what, log.t, first, first_valid))
    windows, skipped = split_windows(log.t, travel, spec, min_travel, valid=valid, ends=ends)
    if not windows:
        reason = why_no_windows(log.t, travel, valid, spec, min_travel, skipped)
        return replace(whole, honesty_errors=np.empty((0, 2)), honesty_cov=np.empty((0, 2, 2)), windows=0,
                       warnings=notes, no_windows=reason, heading_errors=np.empty(0), heading_var=np.empty(0))
    own: list[str] = []
    left_out: list[tuple[str, int]] = []
    if skipped:
        left_out.append((STILL.format(min_travel), skipped))
    found = window_errors(log, robot, noise, samples.poses, valid, windows, truth=truth, method=method)
    if found.dropped:
        left_out.append((headless_note(log.t, found.left_out, spec), found.dropped))
    own += [f"{log.source}: {n} {what}" for what, n in left_out]
    # A start heading's error is carried to the window's end unchanged (∂θ/∂θ₀ = 1): its
    # variance is the start's share of the end's.
    note = first_order_note(found.cov[:, 2, 2], found.start_cov[:, 2, 2])
    if note:
        own.append(f"{log.source}: {note}")
    # found.cov holds the truth's noise at both window ends already (odomkit.window_errors),
    # its heading's too (heading_sigma² at the start, carried, and at the end); found.error's
    # θ is NaN where the truth has no heading, so those ends have no heading NEES.
    return replace(whole, honesty_errors=found.error[:, :2], honesty_cov=found.cov[:, :2, :2],
                   heading_errors=found.error[:, 2], heading_var=found.cov[:, 2, 2],
                   windows=len(found.windows), warnings=notes + own, window_notes=tuple(own),
                   left_out=tuple(left_out), honesty_t=log.t[found.end_rows],
                   start_heading_var=found.start_cov[:, 2, 2],
                   honesty_t0=log.t[np.array([w.start for w in found.windows], dtype=np.int64)])


def window_specs(window: str | Sequence[str] | None) -> list[WindowSpec | None]:
    """The window lengths asked for, in order (``[None]``: one window per log;
    :func:`odomkit.windows.parse_windows`)."""
    from odomkit.windows import parse_windows

    return list(parse_windows(window))


def several_lengths_notes(by_spec: Sequence[Sequence[Scored]],
                          reports: Sequence[dict[str, Any]]) -> list[str]:
    """The ``warnings`` of several window lengths: the whole runs' once (alike for every
    length), then each length's own, after its length (``"10 s windows: ..."``)."""
    from odomkit.workflows.results import grouped_warnings

    whole = grouped_warnings(list(dict.fromkeys(w for s in by_spec[0] for w in s.warnings
                                                if w not in s.window_notes)),
                             among=[s.label for s in by_spec[0]])
    own = [f"{r['window']} windows: {w}" for r in reports for w in r["warnings"] if w not in whole]
    return whole + own


def white_only(logs: Sequence[str | Path], robot: Robot, white: Sequence[NoiseModel],
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
        out.append(_score_log(log, robot, noise, require_truth(opts, log), opts.max_gap, [spec],
                              min_travel=min_travel, align="none", rpe_distances=(), method=method)[0])
    return out
