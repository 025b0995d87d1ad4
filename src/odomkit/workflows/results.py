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

import re
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager

import numpy as np
from numpy.typing import ArrayLike

from odomkit.errors import ModelError

__all__ = ["check_result", "collected_warnings", "grouped_warnings", "listed", "numeric_guard", "RESULT_RTOL",
           "short_names"]

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
