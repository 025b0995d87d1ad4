"""Jacobians by perturbation (manif style); the sinc factor itself: tests/test_angles.py."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.kinematics import (
    step_displacement,
    step_jacobians,
    tricycle_body_jacobian,
    tricycle_body_steps,
)


def step(pose, u, method):
    dx, dy = step_displacement(pose[2], u[0], u[1], method)
    return np.array([pose[0] + dx, pose[1] + dy, pose[2] + u[1]])


@pytest.mark.parametrize("method", ["exact", "midpoint", "euler"])
@settings(max_examples=50, deadline=None)
@given(theta=st.floats(-7, 7), dd=st.floats(-0.5, 0.5), dth=st.floats(-1.5, 1.5))
def test_step_jacobians_match_central_differences(numeric_jacobian, method, theta, dd, dth):
    pose = np.array([0.3, -0.2, theta])
    u = np.array([dd, dth])
    F, G = step_jacobians(theta, dd, dth, method)
    assert np.allclose(F, numeric_jacobian(lambda p: step(p, u, method), pose), atol=1e-8)
    assert np.allclose(G, numeric_jacobian(lambda v: step(pose, v, method), u), atol=1e-8)


def test_tricycle_jacobian_matches_central_differences(numeric_jacobian):
    s, a, L = 0.07, 0.4, 0.68

    def f(v):
        dd, dth = tricycle_body_steps(v[0], v[1], v[2])
        return np.array([dd, dth])

    assert np.allclose(tricycle_body_jacobian(s, a, L), numeric_jacobian(f, [s, a, L]), atol=1e-9)
