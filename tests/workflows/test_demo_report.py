"""The demo report's checks (odomkit.workflows.demo_report) against independent ones: the
Monte Carlo check's statistics recomputed from its end points with numpy, and the virtual
UMBmark's estimated E_d, E_b against the true ones it was made with."""

from __future__ import annotations

import numpy as np

from odomkit.noise import WheelNoise
from odomkit.workflows.demo_report import monte_carlo_check, virtual_umbmark_check


def test_monte_carlo_check_reports_the_spread_of_its_own_end_points():
    check = monte_carlo_check(WheelNoise(1e-3, 1e-3), 0.2, 0.75, runs=1000, seed=3)
    assert check.endpoints.shape == (1000, 3)
    spread = np.std(check.endpoints, axis=0, ddof=1)
    np.testing.assert_allclose(check.summary["simulated_std"], spread, rtol=1e-9)
    # and the prediction it is checked against agrees within the sampling error of a std
    # (relative standard error of a std ≈ 1/√(2n) ≈ 2.2 %; five of them)
    np.testing.assert_allclose(spread, np.sqrt(np.diag(check.cov)), rtol=0.11)
    assert check.summary["consistent"] is True


def test_virtual_umbmark_recovers_the_errors_it_was_given_and_shrinks_e_max():
    v = virtual_umbmark_check(E_d=1.002, E_b=1.006, runs=5, seed=2)
    est = v.summary["estimated"]
    assert abs(est["E_d"] - 1.002) < 5e-4 and abs(est["E_b"] - 1.006) < 2e-3
    assert v.summary["e_max_syst_after"] < v.summary["e_max_syst_before"] / 5
    assert v.cw.shape == v.ccw.shape == v.cw_after.shape == (5, 2)
