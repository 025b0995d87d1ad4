"""``odomkit evaluate``: how wrong a track is against ground truth, and how honest its covariance.

::

    odomkit evaluate TRACK.csv [TRACK.csv ...] [--truth GT ...] [--align none|start|se2] [--json]
    odomkit evaluate LOG [LOG ...] --robot ROBOT.toml [--truth GT ...] [--window 30s|5m ...] [--json]
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from odomkit.cli.application import app
from odomkit.cli.log_options import (
    reported_warnings,
    with_log_options,
    with_warnings,
)
from odomkit.cli.output import print_json
from odomkit.cli.progress import progress_bar
from odomkit.cli.truth_options import (
    TruthListOption,
    with_truth_options,
)
from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["evaluate_command", "print_report"]


def _distances(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or not all(v > 0 for v in values):
        raise InputError(f"--rpe expects positive distances in metres, e.g. 0.5,1, got {text!r}")
    return values


@app.command("evaluate")
@with_log_options
@with_truth_options
def evaluate_command(
    files: Annotated[list[Path], typer.Argument(
        help="Track CSVs (odomkit track --out), or logs with --robot.")],
    robot: Annotated[Path | None, typer.Option(
        "--robot", help="Robot file (TOML) with [noise]: FILES are logs, re-run from truth.")] = None,
    window: Annotated[list[str] | None, typer.Option(
        "--window", help="Honesty-test windows: 30s (time) or 5m (odometry travel); repeat it to score "
                         "each length on its own (--window 10s --window 30s); default one window per "
                         "log.")] = None,
    min_travel: Annotated[float, typer.Option(
        "--min-travel", help="Windows travelling less [m] are left out and counted.")] = 0.05,
    align: Annotated[str, typer.Option("--align", help="none | start | se2 (Umeyama, no scale).")] = "none",
    rpe: Annotated[str, typer.Option("--rpe", help="RPE distances [m], comma-separated.")] = "1",
    truth: TruthListOption = None,
    method: Annotated[str, typer.Option("--method", help="exact | midpoint | euler")] = "exact",
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw the tracks against truth, the coverage diagram and the NEES into this file "
                       "(.png, .svg or .pdf; needs the plot extra).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace an existing --plot file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:
    """Score tracks against ground truth (ATE, RPE, drift, NEES, ellipse coverage); with --robot,
    the windowed honesty test of the robot file's noise on logs."""
    from odomkit.evaluate import ALIGNMENTS
    from odomkit.workflows.evaluate import evaluate_logs, evaluate_tracks
    from odomkit.workflows.truth import truth_options_per_log, with_truth_topic

    if align not in ALIGNMENTS:
        raise InputError(f"--align must be one of {', '.join(ALIGNMENTS)}, got {align!r}")
    distances = _distances(rpe)
    options, base = with_truth_topic(log_opts, truth_base, bool(truth))
    per_file = truth_options_per_log(base, list(truth or []), len(files))
    if robot is None:
        if window:
            raise InputError("--window re-runs dead reckoning, so it needs --robot (and FILES that are logs)")
        if options.given():
            raise InputError(f"{', '.join(options.given())} reads logs, so it needs --robot (and FILES "
                             "that are logs)")
    noun = "logs" if robot is not None else "tracks"
    with reported_warnings(noun) as warned, progress_bar(json_out) as progress:
        if robot is None:
            out = evaluate_tracks(files, per_file, align=align, rpe_distances=distances,
                                  min_travel=min_travel, progress=progress, plot=plot, overwrite=force)
        else:
            out = evaluate_logs(files, robot, per_file, log_options=options, window=window or None,
                                min_travel=min_travel, align=align, rpe_distances=distances, method=method,
                                progress=progress, plot=plot, overwrite=force)
    out = with_warnings(out, warned, noun)
    if json_out:
        print_json(out)
        return
    print_report(out, windowed=robot is not None, whole_runs=not window, aligned=align == "se2")
    for kind, path in out.get("outputs", {}).items():
        print(f"wrote {kind}: {path}")


def _fmt(value: float | None, spec: str = ".4f") -> str:
    return "n/a" if value is None else format(value, spec)


def _nees_texts(mean: float, lo: float, hi: float) -> tuple[str, str, str]:
    """``mean`` and its bounds ``lo``, ``hi`` as printed: 3 significant digits, or as many
    more as it takes for the printed numbers to stand in the order of the true ones (a mean
    just below its lower bound must not print equal to it beside the verdict "below")."""
    def side(a: float, b: float) -> int:
        return (a > b) - (a < b)

    for digits in range(3, 18):
        m, a, b = (format(v, f".{digits}g") for v in (mean, lo, hi))
        if side(float(m), float(a)) == side(mean, lo) and side(float(m), float(b)) == side(mean, hi):
            return m, a, b
    return repr(mean), repr(lo), repr(hi)  # 17 digits tell any two floats apart; not reached


def print_report(out: dict[str, Any], windowed: bool, whole_runs: bool = False,
                 aligned: bool = False) -> None:
    """The short text report of ``odomkit evaluate``: ``windowed`` for logs dead-reckoned
    from the truth, in ``--window`` windows or (``whole_runs``) one window per log; with
    several window lengths (``by_window``) a block for each, after the whole runs' errors.
    ``aligned``: the whole runs' errors are after an SE(2) alignment (``--align se2``)."""
    from odomkit.log import clock_text
    from odomkit.workflows.evaluate import CONTAINMENT_NOTE, WHOLE_RUN_NOTE, WINDOWED_NOTE

    print(f"{out['rows_evaluated']} rows evaluated, {out['rows_skipped']} skipped (no truth there, or "
          f"before the start), {len(out['per_log'])} file(s)")
    final = "final" if len(out["per_log"]) < 2 else f"final (mean of {len(out['per_log'])} logs)"
    print(f"position error: {final} {_fmt(out['final_position_error'])} m, max "
          f"{_fmt(out['max_position_error'])} m, ATE RMSE {_fmt(out['ate_rmse'])} m, drift "
          f"{_fmt(out['drift_percent'], '.2f')} %")
    print("RPE RMSE: " + ", ".join(("n/a" if v is None else f"{v:.4f} m") + f" over {k} m"
                                   for k, v in out["rpe"].items()))
    for one in out["per_log"]:
        if one.get("start_heading_fitted"):
            # The whole-run figures hang on it (a user study: two truths 0.36 m apart gave ATE
            # 3.86 and 18.2 m through start headings 0.107 and 0.165 rad, never shown).
            named = f"{one['log']}: " if len(out["per_log"]) > 1 else ""
            print(f"{named}start heading {one['start_heading']:.4g} ± {one['start_heading_sigma']:.2g} rad "
                  f"at {clock_text(one['start_time'])} s, fitted to the position-only truth (the whole run "
                  + ("starts from it; --align se2 then turns the track onto the truth, so the errors above "
                     "do not hang on it)" if aligned else "starts from it)"))
    for block in out.get("by_window", {}).values() or [out]:
        _print_honesty(block, windowed, whole_runs)
    if out["nees_position_mean"] is None and whole_runs:
        return  # a robot file without [noise]: errors alone, no covariance to judge
    note = (CONTAINMENT_NOTE if not windowed else WHOLE_RUN_NOTE if whole_runs else WINDOWED_NOTE)
    print(f"note: {note}")


def _print_honesty(out: dict[str, Any], windowed: bool, whole_runs: bool) -> None:
    """The NEES and coverage lines of one window length (or of the track rows), headed by
    the length scored, and with several logs each log's."""
    from odomkit.workflows.evaluate import FEW_WINDOW_ENDS

    cov = out["coverage"]
    what = f"{out['windows']} window {_ends(out['windows'])}" if windowed else "track rows"
    if out["nees_position_mean"] is not None:
        if windowed:
            length = out.get("window")
            travel = " (of odometry travel)" if length and length.endswith(" m") else ""
            print(f"honesty test: {length} windows{travel}, each restarted from the truth and scored at its "
                  "end" if length else
                  "honesty test: one window per log (no --window), from the truth at its start to its end")
        lo, hi = out["nees_bounds"]
        mean = out["nees_position_mean"]
        # evaluate's own verdict: given only where the ends are independent samples (windows),
        # as the bounds assume.
        verdict = _NEES_SIDE.get(str(out.get("nees_verdict")), "")
        shown, low, high = _nees_texts(mean, lo, hi)
        print(f"position NEES over {what}: mean {shown} (95 % bounds {low}..{high} if independent), "
              f"median {out['nees_position_median']:.3g}{verdict}")
        print("inside the predicted 50/90/95/99 % ellipses: "
              + " / ".join(_fmt(cov[k], ".3f") for k in ("0.5", "0.9", "0.95", "0.99")))
        if out.get("coverage_overall") is not None:
            print(_coverage_text(out))
        if out.get("verdict_note"):
            print(f"NEES and coverage disagree: {out['verdict_note']}")
        if out.get("nees_heading_mean") is not None:
            print(_heading_text(out, what, verdicts=windowed and not whole_runs))
        if out.get("verdict_heading_note"):
            print(f"heading NEES and coverage disagree: {out['verdict_heading_note']}")
    elif windowed and not whole_runs and out.get("window"):
        print(f"honesty test: {out['window']} windows: no window end scored (see the warnings)")
    if windowed and not whole_runs and len(out["per_log"]) > 1:
        # Windows of one log share its bias draw: coverage comes in lumps, seen log by log.
        for one in out["per_log"]:
            if one.get("nees_position_mean") is None:
                continue
            c = one["coverage"]
            bounds = one.get("nees_bounds") or (one["nees_position_mean"],) * 2
            # Its verdict only from as many ends as the pooled figures need (few_ends: the note).
            judged = not one.get("few_ends")
            said = (f", coverage {one['coverage_overall']}" if judged and one.get("coverage_overall") else
                    "" if judged else f", not judged (under {FEW_WINDOW_ENDS} ends)")
            mean = _nees_texts(one["nees_position_mean"], *bounds)[0]
            print(f"  {one['log']}: {one['windows']} {_ends(one['windows'])}, inside 95 % / 50 %: "
                  f"{_fmt(c['0.95'], '.2f')} / {_fmt(c['0.5'], '.2f')}, NEES mean {mean}{said}"
                  f"{_log_heading_text(one, judged)}")


def _ends(n: int) -> str:
    """"end" or "ends" after a count of ``n`` window ends."""
    return "end" if n == 1 else "ends"


def _log_heading_text(one: dict[str, Any], judged: bool = True) -> str:
    """The heading's part of one log's line, as the position's before it: its coverage of the
    95 and 50 % intervals, its NEES mean and (``judged``: as many ends as the pooled figures
    need) coverage verdict; nothing where the truth has no heading."""
    if one.get("nees_heading_mean") is None:
        return ""
    c = one["coverage_heading"]
    bounds = one.get("nees_heading_bounds") or (one["nees_heading_mean"],) * 2
    said = (f", coverage {one['coverage_heading_overall']}"
            if judged and one.get("coverage_heading_overall") else "")
    return (f"; heading inside 95 % / 50 %: {_fmt(c['0.95'], '.2f')} / {_fmt(c['0.5'], '.2f')}, NEES mean "
            f"{_nees_texts(one['nees_heading_mean'], *bounds)[0]}{said}")


def _heading_text(out: dict[str, Any], what: str, verdicts: bool) -> str:
    """The heading's line, where the truth has heading: its NEES (1 dof) against its bounds,
    its coverage of the 50/90/95/99 % intervals and (``verdicts``: window ends) the coverage
    verdict in one word."""
    lo, hi = out["nees_heading_bounds"]
    mean = out["nees_heading_mean"]
    shown, low, high = _nees_texts(mean, lo, hi)
    side = _HEADING_SIDE.get(str(out.get("nees_heading_verdict")), "") if verdicts else ""
    cov = out["coverage_heading"]
    word = out.get("coverage_heading_overall")
    said = f", coverage {word} ({_MEANING[word]})" if verdicts and word is not None else ""
    return (f"heading NEES over {what}: mean {shown} (95 % bounds {low}..{high} if independent, 1 dof),"
            f"{side} median {out['nees_heading_median']:.3g}; inside the predicted 50/90/95/99 % intervals: "
            + " / ".join(_fmt(cov[k], ".3f") for k in ("0.5", "0.9", "0.95", "0.99")) + said)


#: evaluate's NEES verdicts (``nees_verdict``, ``nees_heading_verdict``) as the text says them.
_NEES_SIDE = {"optimistic": ": above its bounds, the covariance is too small (optimistic)",
              "pessimistic": ": below its bounds, the covariance is too large (pessimistic)",
              "consistent": ": inside its bounds"}
_HEADING_SIDE = {"optimistic": " above its bounds (optimistic),",
                 "pessimistic": " below its bounds (pessimistic),", "consistent": " inside its bounds,"}
#: What each coverage verdict says of the covariance, in the text report.
_MEANING = {"optimistic": "the covariance is too small", "pessimistic": "the covariance is too large",
            "consistent": "no level outside an honest covariance's range",
            "mixed": "heavy tails: no scaling of the covariance fits"}


def _coverage_text(out: dict[str, Any]) -> str:
    """The coverage verdict of one window length: each level against the range an honest
    model's figure falls in over this many ends (``coverage_bounds``), the levels outside
    it first."""
    levels = ("0.5", "0.9", "0.95", "0.99")
    verdict, bounds, cov = out["coverage_verdict"], out["coverage_bounds"], out["coverage"]

    def level(k: str) -> str:
        lo, hi = bounds[k]
        side = "below" if verdict[k] == "optimistic" else "above" if verdict[k] == "pessimistic" else "in"
        return f"{100 * float(k):g} % {cov[k]:.3f} {side} {lo:.3f}..{hi:.3f}"

    off = [k for k in levels if verdict.get(k) not in (None, "consistent")]
    inside = [k for k in levels if verdict.get(k) == "consistent"]
    overall = out["coverage_overall"]
    parts = [level(k) for k in off + inside]
    return (f"coverage verdict: {overall} ({_MEANING[overall]}): " + ", ".join(parts)
            + f" (where an honest model's figure falls in 95 % of tests of {out['windows']} "
            f"{_ends(out['windows'])})")
