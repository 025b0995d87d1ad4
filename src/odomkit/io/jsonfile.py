"""JSON: odomkit's results (nested dicts of numpy values) as plain JSON types and files.

NaN and ±inf have no JSON spelling; they become ``null`` (undefined figures such as the
correlation of a zero variance).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from odomkit.io.files import write_new_text

__all__ = ["to_jsonable", "write_json"]


def to_jsonable(value: object) -> Any:
    """Convert numpy scalars/arrays (recursively) to plain JSON types; NaN/inf -> None.

    Examples
    --------
    >>> to_jsonable({"a": np.array([1.0, np.nan]), 2: (np.int64(3),)})
    {'a': [1.0, None], '2': [3]}
    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_json(path: str | Path, obj: object, overwrite: bool = False) -> Path:
    """Write ``obj`` as indented JSON (:func:`to_jsonable` first) to a new file, or over an
    existing one only when ``overwrite``."""
    return write_new_text(path, json.dumps(to_jsonable(obj), indent=2), overwrite)
