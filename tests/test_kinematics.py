"""Jacobians by perturbation (manif style) and the safe sinc limits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.kinematics import (
    sinc_half,
    sinc_half_derivative,
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


def test_sinc_half_is_continuous_across_the_series_threshold():
    x = np.array([1.999e-3, 2.0e-3, 2.001e-3, 0.0, 1e-9])
    ref_f = np.array([np.sin(v / 2) / (v / 2) if v else 1.0 for v in x])
    assert np.allclose(sinc_half(x), ref_f, rtol=1e-15, atol=0)
    # derivative against a high-precision series of d/dx sin(x/2)/(x/2) = −x/12 + x³/480
    assert np.allclose(sinc_half_derivative(x), -x / 12 + x**3 / 480, rtol=1e-9, atol=1e-20)
    big = np.array([0.5, 2.0, -3.0])
    fd = (sinc_half(big + 1e-6) - sinc_half(big - 1e-6)) / 2e-6
    assert np.allclose(sinc_half_derivative(big), fd, atol=1e-9)


def test_tricycle_jacobian_matches_central_differences(numeric_jacobian):
    s, a, L = 0.07, 0.4, 0.68

    def f(v):
        dd, dth = tricycle_body_steps(v[0], v[1], v[2])
        return np.array([dd, dth])

    assert np.allclose(tricycle_body_jacobian(s, a, L), numeric_jacobian(f, [s, a, L]), atol=1e-9)
