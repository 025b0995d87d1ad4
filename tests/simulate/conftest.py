"""Independent theory for the Monte Carlo tests: the first-order step recursion.

Written here on purpose (not imported from odomkit.propagate) so the simulator is checked
against a second, independent implementation: P ← F·P·Fᵀ + G·Q·Gᵀ over K small steps of
each segment (Chong–Kleeman eq. 2 with the exact-arc Jacobians of
odomkit.kinematics.step_jacobians, themselves tested by finite differences), with
Q = J·diag(k_L²|d_L|, k_R²|d_R|)·Jᵀ (Chong–Kleeman eq. 4), J = [[½, ½], [−1/b, 1/b]].
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.kinematics import step_jacobians


def recursion_theory(segments, wheel_base, k_left, k_right, steps=2000, pose0=(0.0, 0.0, 0.0),
                     cov0=None):
    """Nominal final pose (3,) and first-order covariance (3, 3) of wheel-travel segments
    ``[(L, R), ...]``."""
    pose = np.array(pose0, dtype=float)
    cov = np.zeros((3, 3)) if cov0 is None else np.array(cov0, dtype=float)
    jac = np.array([[0.5, 0.5], [-1.0 / wheel_base, 1.0 / wheel_base]])
    for left, right in segments:
        dl, dr = left / steps, right / steps
        q = jac @ np.diag([k_left**2 * abs(dl), k_right**2 * abs(dr)]) @ jac.T
        dd, dth = 0.5 * (dl + dr), (dr - dl) / wheel_base
        for _ in range(steps):
            F, G = step_jacobians(pose[2], dd, dth)
            F, G = F.reshape(3, 3), G.reshape(3, 2)
            cov = F @ cov @ F.T + G @ q @ G.T
            pose = pose + np.array([F[1, 2], -F[0, 2], dth])  # (Δx, Δy, Δθ)
    return pose, cov


@pytest.fixture
def theory():
    return recursion_theory
