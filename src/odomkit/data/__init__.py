"""Built-in sample data (OptiOdom, MIT licence: see LICENSE-OptiOdom.txt)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["builtin_data_path"]


def builtin_data_path(name: str) -> Path:
    """Path of a file shipped in ``odomkit/data``.

    >>> builtin_data_path("optiodom_diff.toml").name
    'optiodom_diff.toml'
    """
    return Path(str(resources.files("odomkit.data").joinpath(name)))
