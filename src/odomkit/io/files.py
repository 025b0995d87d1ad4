"""Writing files without ever replacing one the user did not ask us to replace."""

from __future__ import annotations

from pathlib import Path

from odomkit.errors import InputError

__all__ = ["refuse_overwrite", "write_new_text"]


def refuse_overwrite(*paths: str | Path | None, overwrite: bool = False) -> None:
    """Raise if any of ``paths`` exists and ``overwrite`` is false.

    Check every target before writing any, so that a refusal leaves nothing half-done.
    """
    for path in paths:
        if path is not None and Path(path).exists() and not overwrite:
            raise InputError("exists already; pass --force to replace it", source=str(path))


def write_new_text(path: str | Path, text: str, overwrite: bool = False) -> Path:
    """Write ``text`` to a new file (or replace it when ``overwrite``)."""
    refuse_overwrite(path, overwrite=overwrite)
    target = Path(path)
    target.write_text(text, encoding="utf-8")
    return target
