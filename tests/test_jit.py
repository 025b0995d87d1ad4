"""The one lazy loader of the numba kernels and its numpy fallbacks."""

from __future__ import annotations

import sys
import types
import warnings

import numpy as np
import pytest

from odomkit import jit
from odomkit.errors import ModelError


@pytest.fixture
def fresh(monkeypatch):
    """An empty loader cache for this test (the real one is restored afterwards)."""
    monkeypatch.setattr(jit, "_cache", {})


def test_load_imports_once_and_caches(fresh, monkeypatch):
    calls = []
    fake = types.ModuleType("odomkit.fake_kernels")

    def import_module(name):
        calls.append(name)
        return fake

    monkeypatch.setattr(jit, "importlib", types.SimpleNamespace(import_module=import_module))
    assert jit.load("fake_kernels") is fake
    assert jit.load("fake_kernels") is fake
    assert calls == ["odomkit.fake_kernels"]


def test_load_returns_none_with_one_warning_when_the_import_fails(fresh, monkeypatch):
    monkeypatch.setitem(sys.modules, "odomkit.propagate._numba", None)  # import fails
    with pytest.warns(UserWarning, match=r"numba is not installed.*odomkit\[fast\]"):
        assert jit.load("propagate._numba") is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the second call neither warns nor retries
        assert jit.load("propagate._numba") is None


def test_all_three_users_go_through_the_loader(fresh):
    """With the loader's answer set to "no numba", every user falls back or refuses."""
    from odomkit.integrate import dead_reckon
    from odomkit.propagate import recursion
    from odomkit.simulate import _kernels

    jit._cache.update({"_integrate_numba": None, "propagate._numba": None, "simulate._numba": None})
    with pytest.raises(ModelError, match="needs numba"):
        dead_reckon(np.ones(3), np.zeros(3), engine="numba")
    np.testing.assert_allclose(dead_reckon(np.ones(3), np.zeros(3))[-1], [3.0, 0.0, 0.0])
    assert recursion._load_kernel() is None
    assert not _kernels.have_numba()
    with pytest.raises(ModelError, match="needs numba"):
        _kernels.advance_numba()


def test_njit_shares_one_configuration():
    pytest.importorskip("numba")
    from odomkit import angles

    f = angles.sin_cos_sinc_series
    compiled = jit.njit(f)
    assert compiled(0.5) == f(0.5)
    assert compiled.targetoptions["nogil"] is True
    assert type(compiled._cache).__name__ == "FunctionCache"  # cache=True: kept on disk
    assert jit.njit(f) is compiled  # compiled once per function and options
    inlined = jit.njit(f, inline="always")
    assert inlined is not compiled and inlined.targetoptions["inline"] == "always"
    assert inlined.targetoptions["nogil"] is True
