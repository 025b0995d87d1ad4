"""Step maps of the engines (:mod:`odomkit.propagate.inputs`): the classical
rotate-then-translate map's Jacobians by finite differences, and the lean per-step terms
against the full Jacobians. (What each noise model contributes per step is tested in
tests/noise/.)"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.errors import ModelError
from odomkit.propagate.inputs import (
    any_step_displacement,
    any_step_jacobians,
    classical_step_displacement,
    classical_step_jacobians,
    step_terms,
)

finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=40, deadline=None)
@given(theta=st.floats(-7, 7, **finite), d=st.floats(-0.5, 0.5, **finite),
       a=st.floats(-1.5, 1.5, **finite))
def test_classical_step_jacobians(numeric_jacobian, theta, d, a):
    """Chong–Kleeman eq. (1): rotate α, then translate D."""

    def step(pose, u):
        dx, dy = classical_step_displacement(pose[2], u[0], u[1])
        return np.array([pose[0] + dx, pose[1] + dy, pose[2] + u[1]])

    pose, u = np.array([0.2, -0.1, theta]), np.array([d, a])
    F, G = classical_step_jacobians(theta, d, a)
    assert np.allclose(F, numeric_jacobian(lambda p: step(p, u), pose), atol=1e-8)
    assert np.allclose(G, numeric_jacobian(lambda v: step(pose, v), u), atol=1e-8)


def test_classical_step_rotates_first():
    """A quarter turn and 1 m: the classical map ends at (0, 1) (the rotation acts before
    the translation), the exact arc on the quarter circle of radius 2/π."""
    dx, dy = any_step_displacement(0.0, 1.0, np.pi / 2, "classical")
    assert (dx, dy) == pytest.approx((0.0, 1.0), abs=1e-15)
    r = 1.0 / (np.pi / 2)
    assert any_step_displacement(0.0, 1.0, np.pi / 2, "exact") == pytest.approx((r, r), rel=1e-14)


@pytest.mark.parametrize("method", ["exact", "midpoint", "euler", "classical"])
def test_step_terms_are_the_step_jacobians(method):
    """The engines' lean per-step terms equal the (n, 3, 3) Jacobians entry by entry."""
    rng = np.random.default_rng(15)
    theta, dd = rng.normal(0, 3, 500), rng.uniform(-0.5, 0.5, 500)
    dtheta = np.concatenate([rng.normal(0, 1e-4, 250), rng.normal(0, 1.0, 250)])
    F, G = any_step_jacobians(theta, dd, dtheta, method)
    dx, dy, g00, g01, g10, g11 = step_terms(theta, dd, dtheta, method)
    assert np.allclose(np.stack([-dy, dx, g00, g01, g10, g11]),
                       np.stack([F[:, 0, 2], F[:, 1, 2], G[:, 0, 0], G[:, 0, 1], G[:, 1, 0],
                                 G[:, 1, 1]]), rtol=1e-13, atol=1e-16)


def test_step_terms_reject_an_unknown_method():
    with pytest.raises(ModelError, match="unknown method 'rk4'"):
        step_terms(np.zeros(2), np.ones(2), np.zeros(2), "rk4")
