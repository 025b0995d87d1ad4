"""Writing files without ever replacing one the user did not ask us to replace.

Every command that writes checks *all* its output paths with :func:`check_outputs` before it
computes or writes anything, so a refusal leaves nothing half-done: an existing file without
``--force``, a folder where a file is wanted (or a file where a folder is), a missing or
read-only folder, two outputs on one path, or an output on one of the inputs.
"""

from __future__ import annotations

import os
from collections.abc import Collection, Iterable, Mapping
from pathlib import Path

from odomkit.errors import InputError

__all__ = ["check_outputs", "EXISTS_ALREADY", "refuse_overwrite", "write_new_text"]

#: What every writer says of an output that exists: the command line's flag and the Python
#: writers' parameter, since both reach the same check.
EXISTS_ALREADY = "exists already; pass --force to replace it (overwrite=True from Python)"


def _key(path: Path) -> str:
    """One spelling per file: absolute, symlinks and ``..`` resolved, case as on disk."""
    return os.path.normcase(str(path.resolve(strict=False)))


def _nearest_existing(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(path.anchor or ".")


def check_outputs(
    outputs: Mapping[str, str | Path | None],
    *,
    overwrite: bool = False,
    folders: Collection[str] = (),
    inputs: Iterable[str | Path] = (),
) -> dict[str, Path]:
    """Check a command's output paths, all before any is written.

    Parameters
    ----------
    outputs : mapping of str to path or None
        Each output by the flag that names it (``{"--out": "track.csv", "--tum": None}``);
        None means not asked for. The flag appears in the messages.
    overwrite : bool
        ``--force``: an existing file may be replaced (never a folder, nor an input).
    folders : collection of str
        The keys of ``outputs`` that are folders to write into (made if missing, parents
        included); an existing folder is fine, an existing file is not. Files inside such a
        folder need not have an existing parent.
    inputs : iterable of path
        Files the command reads: no output may land on one, even with ``overwrite``.

    Returns
    -------
    dict of str to Path
        The outputs that were asked for.

    Raises
    ------
    InputError
        Naming the flag and the path: it exists (without ``overwrite``), it is a folder
        (or, for a folder output, a file), its folder is missing or not writable, two
        outputs share it, or it is an input.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     sorted(check_outputs({"--out": f"{d}/a.csv", "--tum": None}))
    ['--out']
    >>> check_outputs({"--out": "same.csv", "--tum": "./same.csv"})
    Traceback (most recent call last):
    ...
    odomkit.errors.InputError: same.csv: --out and --tum name the same file; give each its own
    """
    asked = {flag: Path(p) for flag, p in outputs.items() if p is not None}
    owner: dict[str, str] = {}
    for flag, path in asked.items():
        other = owner.setdefault(_key(path), flag)
        if other != flag:
            raise InputError(f"{other} and {flag} name the same file; give each its own",
                             source=str(path))
    for source in inputs:
        clash = owner.get(_key(Path(source)))
        if clash is not None:
            raise InputError(f"{clash} would replace an input of this command; write elsewhere",
                             source=str(source))
    made = {_key(asked[f]) for f in folders if f in asked}
    for flag, path in asked.items():
        if flag in folders:
            _check_folder(flag, path)
        else:
            _check_file(flag, path, overwrite, made)
    return asked


def _check_file(flag: str, path: Path, overwrite: bool, made: set[str]) -> None:
    if path.is_dir():
        raise InputError(f"{flag} names a folder; give a file path", source=str(path))
    if path.exists():
        if not overwrite:
            raise InputError(EXISTS_ALREADY, source=str(path))
        if not os.access(path, os.W_OK):
            raise InputError(f"{flag}: the file is not writable", source=str(path))
        return
    parent = path.parent
    if _key(parent) in made:  # written into a folder that this command makes
        return
    if not parent.exists():
        raise InputError(f"{flag}: no such folder {str(parent)!r} (odomkit does not create "
                         "folders for a file)", source=str(path))
    if not parent.is_dir():
        raise InputError(f"{flag}: {str(parent)!r} is a file, not a folder", source=str(path))
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{flag}: the folder {str(parent)!r} is not writable", source=str(path))


def _check_folder(flag: str, path: Path) -> None:
    if path.exists() and not path.is_dir():
        raise InputError(f"{flag} names an existing file; give a folder", source=str(path))
    base = _nearest_existing(path)
    if not base.is_dir():
        raise InputError(f"{flag}: {str(base)!r} is a file, not a folder", source=str(path))
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"{flag}: the folder {str(base)!r} is not writable", source=str(path))


def refuse_overwrite(*paths: str | Path | None, overwrite: bool = False) -> None:
    """Raise if any of ``paths`` exists and ``overwrite`` is false.

    The writers' own last line of defence; commands check their outputs up front with
    :func:`check_outputs`.
    """
    for path in paths:
        if path is not None and Path(path).exists() and not overwrite:
            raise InputError(EXISTS_ALREADY, source=str(path))


def write_new_text(path: str | Path, text: str, overwrite: bool = False) -> Path:
    """Write ``text`` to a new file (or replace it when ``overwrite``)."""
    refuse_overwrite(path, overwrite=overwrite)
    target = Path(path)
    target.write_text(text, encoding="utf-8")
    return target
