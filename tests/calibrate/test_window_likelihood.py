"""The likelihood of window-end errors (odomkit.calibrate.window_likelihood).

Independent truths: a dense multivariate normal over all windows of each log (the
Woodbury form must equal it), finite differences (gradient, observed information) and the
trace formula of the Fisher information on dense matrices.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag

from odomkit.calibrate.window_likelihood import FLOOR, WindowLikelihood
from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_steps
from odomkit.log import OdometryLog
from odomkit.noise import ParameterUncertainty, WheelNoise
from odomkit.robot import DiffDrive
from odomkit.truth import Truth
from odomkit.window_errors import window_covariance_basis
from odomkit.windows import WindowSpec, split_windows

ROBOT = DiffDrive(0.3)
SIGMA = {"k_left": 0.002, "k_right": 0.003, "sigma_wheel_base": 0.003, "sigma_scale_left": 0.004,
         "sigma_scale_right": 0.002}


def _bases(seed=7, n_logs=3, n=800, position_only=(1,)):
    """Logs whose truth is their true wheel travels (white noise plus one bias draw per
    log) dead-reckoned; log 1 has position-only truth."""
    rng = np.random.default_rng(seed)
    models = (WheelNoise(0, 0), ParameterUncertainty())
    bases = []
    for i in range(n_logs):
        t = np.arange(n) * 0.05
        dl = 0.01 + 0.008 * np.sin(t / 2 + rng.uniform(0, 6))
        dr = 0.01 + 0.008 * np.sin(t / 3 + rng.uniform(0, 6))
        eps = rng.normal(0, [SIGMA[k] for k in ("sigma_wheel_base", "sigma_scale_left", "sigma_scale_right")])
        true_l = dl * (1 + eps[1]) + rng.standard_normal(n) * SIGMA["k_left"] * np.sqrt(dl)
        true_r = dr * (1 + eps[2]) + rng.standard_normal(n) * SIGMA["k_right"] * np.sqrt(dr)
        gt = dead_reckon(*diff_body_steps(true_l[1:], true_r[1:], ROBOT.wheel_base + eps[0]))
        log = OdometryLog(t, {"dist_left": dl, "dist_right": dr})
        windows, _ = split_windows(t, t, WindowSpec(10.0, "s"))
        tr = None
        if i in position_only:
            tr = Truth(t, gt[:, :2], None, sigma=1e-4)
            gt = gt.copy()
            gt[:, 2] = np.nan
        bases.append(window_covariance_basis(log, ROBOT, models, gt, np.ones(n, bool), windows, truth=tr))
    return bases


@pytest.fixture(scope="module")
def mixed():
    """Three logs with bias; the second has position-only truth."""
    bases = _bases()
    v = np.array([SIGMA[k] ** 2 for k in SIGMA])
    return WindowLikelihood(bases), bases, v


def _dense(bases, v):
    """Σ of each log over all its windows' observed components, and its parts."""
    out = []
    for b in bases:
        mask = np.isfinite(b.error).reshape(-1)
        D = b.fixed + np.einsum("j,wjab->wab", v[:2], b.white) + FLOOR * np.eye(3)
        S = b.sens.reshape(-1, b.sens.shape[-1])
        col = b.bias_weights.T @ v[2:]
        sigma = (block_diag(*D) + S @ np.diag(col) @ S.T)[np.ix_(mask, mask)]
        parts = [block_diag(*b.white[:, j])[np.ix_(mask, mask)] for j in range(2)]
        parts += [np.outer(S[:, c], S[:, c])[np.ix_(mask, mask)] for c in range(S.shape[1])]
        out.append((sigma, b.error.reshape(-1)[mask], parts))
    return out


def test_likelihood_equals_a_dense_gaussian_over_each_log(mixed):
    lik, bases, v = mixed
    expected = 0.0
    quads = []
    for sigma, e, _ in _dense(bases, v):
        _, logdet = np.linalg.slogdet(sigma)
        quad = e @ np.linalg.solve(sigma, e)
        quads.append(quad)
        expected += -0.5 * (logdet + quad + e.size * np.log(2 * np.pi))
    val = lik(v)
    assert val.loglik == pytest.approx(expected, rel=1e-11)
    np.testing.assert_allclose(val.quad, quads, rtol=1e-9)


def test_gradient_and_observed_information_match_finite_differences(mixed):
    lik, _, v = mixed
    val = lik(v, information=True)
    hess = np.zeros((v.size, v.size))
    for j in range(v.size):
        h = v[j] * 1e-5
        up, down = v.copy(), v.copy()
        up[j] += h
        down[j] -= h
        fd = (lik(up, gradient=False).loglik - lik(down, gradient=False).loglik) / (2 * h)
        assert val.gradient[j] == pytest.approx(fd, rel=1e-5)
        hess[:, j] = (lik(up).gradient - lik(down).gradient) / (2 * h)
    observed = -0.5 * (hess + hess.T)
    # The average information is the mean of the observed and the expected information.
    np.testing.assert_allclose(val.average, 0.5 * (observed + val.information),
                               rtol=0, atol=1e-6 * np.abs(val.average).max())


def test_expected_information_is_the_trace_formula_on_dense_matrices(mixed):
    lik, bases, v = mixed
    info = np.zeros((v.size, v.size))
    for sigma, _, parts in _dense(bases, v):
        inv = np.linalg.inv(sigma)
        for i in range(v.size):
            for j in range(v.size):
                info[i, j] += 0.5 * np.trace(inv @ parts[i] @ inv @ parts[j])
    np.testing.assert_allclose(lik(v, information=True).information, info, rtol=1e-9)


def test_windows_without_heading_are_scored_on_position_only(mixed):
    lik, bases, v = mixed
    hidden = ~lik.observed[:, 2]
    assert hidden.sum() == len(bases[1].windows) and lik.observed[:, :2].all()
    assert lik.nobs.tolist() == [3 * len(bases[0].windows), 2 * len(bases[1].windows),
                                 3 * len(bases[2].windows)]


def test_bases_of_different_models_are_refused():
    a = _bases(n_logs=1, position_only=())
    t = np.arange(400) * 0.05
    log = OdometryLog(t, {"dist_left": np.full(400, 0.01), "dist_right": np.full(400, 0.012)})
    windows, _ = split_windows(t, t, WindowSpec(10.0, "s"))
    other = window_covariance_basis(log, ROBOT, WheelNoise(0, 0), np.zeros((400, 3)), np.ones(400, bool),
                                    windows)
    with pytest.raises(ModelError, match="same noise models"):
        WindowLikelihood(a + [other])
    with pytest.raises(ModelError, match="no windows"):
        WindowLikelihood([])
