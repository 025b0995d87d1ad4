"""``odomkit fit-noise``: the robot file's noise variances from logs with ground truth.

Each log (with its truth file, or its own ``gt_*`` columns) is read, cut into windows that
restart from the truth (:mod:`odomkit.windows`) and turned into per-parameter covariance
bases, one log per task: in worker processes (``workers``), on a Dask cluster
(``scheduler``) or in this process. Tasks are independent and their results are gathered
in log order, so the fit is the same whatever runs them. The maximum-likelihood fit is
:func:`odomkit.calibrate.fit_noise.fit_noise`; the robot file is written again with the
fitted ``[noise]``.

:func:`fit_noise_files` takes files (``odomkit fit-noise``); :func:`fit_noise_in_memory`
takes logs and truths already in memory. Both run the same preparation and fit with the
command's defaults (one path: the file form only reads each log first), so the same inputs
give the same result. The core's building blocks
(:func:`odomkit.window_errors.log_window_basis`, :func:`odomkit.calibrate.fit_noise.fit_noise`)
default to no trimming and no truth-noise columns; these do not.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from odomkit.calibrate.fit_noise import DEFAULT_TRIM
from odomkit.errors import InputError
from odomkit.progress import NO_PROGRESS, Progress, stage

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from odomkit.calibrate.fit_noise import NoiseFit
    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.robot import Robot
    from odomkit.truth import Truth
    from odomkit.window_errors import WindowBasis
    from odomkit.windows import WindowSpec
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["FittedNoise", "fit_noise_files", "fit_noise_in_memory", "KINDS", "LoadedTask", "LogTask",
           "parse_kinds", "prepare_loaded", "prepare_log", "PreparedLog"]

KINDS = ("white", "bias")
#: Below this many log rows in all, worker processes cost more to start than they save.
PARALLEL_ROWS = 1_000_000


def parse_kinds(text: str) -> tuple[str, ...]:
    """``"white,bias"`` -> ("white", "bias"); one line naming ``--kinds`` otherwise."""
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    bad = [k for k in kinds if k not in KINDS]
    if not kinds or bad:
        raise InputError(f"--kinds must be white, bias or white,bias, got {text!r}")
    return kinds


@dataclass(frozen=True)
class LogTask:
    """One log to prepare: where it is, how to read it and its truth, and the fit's setup."""

    path: Path
    truth: TruthOptions
    log_options: LogOptions
    robot: Robot
    models: tuple[NoiseModel, ...]
    specs: tuple[WindowSpec | None, ...]
    min_travel: float
    method: str


@dataclass(frozen=True)
class PreparedLog:
    """A log's windows as bases, or why it has none (``reason``)."""

    name: str
    basis: WindowBasis | None
    rows: int
    skipped: int
    reason: str | None
    scatter: float | None = None  # the truth's fixes about a smooth path [m] (truth.scatter_sigma)
    off: tuple[str, ...] = ()  # travel or turning off the truth's by more than 2x: a unit, a robot file
    # Each window of ``basis``, in its order, as warnings name it: "log.csv 10-20 s"
    window_labels: tuple[str, ...] = ()
    # The truth interpolated between sparse knots (odomkit.truth_knots.interpolated_note), or None.
    interpolated: str | None = None
    # The truth's median fix spacing over the log's span [s], or None (fewer than two fixes there).
    spacing: float | None = None
    # Each window's --window length, in the basis's order ("10 s"; "" for one window per log)
    window_lengths: tuple[str, ...] = ()


@dataclass(frozen=True)
class LoadedTask:
    """One log in memory to prepare (:func:`fit_noise_in_memory`): its name in the result
    and warnings, the log, its truth (on the log's clock), the longest gap between the
    truth's fixes to interpolate across [s], and the fit's setup."""

    name: str
    log: OdometryLog
    truth: Truth
    max_gap: float | None
    robot: Robot
    models: tuple[NoiseModel, ...]
    specs: tuple[WindowSpec | None, ...]
    min_travel: float
    method: str


def prepare_log(task: LogTask) -> PreparedLog:
    """Read one log and its truth, cut its windows and compute their covariance bases
    (:func:`prepare_loaded` once read)."""
    from odomkit.workflows._scoring import require_truth
    from odomkit.workflows.logs import load_log

    log = load_log(task.path, task.robot, task.log_options)
    truth = require_truth(task.truth, log)
    return prepare_loaded(LoadedTask(str(task.path), log, truth, task.truth.max_gap, task.robot, task.models,
                                     task.specs, task.min_travel, task.method))


def prepare_loaded(task: LoadedTask) -> PreparedLog:
    """Cut one log in memory into windows and compute their covariance bases, with the
    truth's noise as columns (:func:`odomkit.window_errors.log_window_basis`,
    ``truth_columns=True``), and what the warnings need (its truth's scatter, motion the
    truth does not share, its fix spacing); or why it has no window."""
    from odomkit.kinematics import body_steps
    from odomkit.truth import no_overlap, scatter_sigma, truth_at, truth_noise
    from odomkit.window_errors import log_window_basis
    from odomkit.windows import cumulative_travel, why_no_windows

    name, log, truth = task.name, task.log, task.truth
    # The truth's own noise is fitted with the rest (held where the user gave it).
    basis, skipped = log_window_basis(log, task.robot, task.models, truth, task.specs,
                                      min_travel=task.min_travel, max_gap=task.max_gap,
                                      method=task.method, truth_columns=True)
    if basis is not None:
        # A unit read wrong (mph as m/s) or a steering ratio left out makes a noise fit absurd
        # with nothing else to say why: odomkit check's comparison with the truth does.
        from odomkit.calibrate.check_ratios import motion_problems

        scatter = scatter_sigma(truth)
        off = motion_problems(log, task.robot, truth, task.max_gap, noise=truth_noise(truth, scatter))
        short = Path(name).name
        from odomkit.log import clock_text

        labels = tuple(f"{short} {clock_text(log.t[w.start])}-{clock_text(log.t[w.end])} s"
                       for w in basis.windows)
        from odomkit.truth_knots import interpolated_note

        inside = truth.t[(truth.t >= log.t[0]) & (truth.t <= log.t[-1])]
        spacing = float(np.median(np.diff(inside))) if inside.size > 1 else None
        lengths = tuple(str(spec) if spec is not None else ""
                        for spec, n in zip(task.specs, basis.per_spec, strict=False) for _ in range(n))
        return PreparedLog(name, basis, len(log), skipped, None, scatter, tuple(off), labels,
                           interpolated_note(truth), spacing, lengths)
    # Why there is no window (the failure path only: sampled again for the message).
    samples = truth_at(truth, log.t, task.max_gap)
    if int(samples.valid.sum()) < 2:
        return PreparedLog(name, None, len(log), skipped, no_overlap(truth, log.t, log.meta.get("time")))
    travel = cumulative_travel(body_steps(task.robot, log))
    reason = why_no_windows(log.t, travel, samples.valid, task.specs[0], task.min_travel, skipped)
    return PreparedLog(name, None, len(log), skipped, reason)


def _grouped(bases: list[WindowBasis], groups: list[str]) -> tuple[list[WindowBasis], list[str]]:
    """One basis per group, in order of first appearance: the logs of one robot share its
    bias draw (:meth:`odomkit.window_errors.WindowBasis.merge`; their white errors are independent,
    being different runs, so the merged likelihood is exact here, not composite)."""
    from odomkit.window_errors import WindowBasis

    order = list(dict.fromkeys(groups))
    return [WindowBasis.merge([b for b, g in zip(bases, groups, strict=True) if g == name])
            for name in order], order


T = TypeVar("T")
R = TypeVar("R")


def _recorded(fn: Callable[[T], R], task: T) -> tuple[R, list[str]]:
    """``fn(task)`` in another process, with the texts of the UserWarnings it raised: a
    worker's warnings go to its own stderr in Python's raw form, never into the JSON."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        result = fn(task)
    return result, [str(w.message) for w in caught if issubclass(w.category, UserWarning)]


def _said(done: tuple[R, list[str]]) -> R:
    """A :func:`_recorded` result, its warnings raised again here, where the command collects
    them (each once: :func:`odomkit.workflows.results.collected_warnings`)."""
    result, texts = done
    for text in texts:
        warnings.warn(text, UserWarning, stacklevel=2)
    return result


def _run_all(fn: Callable[[T], R], tasks: Sequence[T], workers: int, scheduler: str | None,
             progress: Progress = NO_PROGRESS) -> list[R]:
    """``fn`` over ``tasks`` in order: on Dask, in worker processes, or here; ``progress``
    is advanced by one as each task's result arrives. A worker's warnings are raised again
    here, as if the task had run here."""
    if scheduler is not None:
        from odomkit.simulate.distributed import get_client

        client, owned = get_client(scheduler)  # one line if dask is missing
        from dask.distributed import as_completed

        try:
            futures = client.map(partial(_recorded, fn), list(tasks), pure=False)
            index = {f.key: i for i, f in enumerate(futures)}
            done: list[Any] = [None] * len(futures)
            for fut in as_completed(futures):
                done[index[fut.key]] = fut.result()
                progress.advance()
            return [_said(d) for d in done]
        finally:
            if owned:
                client.close()
    results: list[R] = []
    if workers <= 1 or len(tasks) < 2:
        for task in tasks:
            results.append(fn(task))
            progress.advance()
        return results
    # Spawned, not forked: a fork copies numba's and OpenBLAS's threads' locks mid-use and
    # can hang the child.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=context) as pool:
        for item in pool.map(partial(_recorded, fn), tasks, chunksize=max(1, len(tasks) // (4 * workers))):
            results.append(_said(item))
            progress.advance()
    return results


def _rows(path: Path) -> int:
    try:
        return max(path.stat().st_size // 40, 1)  # about 40 bytes a row of a text log
    except OSError:
        return 1


@dataclass(frozen=True)
class FittedNoise:
    """What :func:`fit_noise_in_memory` (and :func:`fit_noise_files`) fitted.

    ``robot`` is the robot the logs were fitted with; ``noise`` the fitted noise models
    (a robot file's ``[noise]``: what :func:`odomkit.track.dead_reckon_log`'s ``noise`` and
    :func:`odomkit.workflows.evaluate.evaluate_in_memory` take); ``truth`` the truth's own
    noise as a robot file's ``[truth]`` holds it (``sigma`` [m], ``heading_sigma`` [rad],
    ``time_sigma`` [s]): the honesty test adds it to every window end
    (``evaluate_in_memory(..., truth_noise=fitted.truth)``), the robot's covariance does
    not; ``fit`` the core's :class:`~odomkit.calibrate.fit_noise.NoiseFit`; ``summary`` the
    JSON of ``odomkit fit-noise`` (its keys: docs/reference/commands/fit-noise.md) without
    ``outputs`` and ``seconds``.
    """

    robot: Robot
    noise: tuple[NoiseModel, ...]
    truth: dict[str, float]
    fit: NoiseFit
    summary: dict[str, Any]

    def write(self, path: str | Path, *, overwrite: bool = False, name: str | None = None) -> Path:
        """Write the fitted robot file (``[robot]``, the fitted ``[noise]`` and ``[truth]``) to
        ``path``, refused if it exists unless ``overwrite``; ``name`` the robot's name in it.
        Returns the path written."""
        from odomkit.io.robotfile import write_robot

        return write_robot(path, self.robot, self.noise, overwrite=overwrite, truth=self.truth, name=name)


def fit_noise_in_memory(
    logs: OdometryLog | Sequence[OdometryLog],
    robot: Robot,
    noise: NoiseModel | Sequence[NoiseModel] = (),
    truths: Truth | Sequence[Truth | None] | None = None,
    *,
    window: str | Sequence[str] | None = None,
    kinds: Sequence[str] = ("white", "bias"),
    fixed: Sequence[str] = (),
    truth_held: Mapping[str, float] | None = None,
    min_travel: float = 0.05,
    max_gap: float | None = 0.5,
    method: str = "exact",
    level: float = 0.95,
    cross_validate: bool = False,
    trim: float | None = DEFAULT_TRIM,
    groups: Sequence[str] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Progress = NO_PROGRESS,
) -> FittedNoise:
    """Fit the noise of ``robot`` to logs with ground truth already in memory, as
    ``odomkit fit-noise`` does to files.

    The same preparation and fit as :func:`fit_noise_files` and the command (one path), with
    their defaults: the white and bias models of :func:`odomkit.calibrate.fit_noise.models_to_fit`
    where ``noise`` names none, the truth's own noise fitted with them (unless
    ``truth_held`` gives it), window ends outside the fit's 99.9 % ellipse left out
    (``trim``, :data:`odomkit.calibrate.fit_noise.DEFAULT_TRIM`). The core's
    :func:`~odomkit.window_errors.log_window_basis` and
    :func:`~odomkit.calibrate.fit_noise.fit_noise` are building blocks that default to
    neither: chained by hand with their defaults they give another, far more cautious model.

    Parameters
    ----------
    logs : OdometryLog or sequence of OdometryLog
        The logs (read by :mod:`odomkit.io` readers, or built from arrays); each is named in
        the result and warnings by its ``source``.
    robot : Robot
    noise : NoiseModel or sequence of NoiseModel
        The models to fit (a robot file's ``[noise]``; their values are the start and what
        ``fixed`` holds); empty: the defaults for the robot
        (:func:`~odomkit.calibrate.fit_noise.models_to_fit`).
    truths : Truth, sequence of Truth or None, or None
        One per log (None: the log's own ground truth, :func:`odomkit.truth.truth_from_log`),
        or one for every log; on the log's clock.
    window : ``"30s"``, ``"5m"``, or several (``["10s", "30s"]``: one model for every
        length); None: each log is one window.
    kinds : which variances are fitted: "white", "bias" or both (the default).
    fixed : parameter names held at their value in ``noise``.
    truth_held : mapping, optional
        The truth's own noise where it is known, held instead of fitted: ``truth_sigma`` [m],
        ``truth_heading_sigma`` [rad], ``truth_time_sigma`` [s] (``--truth-sigma`` and its
        siblings); the others are fitted. A value held is set on every truth (as the flag
        sets it on the truth file); otherwise a truth's own ``sigma`` (zero by default) weighs
        its fixes where a start heading is fitted to position-only truth.
    min_travel : windows whose odometry travels less [m] are left out and counted.
    max_gap : longest gap between the truth's fixes to interpolate across [s] (None: no limit).
    method, level, cross_validate, trim, groups, workers, scheduler, progress :
        as :func:`fit_noise_files`.

    Returns
    -------
    FittedNoise
        ``summary`` is the dict :func:`fit_noise_files` returns (without ``outputs`` and
        ``seconds``); its ``warnings`` are also issued as UserWarnings. ``write(path)``
        writes the fitted robot file.

    Examples
    --------
    The robot is the runs' own (its metres per tick and wheel base: a ``DiffDrive`` left at
    one metre per tick turns ten thousand times as much as the truth, and the fit says so).

    >>> from odomkit.data import builtin_data_path
    >>> from odomkit.io.optiodom import read_run
    >>> from odomkit.io.robotfile import read_robot
    >>> robot, _ = read_robot(builtin_data_path("optiodom_diff.toml"))
    >>> logs = [read_run(builtin_data_path(f"230620202042_run-0{i}.csv")) for i in (1, 2, 3)]
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     fitted = fit_noise_in_memory(logs, robot, window=["10s", "30s"])
    >>> [w for w in said if "turns" in str(w.message)]
    []
    >>> sorted(fitted.truth)
    ['heading_sigma', 'sigma', 'time_sigma']
    >>> [type(m).__name__ for m in fitted.noise]
    ['WheelNoise', 'SpeedNoise', 'LateralSlipNoise', 'ParameterUncertainty']
    """
    from odomkit.calibrate.fit_noise import models_to_fit
    from odomkit.windows import parse_windows
    from odomkit.workflows.results import logs_given, noise_models, truths_given

    given = logs_given(logs, "odomkit.workflows.fit_noise.fit_noise_files")
    from odomkit.io.robotfile import TRUTH_SIGMAS

    held = dict(truth_held or {})
    names_held = tuple(f"truth_{key}" for key in TRUTH_SIGMAS)  # the fit's names of the [truth] noise
    unknown = sorted(set(held) - set(names_held))
    if unknown:
        raise InputError(f"truth_held takes {', '.join(names_held)}, got {', '.join(unknown)}")
    # Held noise is the truths' own, as --truth-sigma's is the truth file's (a start heading
    # fitted to position-only fixes weighs them by it).
    found = truths_given(truths, given, {k.removeprefix("truth_"): v for k, v in held.items()})
    if groups is not None and len(groups) != len(given):
        raise InputError(f"give one group per log: {len(given)} log(s), {len(groups)} group(s)")
    specs = parse_windows(window)
    _check_trim(trim)
    file_models = noise_models(noise)
    models, default_fixed = models_to_fit(robot, file_models, kinds)
    names = _names(given)
    tasks = [LoadedTask(name, log, truth, max_gap, robot, models, specs, min_travel, method)
             for name, log, truth in zip(names, given, found, strict=True)]
    if workers is None:
        workers = (os.cpu_count() or 1) if sum(len(log) for log in given) >= PARALLEL_ROWS else 1
    with stage(progress, len(tasks), "logs"):
        prepared = _run_all(prepare_loaded, tasks, workers, scheduler, progress)
    fitted, _ = _fitted(prepared, robot, file_models, models, default_fixed, specs, kinds=kinds,
                        fixed=fixed, level=level, cross_validate=cross_validate, trim=trim,
                        held=held, groups=groups, progress=progress, from_file=False)
    return fitted


def _names(logs: Sequence[OdometryLog]) -> list[str]:
    """How the result and its warnings name each log: its ``source``, or ``log N`` (from 1)
    where that is the default ``<memory>`` or two logs share one."""
    sources = [log.source for log in logs]
    return [s if s != "<memory>" and sources.count(s) == 1 else f"log {i + 1}" for i, s in enumerate(sources)]


def _check_trim(trim: float | None) -> None:
    if trim is not None and not 0.5 < trim < 1:
        raise InputError(f"--trim must be a probability in (0.5, 1) (or none), got {trim}")


def _fitted(prepared: Sequence[PreparedLog], robot: Robot, file_models: tuple[NoiseModel, ...],
            models: tuple[NoiseModel, ...], default_fixed: frozenset[str],
            specs: tuple[WindowSpec | None, ...],
            *, kinds: Sequence[str], fixed: Sequence[str], level: float, cross_validate: bool,
            trim: float | None, held: dict[str, float], groups: Sequence[str] | None, progress: Progress,
            from_file: bool) -> tuple[FittedNoise, list[WindowBasis]]:
    """The fit of the prepared logs, for :func:`fit_noise_files` and :func:`fit_noise_in_memory`
    alike: the warnings (the fit's, the logs left out, the default models left out, the
    truth's scatter and clock), issued as UserWarnings too, and the summary; with the bases
    fitted (per group), for the figure. ``file_models`` are the models given (a robot file's
    ``[noise]`` when ``from_file``), ``held`` the truth noise given."""
    from odomkit.calibrate.fit_noise import defaults_left_out, fit_noise
    from odomkit.io.robotfile import TRUTH_SIGMAS
    from odomkit.window_errors import HEADLESS
    from odomkit.workflows._scoring import issue_notes
    from odomkit.workflows.results import check_result, numeric_guard

    used = [p for p in prepared if p.basis is not None]
    if not used:
        first = prepared[0]
        raise InputError(first.reason or "no windows", source=first.name)
    notes = []
    missing = defaults_left_out(robot, file_models) if "white" in kinds else {}
    if missing:
        # A user study: the shipped OptiOdom robot file names k_left, k_right, so its fit had no
        # slip terms, unlike the published defaults, and nothing said so.
        given = ", ".join(sorted({type(m).__name__ for m in file_models if m.kind == "white"}))
        if from_file:
            where = "the robot file's [noise]"
            add = ", ".join(f"{f} = 0" for fs in missing.values() for f in fs) + " to its [noise]"
        else:
            where = "the noise given"
            add = ", ".join(f"{cls}({', '.join(f'{f}=0' for f in fs)})" for cls, fs in missing.items())
            add += " to it"
        notes.append(f"{where} names its white models ({given}), so those alone are "
                     f"fitted; fit-noise's default set for a {robot.type_name} also has "
                     f"{', '.join(missing)}: to fit them too, add {add}")
    left_out = [p for p in prepared if p.basis is None]
    if left_out:
        shown = "; ".join(f"{p.name}: {p.reason}" for p in left_out[:3])
        more = f"; and {len(left_out) - 3} more" if len(left_out) > 3 else ""
        notes.append(f"{len(left_out)} of {len(prepared)} logs left out: {shown}{more}")
    unused = _lengths_without_windows(specs, [p.basis.per_spec for p in prepared if p.basis is not None])
    if unused:
        notes.append(unused)
    bases = [p.basis for p in used if p.basis is not None]
    dropped = sum(b.dropped for b in bases)
    notes += [n for b in bases for n in b.notes]  # where a whole-log window starts late, and why
    notes += [f"the noise fit takes odometry that does not move as the truth does: {o}"
              for p in used for o in p.off]
    notes += [f"{p.name}: {p.interpolated}" for p in used if p.interpolated]
    if not any(len(b.windows) for b in bases):
        # Whole-log windows say why they have no start (no row gives a heading) in their notes.
        why = "; ".join(n for b in bases for n in b.notes[:1])
        raise InputError(f"every window ({dropped}) was left out: " + (why or (
                         "no start heading could be fitted to the position-only truth around its start (too "
                         "few fixes, fixes off a smooth path by more than 3 --truth-sigma, too noisy, or the "
                         "robot hardly moves there)")), source=None if why else used[0].name)
    # The windows left out, each named with its times by its log (window_errors.headless_note).
    named = [n for b in bases for n in b.notes if HEADLESS in n]
    if dropped and not named:
        notes.append(f"{dropped} {HEADLESS}")
    # What left the windows few, for an error that the fit finds too few of them: a user
    # study's half log was told only "1 window(s) give 2 numbers for 7 free noise
    # parameter(s)", its first window dropped and its 30 s length without a window unsaid.
    why_few = ([unused] if unused else []) + named
    names = [p.name for p in used]
    labels = [p.window_labels for p in used]
    lengths = [p.window_lengths for p in used]
    if groups is not None:
        of_used = [g for p, g in zip(prepared, groups, strict=True) if p.basis is not None]
        bases, names = _grouped(bases, of_used)
        # Merged as the bases are (WindowBasis.merge: the group's logs in order).
        labels = [tuple(x for lab, g in zip(labels, of_used, strict=True) if g == name for x in lab)
                  for name in names]
        lengths = [tuple(x for lab, g in zip(lengths, of_used, strict=True) if g == name for x in lab)
                   for name in names]
    scatter = _pooled_scatter(used)
    with numeric_guard("the noise fit"), stage(progress, None, "fitting"):
        try:
            fit = fit_noise(bases, models, robot, kinds=kinds, fixed=set(fixed) | default_fixed,
                            level=level, log_names=names, cross_validate=cross_validate,
                            trim=trim, truth_held=held, window_labels=labels, truth_scatter=scatter,
                            window_lengths=lengths)
        except InputError as exc:
            if not why_few:
                raise
            raise InputError(f"{exc}; " + "; ".join(why_few)) from exc
    # An interval's upper bound may be infinite (the data do not bound it; JSON null).
    check_result("the noise fit", {"parameters": list(fit.parameters.values()),
                                   "variances": list(fit.variances.values()),
                                   "log_likelihood": fit.log_likelihood,
                                   "lower bounds": [lo for lo, _ in fit.interval.values()]})
    truth_noise = fit.truth_noise or {}
    truth_table = {key: truth_noise.get(f"truth_{key}", 0.0) for key in TRUTH_SIGMAS}
    result = fit.to_dict()
    below = _floor_below_scatter(fit.parameters.get("truth_sigma"), scatter,
                                 np.concatenate([b.error[:, :2] for b in bases]))
    clock = None if "truth_time_sigma" in held else _clock_beyond_spacing(fit, used)
    said = notes + list(fit.warnings) + [w for w in (below, clock) if w]
    result["warnings"] = said
    result["truth_scatter_sigma"] = scatter
    if groups is not None:  # "logs" counts the groups then (each one basis): the logs too
        result["groups"] = len(names)
        result["logs_in_groups"] = len(used)
    result.update({
        "window": None if specs == (None,) else ",".join(str(x) for x in specs),
        "windows_skipped": sum(p.skipped for p in prepared),
        "windows_dropped": dropped,
        "logs_left_out": [p.name for p in left_out],
    })
    # Issued, not only returned: in a notebook the fit's warnings (a model family that does not
    # describe the logs, coverage off its range) showed nowhere (user study s24, M4). The CLI
    # collects them and prints each once.
    issue_notes(said, stacklevel=4)
    return FittedNoise(robot, tuple(fit.models), truth_table, fit, result), bases


def fit_noise_files(
    robot_path: str | Path,
    logs: str | Path | Sequence[str | Path],
    truths: TruthOptions | Sequence[TruthOptions] | None,
    out: str | Path,
    *,
    window: str | Sequence[str] | None = None,
    kinds: Sequence[str] = ("white", "bias"),
    fixed: Sequence[str] = (),
    log_options: LogOptions | None = None,
    min_travel: float = 0.05,
    method: str = "exact",
    level: float = 0.95,
    cross_validate: bool = False,
    trim: float | None = DEFAULT_TRIM,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress: Progress = NO_PROGRESS,
    plot: str | Path | None = None,
    groups: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Fit the noise of ``robot_path`` to ``logs`` and write the fitted robot file to ``out``.

    For logs and truths already in memory: :func:`fit_noise_in_memory`, whose preparation and
    fit this runs on each log once read (the same defaults, the same result).

    Parameters
    ----------
    robot_path : the robot file; its ``[noise]`` names the models (defaults per vehicle
        when it names none: :func:`odomkit.calibrate.fit_noise.models_to_fit`).
    logs : log files (or one).
    truths : one :class:`TruthOptions` per log (path None: the log's own ``gt_*`` columns),
        or one for every log; None: each log's own truth.
    out : the robot file to write (refused if it exists, unless ``overwrite``, and always if
        it is one of the inputs).
    window : ``"30s"``, ``"5m"`` (:func:`odomkit.windows.parse_window`), or several
        (``["10s", "30s"]``: one model fitted to windows of every length together, so that
        it holds at each; a composite likelihood, see
        :meth:`odomkit.window_errors.WindowBasis.merge`); None: each log is one window.
    kinds : which models' variances are fitted ("white", "bias"); both by default, since
        a real robot's errors over a run grow like a bias (a constant scale or offset
        error per run), which white noise alone covers on some lengths only.
    fixed : parameter names held at the robot file's value.
        The truth's own noise (``truth_sigma`` [m], ``truth_heading_sigma`` [rad],
        ``truth_time_sigma`` [s]; a floor that does not grow with the window) is fitted
        too, unless ``truths`` give it (``--truth-sigma``, ``--truth-heading-sigma``,
        ``--truth-time-sigma``: then held), and written to the
        robot file's ``[truth]`` table, which the honesty test adds to each window end.
    workers : processes for reading logs and computing bases; None: one per core when
        the logs are large (:data:`PARALLEL_ROWS`), else this process.
    scheduler : a Dask scheduler address: run those tasks on its cluster instead.
    trim : fit the bulk: window ends outside this probability's ellipse of the fit are left
        out and counted (:func:`odomkit.calibrate.fit_noise.fit_noise`); None: keep all.
    progress : two stages (:mod:`odomkit.progress`): ``"logs"``, one unit per log read and
        cut into windows, then ``"fitting"`` (of unknown length).
    plot : draw each fitted parameter's profile likelihood and the in-sample coverage into
        this .png, .svg or .pdf file (:func:`odomkit.workflows.figures.profiles_figure`).
    groups : one name per log (``--group``): logs of one name come from one robot and share
        one draw of its bias (its wheel scales, its yaw-rate scale), so the bias variances
        rest on as many draws as there are groups, not logs; the per-log checks and
        ``cross_validate`` then leave out a group at a time. None: each log is its own.

    Returns
    -------
    dict: the JSON output of ``odomkit fit-noise`` (its keys: docs/reference/commands/fit-noise.md);
    an interval's upper bound is ``inf`` (JSON null) where the data do not bound the
    parameter. Its ``warnings`` are also issued as UserWarnings.
    """
    from odomkit.calibrate.fit_noise import models_to_fit
    from odomkit.io.files import check_outputs
    from odomkit.io.robotfile import read_robot, read_robot_name
    from odomkit.windows import parse_windows
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.results import paths_given, truths_per_log
    from odomkit.workflows.truth import clock_from_robot

    started = time.perf_counter()
    if not isinstance(logs, str | os.PathLike) and not logs:
        raise InputError("fit-noise needs at least one --log")
    logs = paths_given(logs, "log", "odomkit.workflows.fit_noise.fit_noise_in_memory")
    if groups is not None and len(groups) != len(logs):
        raise InputError(f"give one --group per log: {len(logs)} log(s), {len(groups)} group(s)")
    truths = truths_per_log(truths, len(logs))
    specs = parse_windows(window)
    _check_trim(trim)
    # Checked against the inputs too: ``--out ROBOT --force`` must not replace the robot file.
    check_outputs({"--out": out, "--plot": plot}, overwrite=overwrite,
                  inputs=[robot_path, *logs, *(t.path for t in truths if t.path is not None)])
    if plot is not None:
        from odomkit.plot import check_plot_file

        check_plot_file(plot)
    robot, file_models = read_robot(robot_path)
    # The truth's clock offset is the calibration's (the robot file's [truth] time_offset)
    # unless --truth-time-offset gives it; it is applied, not fitted, here.
    truths = clock_from_robot(robot_path, truths)
    models, default_fixed = models_to_fit(robot, file_models, kinds)
    options = log_options if log_options is not None else LogOptions()
    tasks = [LogTask(Path(p), t, options, robot, models, specs, min_travel, method)
             for p, t in zip(logs, truths, strict=True)]
    if workers is None:
        big = sum(_rows(Path(p)) for p in logs) >= PARALLEL_ROWS
        workers = (os.cpu_count() or 1) if big else 1
    with stage(progress, len(tasks), "logs"):
        prepared = _run_all(prepare_log, tasks, workers, scheduler, progress)
    held = truths[0].held  # the truth-noise flags are shared by every log
    fitted, bases = _fitted(prepared, robot, file_models, models, default_fixed, specs, kinds=kinds,
                            fixed=fixed, level=level, cross_validate=cross_validate, trim=trim, held=held,
                            groups=groups, progress=progress, from_file=True)
    offset = truths[0].time_offset or truths[0].file_clock  # kept: the robot file's, or as given
    if offset:
        fitted = replace(fitted, truth={**fitted.truth, "time_offset": float(offset)})
    written = fitted.write(out, overwrite=overwrite, name=read_robot_name(robot_path))
    result = dict(fitted.summary)
    result.update({"outputs": {"robot": str(written)}, "seconds": time.perf_counter() - started})
    if plot is not None:
        drawn = _noise_plot(plot, bases, models, robot, fitted.fit, kinds, set(fixed) | default_fixed, level,
                            trim, overlapping=len(specs) > 1)
        result["outputs"] = {"robot": str(written), "plot": str(drawn)}
    return result


def _clock_beyond_spacing(fit: NoiseFit, used: Sequence[PreparedLog]) -> str | None:
    """:func:`odomkit.calibrate.noise_plausible.implausible_truth_clock` for a fitted
    ``truth_time_sigma``, against the widest of the logs' truth spacings (the most lenient);
    nothing where the fit has already called it implausible (a tenth of a window)."""
    from odomkit.calibrate.noise_plausible import implausible_truth_clock

    value = fit.parameters.get("truth_time_sigma")
    if value is None or any(w.startswith("truth_time_sigma =") for w in fit.warnings):
        return None
    spacings = [p.spacing for p in used if p.spacing is not None]
    return implausible_truth_clock(float(value), max(spacings) if spacings else None)


def _lengths_without_windows(specs: Sequence[WindowSpec | None],
                             counts: Sequence[Sequence[int]]) -> str | None:
    """A warning naming each ``--window`` length that no log had a window of (longer than
    every log inside its truth, or travelling less than ``--min-travel``), where others did:
    the fit then rests on the other lengths alone, which the user did not ask for."""
    if len(specs) < 2 or not counts:
        return None
    empty = [str(spec) for j, spec in enumerate(specs) if not any(c[j] for c in counts if len(c) > j)]
    if not empty:
        return None
    return (f"--window {', '.join(empty)}: no log has a window of that length (each is shorter inside "
            "its truth, or its windows travel less than --min-travel); the fit rests on the other "
            "length(s) alone")


def _pooled_scatter(prepared: Sequence[PreparedLog]) -> float | None:
    """The logs' truth scatter (:func:`odomkit.truth.scatter_sigma`) pooled as an RMS [m]."""
    found = [p.scatter for p in prepared if p.scatter is not None]
    return math.sqrt(sum(x * x for x in found) / len(found)) if found else None


#: The fixes' scatter is worth a word only where its variance at a window's two ends is at
#: least this share of the window-end errors' own mean square per axis: a 1 mm motion capture
#: under errors of centimetres changes no fit, wherever the fit put it.
SCATTER_SHARE_THAT_MATTERS = 0.05


def _floor_below_scatter(fitted: float | None, scatter: float | None,
                         errors: NDArray[np.float64]) -> str | None:
    """A warning where the fitted ``truth_sigma`` is under half the fixes' own scatter: every
    window end holds that noise, so the fit has put it elsewhere (in ``truth_time_sigma``,
    which a car at a steady speed cannot tell from it, or in the robot's noise).

    ``errors``, shape (W, 2), are the window-end position errors [m]; nothing is said where
    the scatter is immaterial to them (:data:`SCATTER_SHARE_THAT_MATTERS`)."""
    if fitted is None or scatter is None or fitted >= 0.5 * scatter:
        return None
    mean_square = float(np.nanmean(np.square(errors))) if errors.size else 0.0
    if 2.0 * scatter**2 < SCATTER_SHARE_THAT_MATTERS * mean_square:
        return None
    return (f"the fitted truth_sigma ({fitted:.3g} m) is under half the scatter of the truth's own fixes "
            f"about a smooth path ({scatter:.3g} m per axis, odomkit.truth.scatter_sigma), which every "
            "window end holds: the fit has put the truth's noise elsewhere (truth_time_sigma, the robot's "
            f"noise); if the fixes' noise is known, give it (--truth-sigma {scatter:.3g} if it is white)")


#: The unit of each noise field (the variance parameter is its square for σ and k fields).
_NOISE_UNITS = {"k_left": "m^½", "k_right": "m^½", "alpha_ss": "m", "psd_gyro": "rad²/s",
               "psd_compass": "rad²·s", "alpha_lateral": "m", "alpha_turn": "rad²/rad",
               "alpha_turn_travel": "m²/rad", "sigma_speed": "m/s", "sigma_steer": "rad",
               "sigma_dt": "s", "sigma_distance": "m", "sigma_angle": "rad", "sigma_wheel_base": "m",
               "sigma_scale_left": "relative", "sigma_scale_right": "relative",
               "sigma_steering_offset": "rad",
               "sigma_yaw_rate_offset": "rad/s", "sigma_yaw_rate_scale": "relative",
               "sigma_heading_offset": "rad", "truth_sigma": "m", "truth_heading_sigma": "rad",
               "truth_time_sigma": "s"}


def _noise_plot(plot: str | Path, bases: Sequence[WindowBasis], models: Sequence[NoiseModel],
                robot: Robot, fit: NoiseFit, kinds: Sequence[str], fixed: set[str], level: float,
                trim: float | None, *, overlapping: bool = False) -> Path:
    """``fit-noise --plot``: the profiles of the fit and its in-sample coverage; when it
    fitted white and bias noise, beside the coverage of a white-only refit (bias at zero),
    and the leave-one-log-out coverage when it was cross-validated. The binomial band of
    the coverage diagram assumes independent window ends: with windows of several lengths
    (``overlapping``) they are not, and no band is drawn."""
    from odomkit.calibrate.fit_noise import fit_noise
    from odomkit.calibrate.profile import noise_profiles
    from odomkit.workflows.figures import profiles_figure

    profiles = noise_profiles(bases, models, robot, fit, kinds=kinds, fixed=fixed)
    label = " + ".join(k for k in ("white", "bias") if k in kinds)
    coverages = {f"{label} (this fit)": fit.coverage_in_sample}
    if "bias" in kinds and "white" in kinds:
        white = tuple(m if m.kind != "bias"
                      else m.from_variances({n: 0.0 for n in m.variance_parameters(robot)}) for m in models)
        held = {k: (fit.truth_noise or {})[k] for k in fit.truth_held}
        alone = fit_noise(bases, white, robot, kinds=("white",), fixed=fixed, level=level, trim=trim,
                          truth_held=held)
        coverages["white only (refitted, bias zero)"] = alone.coverage_in_sample
    if fit.cross_validation is not None:
        coverages["leave-one-log-out"] = fit.cross_validation["coverage"]  # type: ignore[assignment]
    units = {p.name: _NOISE_UNITS.get(p.name.rsplit(".", 1)[-1], "") for p in profiles}
    # Coverage is scored on every window end, the trimmed ones too.
    scored = None if overlapping else fit.windows + fit.trimmed
    return profiles_figure(plot, profiles, units=units, coverages=coverages, n_scored=scored,
                           title=f"fit-noise: profile likelihoods ({100 * level:g} % intervals) and coverage")
