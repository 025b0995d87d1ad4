"""``odomkit fit-noise``: maximum-likelihood noise variances from logs with ground truth.

::

    odomkit fit-noise --robot ROBOT.toml LOG [LOG ...] [--truth GT ...]
    odomkit fit-noise --robot ROBOT.toml --log LOG [--truth GT] [--log LOG --truth GT ...]
        [--window 30s|5m ...] [--kinds white,bias] [--fix NAME,...] [--group ROBOT ...] --out FITTED.toml
        [--trim 0.999] [--cross-validate] [--truth-sigma S] [--truth-heading-sigma S] [--truth-time-sigma S]
        [--workers N | --scheduler ADDR]
        [--force] [--json]
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
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

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["fit_noise_command", "print_fit"]


@app.command("fit-noise")
@with_log_options
@with_truth_options
def fit_noise_command(
    robot: Annotated[Path, typer.Option("--robot", help="Robot file (TOML); its [noise] names the models.")],
    out: Annotated[Path, typer.Option("--out", help="Write the robot file with the fitted [noise] here.")],
    logs: Annotated[list[Path] | None, typer.Argument(
        help="Logs with ground truth (as calibrate and evaluate take them), or give each with --log, "
             "not both: the i-th --truth and --group belong to the i-th log.", show_default=False)] = None,
    log: Annotated[list[Path] | None, typer.Option(
        "--log", help="A log with ground truth; repeat it (or give the logs as arguments).")] = None,
    window: Annotated[list[str] | None, typer.Option(
        "--window", help="Windows that restart from truth: 30s (time) or 5m (odometry travel); "
                         "repeat it to fit one model to several lengths (--window 10s --window "
                         "30s); default one window per log.")] = None,
    kinds: Annotated[str, typer.Option(
        "--kinds", help="Which variances to fit: white, bias or white,bias (default: real "
                        "odometry errors grow like a bias, so both).")] = "white,bias",
    fix: Annotated[str | None, typer.Option(
        "--fix", help="Noise fields held at the robot file's value, e.g. sigma_dt.")] = None,
    min_travel: Annotated[float, typer.Option(
        "--min-travel", help="Windows travelling less [m] are left out and counted.")] = 0.05,
    cross_validate: Annotated[bool, typer.Option(
        "--cross-validate", help="Also report leave-one-log-out coverage.")] = False,
    level: Annotated[float, typer.Option("--level", help="Confidence level of the intervals.")] = 0.95,
    trim: Annotated[float, typer.Option(
        "--trim", help="Fit the bulk: window ends outside this probability's ellipse of the fit "
                       "are left out of it and counted (heavy tails); 1 keeps every window.")] = 0.999,
    method: Annotated[str, typer.Option("--method", help="exact | midpoint | euler")] = "exact",
    workers: Annotated[int | None, typer.Option(
        "--workers", help="Processes reading the logs (default: one per core for large inputs).")] = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="Dask scheduler address, e.g. tcp://host:8786.")] = None,
    truth: TruthListOption = None,
    group: Annotated[list[str] | None, typer.Option(
        "--group", help="The robot the i-th log comes from (repeat it, one per log): logs of one "
                        "robot share one draw of its bias, so the bias variances rest on the robots, "
                        "not the logs.")] = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw each fitted parameter's profile likelihood with its interval and the "
                       "in-sample coverage (white only beside white + bias) into this file (.png, .svg "
                       "or .pdf; needs the plot extra).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace an existing --out or --plot file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:
    """Maximum-likelihood white and bias noise variances from logs with ground truth, with
    profile-likelihood intervals and warnings where the data cannot identify them."""
    from odomkit.errors import InputError
    from odomkit.workflows.fit_noise import fit_noise_files, parse_kinds
    from odomkit.workflows.truth import truth_options_per_log, with_truth_topic

    if not 0 < level < 1:
        raise InputError(f"--level must be in (0, 1), got {level}")
    if not 0.5 < trim <= 1:
        raise InputError(f"--trim must be a probability in (0.5, 1], got {trim}")
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be a positive integer, got {workers}")
    paths = _logs(logs, log)
    options, base = with_truth_topic(log_opts, truth_base, bool(truth))
    per_log = truth_options_per_log(base, list(truth or []), len(paths))
    fixed = [f.strip() for f in (fix or "").split(",") if f.strip()]
    with reported_warnings() as warned, progress_bar(json_out) as progress:
        result = fit_noise_files(robot, paths, per_log, out, window=window, kinds=parse_kinds(kinds),
                                 fixed=fixed, log_options=options, min_travel=min_travel,
                                 method=method, level=level, cross_validate=cross_validate,
                                 trim=None if trim >= 1 else trim,
                                 workers=workers, scheduler=scheduler, overwrite=force,
                                 progress=progress, plot=plot, groups=group)
    result = with_warnings(result, warned)
    if json_out:
        print_json(result)
        return
    print_fit(result, already_said=warned)


def _logs(given: list[Path] | None, flagged: list[Path] | None) -> list[Path]:
    """The logs, given as arguments or each with ``--log``. Not both: the order in which
    they were typed is lost between the two (click parses options and arguments apart), and
    the i-th ``--truth`` and ``--group`` belong to the i-th log."""
    from odomkit.errors import InputError

    if given and flagged:
        raise InputError("give the logs either as arguments (fit-noise --robot R A.csv B.csv ...) or each "
                         "with --log (fit-noise --robot R --log A.csv --log B.csv ...), not both: the i-th "
                         "--truth and --group belong to the i-th log, and the order of the two forms "
                         "together is unknown")
    if not given and not flagged:
        raise InputError("no log: give the logs with ground truth as arguments (fit-noise --robot R "
                         "A.csv B.csv ...) or each with --log (fit-noise --robot R --log A.csv --log "
                         "B.csv ...)")
    return list(given or flagged or [])


def print_fit(out: dict[str, Any], already_said: Sequence[str] = ()) -> None:
    """The short text report of ``odomkit fit-noise``; its warnings go to stderr as
    ``odomkit: warning: ...``, as every command's do (those in ``already_said`` were
    printed there when raised, grouped as :func:`odomkit.cli.log_options.reported_warnings`
    prints them)."""
    key = next(k for k in out if k.startswith("interval"))
    trimmed = (f" ({out['windows_trimmed']} more left out: outside the {100 * out['trim']:g} % "
               "ellipse)" if out.get("windows_trimmed") else "")
    of = (f"{out['logs_in_groups']} log(s) in {out['groups']} group(s)" if out.get("groups") else
          f"{out['logs']} log(s)")
    print(f"fitted {len(out['parameters'])} parameter(s) on {out['windows']} window(s){trimmed} of "
          f"{of}; log-likelihood {out['log_likelihood']:.6g}")
    for name, value in out["parameters"].items():
        lo, hi = out[key][name]
        print(f"  {name:20s} {out['kinds'][name]:5s} {value:.6g}   ({100 * out['level']:g} % "
              f"profile interval {lo:.6g} .. {hi:.6g})")
    truth = out.get("truth_noise")
    if truth:
        print(f"the truth's own noise (robot file [truth]: sigma {truth['truth_sigma']:.3g} m, heading_sigma "
              f"{truth['truth_heading_sigma']:.3g} rad, time_sigma {truth['truth_time_sigma']:.3g} s) is not "
              "the robot's: evaluate and report add it to each window end")
    cov = out["coverage_in_sample"]
    print("in-sample coverage of the 50/90/95/99 % ellipses: "
          + " / ".join(f"{cov[k]:.3f}" for k in ("0.5", "0.9", "0.95", "0.99")))
    if "cross_validation" in out:
        cv = out["cross_validation"]["coverage"]
        # With --group a fold leaves out one group's logs (a robot's), not one log.
        what = "group" if out.get("groups") else "log"
        print(f"leave-one-{what}-out coverage ({out['cross_validation']['folds']} folds"
              + (", every length pooled" if "by_length" in out["cross_validation"] else "") + "): "
              + " / ".join(f"{cv[k]:.3f}" for k in ("0.5", "0.9", "0.95", "0.99")))
        for length, each in out["cross_validation"].get("by_length", {}).items():
            print(f"  {length} windows ({each['windows']}): "
                  + " / ".join(f"{each['coverage'][k]:.3f}" for k in ("0.5", "0.9", "0.95", "0.99")))
    from odomkit.workflows.results import grouped_warnings

    said = set(already_said) | set(grouped_warnings(already_said))
    for w in out["warnings"]:
        if w not in said:
            print(f"odomkit: warning: {w}", file=sys.stderr)
    for kind, path in out["outputs"].items():
        print(f"wrote {kind}: {path}")
