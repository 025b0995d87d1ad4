"""Printing helpers shared by the commands (one JSON object on stdout)."""

from __future__ import annotations

import json

from odomkit.io.jsonfile import to_jsonable

__all__ = ["print_json"]


def print_json(obj: object) -> None:
    """Print one JSON object on stdout."""
    print(json.dumps(to_jsonable(obj), indent=2))
