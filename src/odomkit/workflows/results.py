"""The last check of every command: the numbers it returns are finite, its covariances
symmetric positive semi-definite, and numeric trouble on the way is one line, not a
traceback or a NaN printed as ``null`` (issue 10).

Extreme but finite inputs (a wheel base of 1e-300 m, a noise of 1e200 m^½) make the
arithmetic overflow or underflow. Inside :func:`numeric_guard` numpy computes on quietly
(``inf``/``nan`` instead of RuntimeWarnings printed before an error), and the failures
that cannot compute on (a Python float overflowing, ``math.cos(inf)``, an SVD that does not
converge on ``inf``) become one :class:`~odomkit.errors.ModelError`; :func:`check_result` then names
the first number that is not finite.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from odomkit.errors import InputError, ModelError

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.noise import NoiseModel
    from odomkit.truth import Truth
    from odomkit.workflows.truth import TruthOptions

__all__ = ["check_result", "collected_warnings", "grouped_warnings", "listed", "logs_given", "noise_models",
           "numeric_guard",
           "paths_given", "RESULT_RTOL", "short_names", "truths_given", "truths_per_log"]

#: Asymmetry and negative eigenvalue a computed covariance may show, relative to its largest
#: entry: rounding of long recursions and prefix sums (~1e-13), far below any real defect.
RESULT_RTOL = 1e-8

_ADVICE = "check the units and the size of the inputs (robot file, log, flags)"


@contextmanager
def numeric_guard(what: str) -> Iterator[None]:
    """Run a command's numerics with numpy's floating-point warnings off and its overflow
    failures turned into one :class:`~odomkit.errors.ModelError` naming ``what``.

    Examples
    --------
    >>> with numeric_guard("the track"):
    ...     float(np.float64(1e300) * 1e300)
    inf
    >>> with numeric_guard("the track"):
    ...     2.0 ** 5000
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: the track: a number overflowed (Numerical result out of range); \
check the units and the size of the inputs (robot file, log, flags)
    """
    with np.errstate(all="ignore"):
        try:
            yield
        except OverflowError as exc:
            reason = exc.args[-1] if exc.args else exc
            raise ModelError(f"{what}: a number overflowed ({reason}); {_ADVICE}") from None
        except (FloatingPointError, np.linalg.LinAlgError) as exc:
            raise ModelError(f"{what}: the numerics failed ({exc}), a number is out of range; "
                             f"{_ADVICE}") from None
        except ValueError as exc:
            # ``math.cos(inf)``, ``math.sqrt(-1.0)``: the math module raises ValueError where
            # numpy would return nan. Only that message: other ValueErrors are real bugs.
            if str(exc) != "math domain error":
                raise
            raise ModelError(f"{what}: the numerics failed (math domain error), a number is out of "
                             f"range; {_ADVICE}") from None


def check_result(what: str, values: Mapping[str, ArrayLike | None],
                 covariances: Mapping[str, ArrayLike | None] | None = None) -> None:
    """Raise if a returned number is not finite or a covariance is not symmetric PSD.

    Parameters
    ----------
    what : str
        The result, for the message (``"the track"``).
    values : mapping of str to array_like, nested mapping or None
        Named numbers or arrays that must be finite (None: not computed, skipped); a
        nested mapping is checked entry by entry (``cg.cw``).
    covariances : mapping of str to array_like or None, optional
        Named covariances, shape (3, 3) or (N, 3, 3): all finite; the last one symmetric
        and positive semi-definite to :data:`RESULT_RTOL` of its largest entry.

    Raises
    ------
    ModelError
        ``"{what}: {name} is not finite (inf); a number overflowed; check ..."`` or
        ``"... is not a covariance ..."``.

    Examples
    --------
    >>> check_result("the fit", {"k_left": 0.001, "mean": [0.0, 1.0]})
    >>> check_result("the fit", {"k_left": 0.001, "mean": [0.0, float("nan")]})
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: the fit: mean is not finite (nan); a number overflowed or \
lost all precision; check the units and the size of the inputs (robot file, log, flags)
    """
    for name, value in _flat({**values, **(covariances or {})}):
        arr = np.asarray(value, dtype=float)
        bad = ~np.isfinite(arr)
        if bad.any():
            raise ModelError(f"{what}: {name} is not finite ({float(arr[bad].flat[0])!r}); a number "
                             f"overflowed or lost all precision; {_ADVICE}")
    for name, cov in (covariances or {}).items():
        if cov is not None:
            _check_psd(what, name, np.asarray(cov, dtype=float))


def _flat(values: Mapping[str, object], prefix: str = "") -> Iterator[tuple[str, ArrayLike]]:
    """(name, array) pairs, nested dicts (``{"cg": {"cw": [x, y]}}``) named ``cg.cw``."""
    for name, value in values.items():
        if isinstance(value, Mapping):
            yield from _flat(value, f"{prefix}{name}.")
        elif value is not None:
            yield f"{prefix}{name}", value  # type: ignore[misc]


def _check_psd(what: str, name: str, cov: np.ndarray) -> None:
    last = cov.reshape(-1, *cov.shape[-2:])[-1] if cov.ndim > 2 else cov
    scale = float(np.max(np.abs(last))) if last.size else 0.0
    if scale == 0.0:
        return
    asymmetric = float(np.max(np.abs(last - last.T))) > RESULT_RTOL * scale
    if asymmetric or float(np.min(np.linalg.eigvalsh(0.5 * (last + last.T)))) < -RESULT_RTOL * scale:
        raise ModelError(f"{what}: {name} is not a covariance (not symmetric positive "
                         f"semi-definite: {last.tolist()}); the numerics lost all precision; {_ADVICE}")


@contextmanager
def collected_warnings() -> Iterator[list[str]]:
    """Collect the UserWarnings raised inside the block: the yielded list gets their texts,
    once each, whitespace folded to one line, when the block ends (also when it raises).
    odomkit warns with UserWarning; other categories (a library's DeprecationWarning,
    numpy's RuntimeWarning) are warned again afterwards, under Python's own filters."""
    texts: list[str] = []
    others: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            try:
                yield texts
            finally:
                for item in caught:
                    text = " ".join(str(item.message).split())
                    if not issubclass(item.category, UserWarning):
                        others.append(item)
                    elif text not in texts:
                        texts.append(text)
    finally:
        for item in others:  # outside catch_warnings: Python's own display
            warnings.showwarning(item.message, item.category, item.filename, item.lineno)


def short_names(paths: Sequence[str], among: Sequence[str] = ()) -> list[str]:
    """How a warning names each of ``paths``: its file name where no two of ``paths`` and
    ``among`` (the other files of the command) share one, else the paths as given
    (``run1/odom.csv`` and ``run2/odom.csv``)."""
    def name(path: str) -> str:
        return re.split(r"[\\/]", path.rstrip("/\\"))[-1] or path

    every = set(paths) | set(among)
    unique = len({name(p) for p in every}) == len(every)
    return [name(p) for p in paths] if unique else list(paths)


def listed(items: Sequence[str], limit: int = 3) -> str:
    """At most ``limit`` of ``items`` and how many more: ``a, b, c and 21 more``."""
    shown = ", ".join(items[:limit])
    return shown + (f" and {len(items) - limit} more" if len(items) > limit else "")


#: An already grouped warning's head, ``6 logs (a.csv, b.csv, c.csv and 3 more)``.
_GROUPED = re.compile(r"\d+ \S+ \(.*\)")


def _about_one_file(head: str) -> bool:
    """Whether ``head``, the text before a warning's first ``": "``, is a file's path (a
    folder in it, or a file extension) and not a group of them."""
    path_like = "/" in head or "\\" in head or re.search(r"\.[A-Za-z][A-Za-z0-9]*$", head) is not None
    return bool(head) and path_like and not head.startswith("-") and _GROUPED.fullmatch(head) is None


def grouped_warnings(texts: Sequence[str], noun: str = "logs", among: Sequence[str] = ()) -> list[str]:
    """``texts`` once each, where those that say the same of different files (``PATH: text``)
    are one line, ``3 logs (a.csv, b.csv, c.csv): text`` (at most three named, then ``and N
    more``; :func:`short_names`, file names where neither ``among``, the command's files,
    nor the files the texts name share one), in the place of the first of them.

    A command that reads many logs (evaluate on 86 short runs) would otherwise repeat one
    warning per log and push its results off the screen.

    Examples
    --------
    >>> grouped_warnings(["a/x.csv: no RPE over 1 m", "b/y.csv: no RPE over 1 m", "only 3 windows"])
    ['2 logs (x.csv, y.csv): no RPE over 1 m', 'only 3 windows']
    """
    order: list[tuple[bool, str]] = []  # (a group?, its text after the path, or the whole text)
    paths: dict[str, list[str]] = {}
    for text in dict.fromkeys(texts):
        head, sep, rest = text.partition(": ")
        if not (sep and _about_one_file(head)):
            order.append((False, text))
            continue
        if rest not in paths:
            paths[rest] = []
            order.append((True, rest))
        paths[rest].append(head)
    files = [*among, *(p for named in paths.values() for p in named)]
    out = []
    for group, text in order:
        named = paths[text] if group else []
        if len(named) == 1:
            out.append(f"{named[0]}: {text}")
        elif group:
            out.append(f"{len(named)} {noun} ({listed(short_names(named, files))}): {text}")
        else:
            out.append(text)
    return out


def paths_given(given: str | os.PathLike[str] | Sequence[str | os.PathLike[str]], what: str = "log",
                in_memory: str | None = None) -> list[str | Path]:
    """The files a workflow function was given, as a list: a sequence of paths, or one path
    (``str`` or :class:`~pathlib.Path`) as a list of one (a ``str`` is never read as the
    sequence of its characters). ``what`` names a file in messages (``"log"``); ``in_memory``
    names the function that takes objects instead (``"odomkit.workflows.evaluate.evaluate_in_memory"``),
    for the message when one is given here.

    Raises
    ------
    InputError
        One line where nothing is given, or an item is not a path.

    Examples
    --------
    >>> paths_given("run.csv")
    ['run.csv']
    >>> paths_given(["a.csv", "b.csv"])
    ['a.csv', 'b.csv']
    """
    if isinstance(given, str | os.PathLike):
        return [given if isinstance(given, str) else Path(given)]
    try:
        items = list(given)
    except TypeError:
        items = [given]  # type: ignore[list-item]  # reported as not a path below
    if not items:
        raise InputError(f"no {what}: give a {what} file's path or a list of them")
    for item in items:
        if not isinstance(item, str | os.PathLike):
            kind = type(item).__name__
            instead = f"; for {kind} objects in memory use {in_memory}" if in_memory else ""
            raise InputError(f"each {what} must be a file path (str or pathlib.Path), got a {kind}{instead}")
    return [x if isinstance(x, str) else Path(x) for x in items]


def truths_per_log(truth: TruthOptions | Sequence[TruthOptions] | None, count: int,
                   what: str = "log") -> list[TruthOptions]:
    """One :class:`~odomkit.workflows.truth.TruthOptions` per file of a workflow function:
    None gives each file its own truth (``TruthOptions()``: its ``gt_*`` columns, an OptiOdom
    or Snowhite log's), one ``TruthOptions`` is every file's, and a sequence must hold one per
    file (the i-th for the i-th), else one line."""
    from odomkit.workflows.truth import TruthOptions

    if truth is None:
        return [TruthOptions()] * count
    if isinstance(truth, TruthOptions):
        return [truth] * count
    items = list(truth)
    bad = [type(t).__name__ for t in items if not isinstance(t, TruthOptions)]
    if bad:
        raise InputError(f"truth must be TruthOptions (or a list of them, or None for each {what}'s own), "
                         f"got a {bad[0]}")
    if len(items) != count:
        raise InputError(f"give one TruthOptions per {what}: {count} {what}(s), {len(items)} TruthOptions "
                         f"(or one TruthOptions for every {what}, or None for each {what}'s own truth)")
    return items


def logs_given(logs: OdometryLog | Sequence[OdometryLog], files: str) -> list[OdometryLog]:
    """The logs a workflow function takes in memory, as a list: one :class:`~odomkit.log.OdometryLog`
    or a sequence of them; one line otherwise, naming ``files``, the function that takes
    paths instead (``"odomkit.workflows.evaluate.evaluate_logs"``)."""
    from odomkit.log import OdometryLog

    if isinstance(logs, OdometryLog):
        return [logs]
    if isinstance(logs, str | os.PathLike):
        raise InputError(f"expected OdometryLog objects, got a path ({logs}); for log files use {files}")
    try:
        items = list(logs)
    except TypeError:
        items = [logs]  # type: ignore[list-item]  # reported as not a log below
    if not items:
        raise InputError("no log: give an OdometryLog or a list of them")
    for item in items:
        if not isinstance(item, OdometryLog):
            kind = "a path" if isinstance(item, str | os.PathLike) else f"a {type(item).__name__}"
            raise InputError(f"each log must be an OdometryLog (odomkit.log), got {kind}; for log files use "
                             f"{files}")
    return items


def noise_models(noise: NoiseModel | Sequence[NoiseModel]) -> tuple[NoiseModel, ...]:
    """One noise model or several (a NoiseSet's models too) as a tuple, in the order given:
    what the workflow functions that take logs in memory take as ``noise``."""
    from odomkit.noise import NoiseModel, NoiseSet

    if isinstance(noise, NoiseModel):
        return (noise,)
    if isinstance(noise, NoiseSet):
        return tuple(noise.models)
    return tuple(noise)


def truths_given(truths: Truth | Sequence[Truth | None] | None, logs: Sequence[OdometryLog],
                 truth_noise: Mapping[str, float] | None = None) -> list[Truth]:
    """One :class:`~odomkit.truth.Truth` per log of a workflow function that takes logs in
    memory: None (or a None in the sequence) is the log's own truth
    (:func:`odomkit.truth.truth_from_log`: its ground truth, an OptiOdom or Snowhite log's),
    one ``Truth`` is every log's, a sequence holds one per log (the i-th for the i-th); one
    line where a log has none or the count differs.

    ``truth_noise``, a robot file's ``[truth]`` table (``sigma`` [m], ``heading_sigma``
    [rad], ``time_sigma`` [s]; what :func:`odomkit.workflows.fit_noise.fit_noise_in_memory`
    returns as ``truth``), replaces those of every truth; None keeps each truth's own."""
    from odomkit.truth import Truth, truth_from_log
    from odomkit.workflows.truth import warn_of_truth, without_spikes

    if truths is None or isinstance(truths, Truth):
        items: list[Truth | None] = [truths] * len(logs)
    else:
        try:
            items = list(truths)
        except TypeError:
            items = [truths]  # type: ignore[list-item]  # reported as not a Truth below
        if len(items) != len(logs):
            raise InputError(f"give one Truth per log: {len(logs)} log(s), {len(items)} truth(s) (or one "
                             "Truth for every log, or None for each log's own ground truth)")
    from odomkit.io.robotfile import TRUTH_SIGMAS  # a robot file's [truth] noise: σ [m], σθ [rad], σt [s]

    noise = dict(truth_noise or {})
    unknown = sorted(set(noise) - set(TRUTH_SIGMAS))
    if unknown:
        more = ("; a clock offset is not noise: move the truth's clock (Truth.t - offset) before" if
                "time_offset" in unknown else "")
        raise InputError(f"truth_noise takes {', '.join(TRUTH_SIGMAS)} (a robot file's [truth]), got "
                         f"{', '.join(unknown)}{more}")
    out = []
    for log, truth in zip(logs, items, strict=True):
        if truth is not None and not isinstance(truth, Truth):
            raise InputError(f"each truth must be an odomkit.truth.Truth or None, got a "
                             f"{type(truth).__name__}")
        found = truth if truth is not None else truth_from_log(log)
        if found is None:
            raise InputError("no truth: the log has no ground truth of its own; give a Truth "
                             "(odomkit.truth.Truth, or odomkit.io.truth.read_truth) for it",
                             source=log.source)
        found = without_spikes(found)  # as a truth file is screened and asked when a command reads it
        warn_of_truth(found, log)
        if noise:
            from dataclasses import replace

            found = replace(found, sigma=float(noise.get("sigma", found.sigma)),
                            heading_sigma=float(noise.get("heading_sigma", found.heading_sigma)),
                            time_sigma=float(noise.get("time_sigma", found.time_sigma)))
        out.append(found)
    return out
