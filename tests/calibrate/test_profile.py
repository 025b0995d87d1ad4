"""Profile likelihoods (odomkit.calibrate.profile): a Gaussian log-likelihood whose profile
is known in closed form (with the bound v ≥ 0 active and not), and the profiles of real
fits crossing χ²₁(0.95) exactly where the fits' own interval search put their ends."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from odomkit.calibrate.amcl import amcl_data, fit_amcl
from odomkit.calibrate.fit_noise import fit_noise
from odomkit.calibrate.profile import amcl_profiles, noise_profiles, profile_grid, profile_log_likelihood

CHI2_1_95 = 3.841458820694124

_spec = importlib.util.spec_from_file_location("odomkit_test_fit_noise",
                                               Path(__file__).with_name("test_fit_noise.py"))
_fit_noise_tests = sys.modules.setdefault("odomkit_test_fit_noise", importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(_fit_noise_tests)
synthetic_bases, ROBOT = _fit_noise_tests.synthetic_bases, _fit_noise_tests.ROBOT

A = np.array([[2.0, 0.8], [0.8, 1.0]])
MU = np.array([1.0, 0.3])


def _gaussian(curvature):
    def f(v):
        d = v - MU
        return -0.5 * d @ A @ d, -A @ d, (A if curvature else None)
    return f


def _closed_form(x):
    """max over v₂ ≥ 0 of the Gaussian with v₁ = x: v₂ = μ₂ − A₂₁/A₂₂ (x − μ₁), clipped at 0."""
    v2 = max(MU[1] - A[1, 0] / A[1, 1] * (x - MU[0]), 0.0)
    d = np.array([x, v2]) - MU
    return -0.5 * d @ A @ d


@pytest.mark.parametrize("curvature", [True, False], ids=["newton", "lbfgsb"])
def test_profile_of_a_gaussian_with_the_bound_active_and_not(curvature):
    grid = np.linspace(-1.0, 2.5, 15)  # v₂ hits its bound for x > 1.375
    got = profile_log_likelihood(_gaussian(curvature), MU, 0, grid)
    assert np.allclose(got, [_closed_form(x) for x in grid], atol=1e-9)


def _crossings(profiles, fit_max):
    for p in profiles:
        dev = 2.0 * (fit_max - p.log_likelihood)
        assert np.all(dev > -1e-6)  # no point beats the maximum
        at = dict(zip(p.values.tolist(), dev.tolist(), strict=True))
        assert at[p.estimate] == pytest.approx(0.0, abs=1e-6)
        for end in p.interval:
            if end > 0 and np.isfinite(end):
                assert at[end] == pytest.approx(CHI2_1_95, abs=2e-3), p.name


@pytest.mark.parametrize("bias", [False, True], ids=["white", "white+bias"])
def test_fit_noise_profiles_cross_the_threshold_at_the_interval_ends(bias):
    bases, models = synthetic_bases(11, n_logs=6 if bias else 4, bias=bias)
    kinds = ("white", "bias") if bias else ("white",)
    fit = fit_noise(bases, models, ROBOT, kinds=kinds)
    profiles = noise_profiles(bases, models, ROBOT, fit, kinds=kinds, points=9)
    assert [p.name for p in profiles] == list(fit.parameters)
    _crossings(profiles, fit.log_likelihood)


def test_a_trimmed_fit_is_profiled_on_the_windows_it_kept():
    bases, models = synthetic_bases(4, n_logs=4, bias=False, scale=2.0)  # one log 3× noisier
    fit = fit_noise(bases, models, ROBOT, trim=0.9)
    assert fit.trimmed > 0
    _crossings(noise_profiles(bases, models, ROBOT, fit, points=9), fit.log_likelihood)


def test_amcl_profiles_cross_the_threshold_at_the_interval_ends():
    rng = np.random.default_rng(8)
    n = 150
    o0 = np.zeros((n, 3))
    o1 = np.column_stack([rng.uniform(0.2, 0.4, n), rng.uniform(-0.05, 0.05, n), rng.uniform(-0.6, 0.6, n)])
    g1 = o1 + rng.normal(0.0, [0.01, 0.01, 0.02], (n, 3))
    fit = fit_amcl(amcl_data(o0, o1, o0, g1, "diff"))
    _crossings(amcl_profiles(amcl_data(o0, o1, o0, g1, "diff"), fit, points=5), fit.log_likelihood)


def test_the_grid_holds_the_estimate_and_the_interval():
    grid = profile_grid(2e-3, (1e-3, np.inf), 7)
    assert 2e-3 in grid and 1e-3 in grid and grid.min() >= 0 and grid.max() == pytest.approx(6e-3)
