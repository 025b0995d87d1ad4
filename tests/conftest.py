"""Shared fixtures: where the real data lives (ODOMKIT_DATA or ../shared/data)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def _data_dir() -> Path | None:
    env = os.environ.get("ODOMKIT_DATA")
    for candidate in ([Path(env)] if env else []) + [REPO.parent / "shared" / "data"]:
        if candidate.is_dir():
            return candidate
    return None


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The real-data folder; tests that need it skip with a reason when it is absent."""
    found = _data_dir()
    if found is None:
        pytest.skip("real data not found: set ODOMKIT_DATA or place shared/data beside the repo")
    return found


@pytest.fixture()
def run_cli(capsys):
    """Run ``odomkit`` in-process; return (exit code, stdout, stderr)."""
    from odomkit.cli import main

    def run(*args: str) -> tuple[int, str, str]:
        code = main([str(a) for a in args])
        captured = capsys.readouterr()
        return code, captured.out, captured.err

    return run


def _central_difference_jacobian(f, x, eps=1e-6):
    """∂f/∂x by central differences (manif-style perturbation check of a Jacobian):
    column i is (f(x + eps·e_i) − f(x − eps·e_i)) / (2·eps), error O(eps²)."""
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        h = np.zeros_like(x)
        h[i] = eps
        cols.append((np.asarray(f(x + h)) - np.asarray(f(x - h))) / (2 * eps))
    return np.column_stack(cols)


@pytest.fixture(scope="session")
def numeric_jacobian():
    """The central-difference Jacobian every Jacobian test compares against (session
    scope, so hypothesis tests may use it)."""
    return _central_difference_jacobian
