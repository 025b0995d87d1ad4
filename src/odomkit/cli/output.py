"""Printing helpers shared by the commands (one JSON object on stdout)."""

from __future__ import annotations

import json

__all__ = ["print_json"]


def print_json(obj: object) -> None:
    """Print one JSON object on stdout."""
    # Here, not at the top: the converter imports numpy, which no --help needs (35 ms of the
    # start-up that benchmarks/startup.py measures).
    from odomkit.io.jsonfile import to_jsonable

    print(json.dumps(to_jsonable(obj), indent=2))
