"""What both forms of ``odomkit evaluate`` share: one track's or log's raw figures
(:class:`Scored`), the scoring of its rows against truth, their pooling
(:func:`summarise`) and the report and warnings made of them.

Internal to :mod:`odomkit.workflows` (the public names are re-exported by
:mod:`odomkit.workflows.evaluate`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.truth import Truth
    from odomkit.workflows.truth import TruthOptions

__all__ = ["FEW_WINDOW_ENDS", "few_ends_note", "issue_notes", "pooled_report", "require_truth",
           "score_rows", "Scored", "summarise", "TrackRows", "verdicts"]


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
    # (m,) variance of each window's start heading [rad²]: the truth's heading noise, or the
    # heading fitted to position-only truth (empty as honesty_t)
    start_heading_var: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
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
    # The whole run's start (a log's: run_start): log time [s], heading and its σ [rad], and
    # whether the heading was fitted to position-only truth (the whole-run figures hang on it)
    start_time: float | None = None
    start_heading: float | None = None
    start_heading_sigma: float | None = None
    start_heading_fitted: bool = False
    # (m,) the heading errors [rad] at the honesty samples' rows (wrapped) and their predicted
    # variance [rad²] (the truth's heading noise in), NaN where the truth has no heading; empty
    # where no heading is scored (:func:`_headings` fills NaN)
    heading_errors: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))
    heading_var: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))


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


def score_rows(label: str, poses: NDArray[np.float64], cov: NDArray[np.float64] | None,
               truth: NDArray[np.float64], valid: NDArray[np.bool_], *, align: str,
               truth_sigma: float, rpe_distances: Sequence[float], min_travel: float,
               honesty_from_rows: bool, t: NDArray[np.float64] | None = None,
               truth_heading_sigma: float = 0.0) -> Scored:
    """Score the rows of one track where ``valid``; ``truth`` (N, 3), θ NaN if unknown;
    ``t`` (N,) the rows' times, kept with them (:class:`TrackRows`) when given. The truth's
    own noise, ``truth_sigma`` [m] per axis and ``truth_heading_sigma`` [rad], is added to
    the covariance the rows are scored against (``honesty_from_rows``)."""
    from odomkit.angles import wrap_angle
    from odomkit.evaluate import align_track, relative_pose_errors, singular_nees_note

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
        # θ NaN where the truth has no heading: those rows have no heading NEES.
        hh, hv = wrap_angle(est[:, 2] - ref[:, 2]), P[:, 2, 2] + truth_heading_sigma**2
        note = singular_nees_note(he, hc)
        if note:
            notes.append(f"{label}: {note}")
    else:
        he, hc, hh, hv = np.empty((0, 2)), np.empty((0, 2, 2)), np.empty(0), np.empty(0)
        if honesty_from_rows:
            notes.append(f"{label}: the track has no covariance, so there is no NEES or coverage")
    kept = None if t is None else TrackRows(np.asarray(t, dtype=float)[rows], est, ref, P)
    return Scored(label, int(rows.size), int(n - rows.size), err, path, rpe, he, hc, 0, notes, rows=kept,
                  heading_errors=hh, heading_var=hv)


def _headings(scored: Sequence[Scored]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The heading errors [rad] and variances [rad²] of ``scored``'s honesty samples, (m,)
    each in their order, NaN where a log scored none (:class:`Scored`'s ``heading_*``)."""
    errors, variances = [], []
    for s in scored:
        m = s.honesty_errors.shape[0]
        have = s.heading_errors.shape == (m,) and s.heading_var.shape == (m,)
        errors.append(s.heading_errors if have else np.full(m, np.nan))
        variances.append(s.heading_var if have else np.full(m, np.nan))
    return np.concatenate(errors), np.concatenate(variances)


def _heading_summary(scored: Sequence[Scored]) -> dict[str, Any]:
    """The heading's keys of :func:`summarise`: its NEES (1 dof) and coverage of the
    intervals, each None where no sample has a truth heading (and a predicted variance)."""
    from odomkit.evaluate import heading_coverage, heading_nees_summary

    hh, hv = _headings(scored)
    head = heading_nees_summary(hh, hv)
    cover = heading_coverage(hh, hv) if head["count"] else None
    return {"nees_heading_mean": head["mean"], "nees_heading_median": head["median"],
            "nees_heading_bounds": head["bounds"], "coverage_heading": cover}


def summarise(scored: Sequence[Scored], rpe_distances: Sequence[float]) -> dict[str, Any]:
    """The output keys of ``odomkit evaluate`` (docs/reference/commands/evaluate.md) pooled
    over ``scored`` (without ``per_log``).

    Pooled: ``ate_rmse`` and each ``rpe`` are the RMS over every sample of every log,
    ``max_position_error`` the largest, ``final_position_error`` the mean of the logs'
    final errors, ``drift_percent`` 100 × Σ final errors / Σ true travel, and the NEES
    and coverage figures use every scored pose (window ends, or track rows); the heading's
    (``nees_heading_*``, ``coverage_heading``) those of them where the truth has heading,
    None where none has.
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
        **_heading_summary(scored),
    }


def _window_ends(s: Scored) -> dict[str, Any]:
    """``window_ends`` of a log scored in windows: each window's ``start`` and ``end`` [s, log
    time], its end's position ``error`` [m] (truth − odometry, x and y: the opposite sign of
    :func:`odomkit.evaluate.pose_errors`) and ``nees``, its
    ``heading_error`` [rad] and ``nees_heading`` (None where the truth has no heading), and
    the σ of its start heading ``start_heading_sigma`` [rad] (fitted to position-only truth, or
    the truth's heading noise), so that an outlier can be found and looked at (a window that
    starts slow and turning gets a start heading its fixes barely support); nothing for a
    whole-track score."""
    if not s.honesty_t0.size:
        return {}
    from odomkit.evaluate import heading_nees, nees

    q = nees(s.honesty_errors, s.honesty_cov)
    hh, hv = _headings([s])
    qh = heading_nees(hh, hv)

    def number(x: float) -> float | None:
        return float(x) if np.isfinite(x) else None

    m = s.honesty_t0.size
    start_var = s.start_heading_var if s.start_heading_var.shape == (m,) else np.full(m, np.nan)
    rows = zip(s.honesty_t0, s.honesty_t, s.honesty_errors, q, hh, qh, start_var, strict=True)
    return {"window_ends": [{"start": float(a), "end": float(b), "error": [float(e[0]), float(e[1])],
                             "nees": float(n), "heading_error": number(h), "nees_heading": number(nh),
                             "start_heading_sigma": number(math.sqrt(max(v, 0.0)) if np.isfinite(v) else v)}
                            for a, b, e, n, h, nh, v in rows]}


def pooled_report(scored: list[Scored], rpe_distances: Sequence[float], window: str | None = None,
                  noun: str = "logs") -> dict[str, Any]:
    """The pooled figures, ``window`` (the length scored: ``"30 s"``, None for none or one
    window per log), ``per_log`` (each with its own ``warnings``), and ``warnings``: every
    log's, those that say the same of several logs in one line (:func:`_pooled_notes`)."""
    out: dict[str, Any] = {"window": window, **summarise(scored, rpe_distances)}
    out.update(verdicts(out, scored, windowed=window is not None))
    out.update(_start(scored[0]) if len(scored) == 1 else _start(None))
    # A log's own verdicts from fewer ends than the pooled figures' rule are not to be judged by
    # (a user study read "coverage consistent" from one end of NEES 27.1): ``few_ends`` says so.
    out["per_log"] = [{"log": s.label, **(one := summarise([s], rpe_distances)),
                       **verdicts(one, [s], windowed=window is not None), **_start(s), **_window_ends(s),
                       "few_ends": few_ends_note(one["windows"]) if window is not None else None,
                       "warnings": list(s.warnings)} for s in scored]
    out["warnings"] = _pooled_notes(scored, noun)
    few = few_ends_note(out["windows"])
    if few:
        out["warnings"].append(few)
    return out


def _start(s: Scored | None) -> dict[str, Any]:
    """The keys of the whole run's start (:class:`Scored`'s ``start_*``): None for a track,
    or (pooled) for several logs, each of which has its own in ``per_log``."""
    return {"start_time": None if s is None else s.start_time,
            "start_heading": None if s is None else s.start_heading,
            "start_heading_sigma": None if s is None else s.start_heading_sigma,
            "start_heading_fitted": False if s is None else s.start_heading_fitted}


def verdicts(summary: dict[str, Any], scored: Sequence[Scored], windowed: bool) -> dict[str, Any]:
    """The honesty verdicts of a :func:`summarise` of ``scored``: ``coverage_bounds``
    {level: [low, high]} (:func:`odomkit.evaluate.coverage_range`: where an honest model's
    coverage falls in 95 % of such tests over this many window ends), ``coverage_verdict``
    {level: "optimistic" | "consistent" | "pessimistic"}, ``coverage_overall`` (one word,
    :func:`odomkit.evaluate.overall_verdict`), ``nees_verdict`` (the mean against
    ``nees_bounds``) and ``verdict_note``, which of the two to trust where they differ; and
    the heading's alike (:func:`_heading_verdicts`).

    Only for window ends (``windowed``), the independent samples both ranges assume; every
    key None otherwise (track rows, one window per log)."""
    from odomkit.evaluate import coverage_range, coverage_verdicts, nees, nees_verdict, overall_verdict

    empty: dict[str, Any] = {"coverage_bounds": None, "coverage_verdict": None, "coverage_overall": None,
                             "nees_verdict": None, "verdict_note": None,
                             **_heading_verdicts(summary, scored, windowed)}
    if not windowed or summary.get("nees_position_mean") is None:
        return empty
    he = np.concatenate([s.honesty_errors for s in scored])
    hc = np.concatenate([s.honesty_cov for s in scored])
    values = nees(he, hc)
    values = values[np.isfinite(values)]
    n = int(values.size)
    cover = summary["coverage"]
    levels = coverage_verdicts(cover, n)
    overall = overall_verdict(levels)
    by_nees = nees_verdict(summary["nees_position_mean"], summary["nees_bounds"])
    note = _disagreement_note(levels, overall, by_nees, values, dof=2)
    return {"coverage_bounds": {k: list(coverage_range(n, float(k))) for k in cover},
            "coverage_verdict": levels, "coverage_overall": overall, "nees_verdict": by_nees,
            "verdict_note": note, **_heading_verdicts(summary, scored, windowed)}


def _disagreement_note(levels: dict[str, str | None], overall: str | None, by_nees: str | None,
                       values: NDArray[np.float64], dof: int) -> str | None:
    """Which verdict to trust where the NEES mean's (``by_nees``) and coverage's
    (``overall``, ``levels``) differ, and why; None where they agree. ``values`` are the
    window ends' NEES (n,), χ² with ``dof`` degrees of freedom for an honest covariance
    (2: a position's ellipse, 1: a heading's interval)."""
    if overall is None or by_nees is None or overall == by_nees:
        return None
    shape = "ellipse" if dof == 2 else "interval"
    n = int(values.size)
    big, mid = float(values.max()), float(np.median(values))
    if overall == "mixed":
        low = [f"{100 * float(k):g} %" for k, v in levels.items() if v == "optimistic"]
        high = [f"{100 * float(k):g} %" for k, v in levels.items() if v == "pessimistic"]
        return (f"coverage is optimistic at {', '.join(low)} and pessimistic at {', '.join(high)} "
                "(heavy tails: more ends than predicted near the centre and beyond the outer "
                f"{shape}s), which the NEES mean ({by_nees}) averages away: trust coverage, level by "
                "level; no scaling of the covariance mends it")
    chance = _largest_end_chance(values, dof)
    if by_nees == "optimistic" and chance < _EXTREME:
        # Coverage counts an end in or out of the 99 % ellipse at most: an end far beyond
        # it (which an honest Gaussian covariance almost never gives) is evidence that
        # coverage cannot weigh, however few or many ends there are.
        few = f"with only {n} ends coverage can hardly tell a model apart; " if n < FEW_WINDOW_ENDS else ""
        return (f"the NEES mean says optimistic but coverage says {overall}: {few}the largest end "
                f"(NEES {big:.3g}, median {mid:.3g}) lies far beyond the 99 % {shape}, a chance of "
                f"{chance:.1g} over {n} ends for an honest covariance, which "
                "coverage (in or out at 50-99 %) cannot see: the errors have a heavier tail than the "
                "covariance (an outlier window, or an error the model lacks); look at that end in "
                "--json's per_log window_ends")
    why = (f"more ends fall outside the {shape}s than an honest covariance's would, while the mean "
           f"averages them with many small ones (median {mid:.3g})" if overall == "optimistic" else
           f"a few large ends pull the mean up (largest {big:.3g}, median {mid:.3g})"
           if by_nees == "optimistic" else
           f"more ends fall inside the {shape}s than an honest covariance's would, while a few large "
           f"ones hold the mean up (largest {big:.3g}, median {mid:.3g})" if overall == "pessimistic"
           else f"the mean weighs each end by its size (largest {big:.3g}, median {mid:.3g})")
    return (f"the NEES mean says {by_nees} but coverage says {overall}: trust coverage, which "
            f"counts each window end once, in or out; {why}; each end is in --json's per_log "
            "window_ends")


#: A largest window end whose chance under an honest covariance is below this is an outlier
#: that the NEES mean rightly weighs and coverage cannot (:func:`verdicts`).
_EXTREME = 0.01


def _largest_end_chance(values: NDArray[np.float64], dof: int = 2) -> float:
    """The chance that the largest of n NEES values (each χ² with ``dof`` = 2 (a position,
    tail exp(−q/2)) or 1 (a heading, tail erfc(√(q/2))) for an honest covariance) reaches
    the largest seen: 1 − (1 − tail(q_max))ⁿ, computed without cancellation."""
    q = float(values.max())
    tail = math.exp(-q / 2) if dof == 2 else math.erfc(math.sqrt(q / 2))
    if tail >= 1.0:  # q = 0: every end reaches it (and log1p(-1) would warn of a division by zero)
        return 1.0
    return float(-np.expm1(values.size * np.log1p(-tail)))


def _heading_verdicts(summary: dict[str, Any], scored: Sequence[Scored], windowed: bool) -> dict[str, Any]:
    """The heading's verdicts, as :func:`verdicts` gives the position's: ``coverage_heading_bounds``
    (the binomial ranges over the ends that have a heading NEES), ``coverage_heading_verdict``,
    ``coverage_heading_overall`` and ``nees_heading_verdict`` (the mean against
    ``nees_heading_bounds``, 1 dof) and ``verdict_heading_note`` (which to trust where they
    differ, as ``verdict_note`` says for the position). None without window ends
    (``windowed``) or where the truth has no heading."""
    from odomkit import evaluate as ev

    cover = summary.get("coverage_heading")
    if not windowed or cover is None or summary.get("nees_heading_mean") is None:
        return {"coverage_heading_bounds": None, "coverage_heading_verdict": None,
                "coverage_heading_overall": None, "nees_heading_verdict": None, "verdict_heading_note": None}
    values = ev.heading_nees(*_headings(scored))
    values = values[np.isfinite(values)]
    n = int(values.size)
    levels = ev.coverage_verdicts(cover, n)
    overall = ev.overall_verdict(levels)
    by_nees = ev.nees_verdict(summary["nees_heading_mean"], summary["nees_heading_bounds"])
    return {"coverage_heading_bounds": {k: list(ev.coverage_range(n, float(k))) for k in cover},
            "coverage_heading_verdict": levels, "coverage_heading_overall": overall,
            "nees_heading_verdict": by_nees,
            "verdict_heading_note": _disagreement_note(levels, overall, by_nees, values, dof=1)}


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


def issue_notes(notes: Sequence[str], stacklevel: int = 3) -> None:
    """Raise each of ``notes`` as a UserWarning, which the CLI prints on stderr (once: it
    collects them, :func:`odomkit.workflows.results.collected_warnings`, and adds those not
    in a result's ``warnings`` to it); ``stacklevel`` 3 names the caller of the function that
    calls this."""
    for text in notes:
        warnings.warn(text, stacklevel=stacklevel)


#: Fewer window ends than this make a coverage figure too coarse to judge a model by.
FEW_WINDOW_ENDS = 20


def few_ends_note(ends: int) -> str | None:
    """The warning for a windowed test of fewer than :data:`FEW_WINDOW_ENDS` ends: how far
    an honest model's 95 % coverage then scatters (its binomial 2.5 and 97.5 % points); None
    for more ends, or none. The pooled figures' warning, and each log's ``few_ends`` in
    ``per_log`` (its own verdicts then not judged, :func:`pooled_report`)."""
    if not 0 < ends < FEW_WINDOW_ENDS:
        return None
    from odomkit.evaluate import coverage_range

    low, high = coverage_range(ends, 0.95)
    return (f"only {ends} window end(s): coverage moves in steps of 1/{ends}, and an honest model's "
            f"95 % figure falls anywhere in {low:.2f}..{high:.2f} in 95 % of such tests; score more "
            "windows (more or longer logs, shorter windows) before judging the model")


def require_truth(opts: TruthOptions, log: OdometryLog | None) -> Truth:
    """The truth ``opts`` names (or ``log``'s own ``gt_*`` columns); an error when there is none."""
    from odomkit.workflows.truth import load_truth

    found = load_truth(opts, log)
    if found is None:
        source = getattr(log, "source", None)
        raise InputError("no truth: give --truth FILE, or --truth-topic TOPIC for a bag's own, or a log "
                         "with ground truth (gt_* columns, OptiOdom, Snowhite)", source=source)
    return found
