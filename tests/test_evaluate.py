"""Evaluation metrics against hand-computable cases and a chi-square property."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from odomkit.evaluate import evaluate_track, nees, relative_pose_errors


def test_constant_offset_gives_known_metrics():
    truth = np.column_stack((np.linspace(0, 10, 101), np.zeros(101), np.zeros(101)))
    est = truth + [0.0, 0.3, 0.0]
    ev = evaluate_track(est, truth)
    assert ev.final_position_error == pytest.approx(0.3)
    assert ev.ate_rmse == pytest.approx(0.3)
    assert ev.true_path_length == pytest.approx(10.0)
    assert ev.drift_per_distance == pytest.approx(0.03)
    # a rigid offset has no relative error
    assert np.allclose(relative_pose_errors(est, truth, 1.0), 0.0, atol=1e-12)


def test_rpe_sees_a_heading_bias_as_across_track_error():
    n = 1001
    s = np.linspace(0, 10, n)
    truth = np.column_stack((s, np.zeros(n), np.zeros(n)))
    est = np.column_stack((s * np.cos(0.01), s * np.sin(0.01), np.full(n, 0.01)))
    rpe = relative_pose_errors(est, truth, 2.0)
    # over 2 m the estimate moves 2 m at its own heading: same local motion, so the
    # only relative error is none in position and none in heading
    assert np.allclose(rpe, 0.0, atol=1e-12)


def test_nees_of_gaussian_samples_follows_chi_square():
    rng = np.random.default_rng(5)
    n = 20000
    A = np.array([[2.0, 0.3], [0.0, 0.5]])
    cov = np.broadcast_to(A @ A.T, (n, 2, 2))
    e = rng.standard_normal((n, 2)) @ A.T
    values = nees(e, cov)
    # mean of χ²₂ is 2 with standard error sqrt(4/n) = 0.014; 4 standard errors
    assert values.mean() == pytest.approx(2.0, abs=4 * np.sqrt(4 / n))
    inside = np.mean(values <= chi2.ppf(0.95, 2))
    # binomial standard error sqrt(0.95·0.05/n) = 0.0015
    assert inside == pytest.approx(0.95, abs=4 * np.sqrt(0.95 * 0.05 / n))


def test_singular_covariance_gives_nan_not_inf():
    assert np.isnan(nees(np.ones((1, 2)), np.zeros((1, 2, 2))))[0]
