"""Per-wheel noise fit (k_L, k_R): basis covariances and the likelihood fit."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.calibrate.noise_fit import (
    ellipse_points,
    fit_wheel_noise,
    fit_wheel_noise_from_runs,
    wheel_noise_basis,
)
from odomkit.errors import InputError, OdomkitError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_jacobian, diff_body_steps
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive

B = 0.5
STEP = 0.05
# The first-order model holds when the second-order along-track term (≈ D·σθ²/2) is small
# against the first-order one (≈ k·√D): k·D^1.5/B² ≪ 1. With k = 0.001 m^½, D = 5 m and
# B = 0.5 m that ratio is 0.045 (Chong–Kleeman's own 10 m runs with k = 0.0006 m^½ and
# B ≈ 0.3 m would sit near 0.2).
K_LEFT, K_RIGHT = 0.001, 0.0005


def forward_and_back(length: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
    """Chong–Kleeman's experiment: forward ``length`` then backward to the start."""
    n = int(round(length / STEP))
    d = np.r_[np.full(n, STEP), np.full(n, -STEP)]
    return d.copy(), d.copy()


def noisy_end_errors(k_left: float, k_right: float, runs: int, rng: np.random.Generator):
    """End pose of the true (noisy) wheels minus the odometry end, Chong–Kleeman eq. (4)."""
    dl, dr = forward_and_back()
    odo_end = dead_reckon(*diff_body_steps(dl, dr, B))[-1]
    errs = []
    for _ in range(runs):
        tl = dl + k_left * np.sqrt(np.abs(dl)) * rng.standard_normal(dl.size)
        tr = dr + k_right * np.sqrt(np.abs(dr)) * rng.standard_normal(dr.size)
        errs.append(dead_reckon(*diff_body_steps(tl, tr, B))[-1] - odo_end)
    return np.array(errs)


def test_basis_matches_chong_kleeman_straight_line_closed_form():
    # Chong–Kleeman eq. (27) (θ = 0, D = 3 m) with the known misprint of eq. (26) avoided:
    # Cov = [[D/4 Σ, D²/(4B) Δ, D/(2B) Δ], [., D³/(3B²) Σ, D²/(2B²) Σ], [., ., D/B² Σ]]
    # with Σ = k_R² + k_L², Δ = k_R² − k_L². Continuous limit: 3000 steps.
    D, n = 3.0, 3000
    A, Bc = wheel_noise_basis(np.full(n, D / n), np.full(n, D / n), B)
    kl2, kr2 = 0.003**2, 0.002**2
    got = kl2 * A + kr2 * Bc
    S, Dl = kr2 + kl2, kr2 - kl2
    want = np.array([
        [D / 4 * S, D**2 / (4 * B) * Dl, D / (2 * B) * Dl],
        [D**2 / (4 * B) * Dl, D**3 / (3 * B**2) * S, D**2 / (2 * B**2) * S],
        [D / (2 * B) * Dl, D**2 / (2 * B**2) * S, D / B**2 * S],
    ])
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-12)


def test_basis_matches_the_step_recursion_engine():
    from odomkit.propagate.recursion import propagate_recursion

    rng = np.random.default_rng(7)
    dl, dr = rng.uniform(-0.02, 0.05, 500), rng.uniform(-0.02, 0.05, 500)
    pose0 = np.array([1.0, -2.0, 0.4])
    A, Bc = wheel_noise_basis(dl, dr, B, pose0)
    dd, dth = diff_body_steps(dl, dr, B)
    theta = dead_reckon(dd, dth, pose0)[:-1, 2]
    J = diff_body_jacobian(B)
    for basis, d, col in ((A, dl, 0), (Bc, dr, 1)):
        q = np.abs(d)[:, None, None] * np.outer(J[:, col], J[:, col])[None]
        ref = propagate_recursion(theta, dd, dth, q, np.zeros((3, 3)))[-1]
        np.testing.assert_allclose(basis, ref, rtol=1e-10, atol=1e-15)


def test_fit_recovers_known_k_within_its_interval():
    rng = np.random.default_rng(11)
    errs = noisy_end_errors(K_LEFT, K_RIGHT, 60, rng)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(errs, A, Bc)
    assert fit.ci_left[0] < K_LEFT < fit.ci_left[1]
    assert fit.ci_right[0] < K_RIGHT < fit.ci_right[1]
    assert fit.ci_left[0] < fit.k_left < fit.ci_left[1]
    # The fitted covariance is close to the sample covariance (n = 60: ~20 % noise).
    np.testing.assert_allclose(np.diag(fit.cov_fitted), np.diag(fit.cov_empirical), rtol=0.5)


@pytest.mark.slow
def test_profile_intervals_cover_at_the_nominal_rate():
    # 40 seeded experiments of 30 runs each; a 90 % interval misses Binomial(40, 0.1)
    # times: mean 4, and P(misses ≥ 11) = 0.002. The first-order model is exact here up to
    # the (tiny, σθ ≈ 0.05 rad) linearisation error.
    rng = np.random.default_rng(99)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    miss_l = miss_r = 0
    for _ in range(40):
        fit = fit_wheel_noise(noisy_end_errors(K_LEFT, K_RIGHT, 30, rng), A, Bc, level=0.9)
        miss_l += not fit.ci_left[0] < K_LEFT < fit.ci_left[1]
        miss_r += not fit.ci_right[0] < K_RIGHT < fit.ci_right[1]
    assert miss_l <= 10 and miss_r <= 10, (miss_l, miss_r)


def test_fit_from_logs_with_ground_truth():
    rng = np.random.default_rng(12)
    robot = DiffDrive(B, 1e-4, 1e-4)
    dl, dr = forward_and_back()
    logs = []
    for _ in range(40):
        tl = dl + K_LEFT * np.sqrt(np.abs(dl)) * rng.standard_normal(dl.size)
        tr = dr + K_RIGHT * np.sqrt(np.abs(dr)) * rng.standard_normal(dr.size)
        gt = dead_reckon(*diff_body_steps(tl, tr, B))
        ch = {"ticks_left": np.r_[0, dl / 1e-4], "ticks_right": np.r_[0, dr / 1e-4]}
        logs.append(OdometryLog(np.arange(gt.shape[0]) * 0.1, ch, gt))
    fit = fit_wheel_noise_from_runs(logs, robot)
    assert fit.ci_left[0] < K_LEFT < fit.ci_left[1]
    assert fit.ci_right[0] < K_RIGHT < fit.ci_right[1]
    assert fit.n_runs == 40


def test_a_quiet_wheel_is_identified():
    # Data made with k_R = 0: the fit must say the right wheel is much quieter than the
    # left, with an interval that stays below k_L.
    rng = np.random.default_rng(5)
    errs = noisy_end_errors(K_LEFT, 0.0, 60, rng)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(errs, A, Bc)
    assert fit.k_right < 0.2 * K_LEFT
    assert fit.ci_right[1] < 0.5 * K_LEFT
    assert fit.ci_left[0] < K_LEFT < fit.ci_left[1]


def test_shared_and_per_run_bases_give_the_same_fit():
    # Two code paths of the likelihood (scatter matrix vs per-run covariances).
    rng = np.random.default_rng(8)
    errs = noisy_end_errors(K_LEFT, K_RIGHT, 30, rng)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    shared = fit_wheel_noise(errs, A, Bc)
    per_run = fit_wheel_noise(errs, np.repeat(A[None], 30, 0), np.repeat(Bc[None], 30, 0))
    assert shared.loglik == pytest.approx(per_run.loglik, rel=1e-9)
    assert shared.k_left == pytest.approx(per_run.k_left, rel=1e-4)
    np.testing.assert_allclose(shared.ci_right, per_run.ci_right, rtol=1e-4)


def test_ellipse_holds_the_chi2_2dof_probability():
    # Monte Carlo: the fraction of 2-D Gaussian samples inside the 95 % ellipse is 0.95
    # (σ of the fraction with 20000 samples: 0.0015); the 1-D radius 1.96 would hold 0.85.
    rng = np.random.default_rng(2)
    cov = np.array([[4.0, 1.2], [1.2, 1.0]])
    pts = ellipse_points(cov, (0, 0), 0.95, n=4)
    r2 = np.einsum("ni,ij,nj->n", pts, np.linalg.inv(cov), pts)
    np.testing.assert_allclose(r2, 5.991, rtol=1e-3)
    x = rng.multivariate_normal([0, 0], cov, size=20000)
    inside = np.einsum("ni,ij,nj->n", x, np.linalg.inv(cov), x) <= r2[0]
    assert abs(inside.mean() - 0.95) < 0.006


def test_fit_ellipse_points_have_the_right_shape_and_center():
    rng = np.random.default_rng(3)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(noisy_end_errors(K_LEFT, K_RIGHT, 30, rng), A, Bc)
    for empirical in (False, True):
        e = fit.ellipse(("x", "theta"), empirical=empirical, n=64)
        assert e.shape == (64, 2)
        np.testing.assert_allclose(e.mean(axis=0), fit.mean[[0, 2]], atol=1e-12)


def test_bad_input():
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    with pytest.raises(InputError, match="at least two runs"):
        fit_wheel_noise(np.zeros((1, 3)), A, Bc, mean=np.zeros(3))
    with pytest.raises(InputError, match="at least three"):
        fit_wheel_noise(np.ones((2, 3)), A, Bc)
    with pytest.raises(InputError, match="shape"):
        fit_wheel_noise(np.zeros((5, 2)), A, Bc)
    with pytest.raises(OdomkitError, match="components"):
        fit_wheel_noise(np.ones((5, 3)), A, Bc, components=("x", "z"))
    with pytest.raises(OdomkitError, match="2x2"):
        ellipse_points(np.eye(3))


# --- issue 10, item 6: say when the data cannot identify the fit -----------------------


def forward_spin_back(length: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
    """Forward ``length``, spin 180° on the spot, forward ``length`` back to the start."""
    n, m = int(round(length / STEP)), 60
    spin = np.full(m, np.pi * B / 2 / m)   # each wheel travels π·B/2 for a half turn
    straight = np.full(n, STEP)
    return np.r_[straight, -spin, straight], np.r_[straight, spin, straight]


def end_errors_on(path: tuple[np.ndarray, np.ndarray], k_left: float, k_right: float, runs: int,
                  rng: np.random.Generator) -> np.ndarray:
    """Chong–Kleeman eq. (4) noise on the wheels of ``path``: end of truth minus odometry."""
    dl, dr = path
    odo_end = dead_reckon(*diff_body_steps(dl, dr, B))[-1]
    errs = []
    for _ in range(runs):
        tl = dl + k_left * np.sqrt(np.abs(dl)) * rng.standard_normal(dl.size)
        tr = dr + k_right * np.sqrt(np.abs(dr)) * rng.standard_normal(dr.size)
        errs.append(dead_reckon(*diff_body_steps(tl, tr, B))[-1] - odo_end)
    return np.array(errs)


def test_a_well_posed_fit_has_no_warnings():
    rng = np.random.default_rng(11)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(noisy_end_errors(K_LEFT, K_RIGHT, 60, rng), A, Bc)
    assert fit.warnings == ()
    assert fit.to_dict()["warnings"] == []


def test_forward_spin_back_cannot_tell_the_wheels_apart():
    # After the half turn each wheel drives the other's side of the return leg: the end
    # error depends (almost) on k_L² + k_R² only.
    rng = np.random.default_rng(4)
    path = forward_spin_back()
    A, Bc = wheel_noise_basis(*path, B)
    fit = fit_wheel_noise(end_errors_on(path, K_LEFT, K_RIGHT, 60, rng), A, Bc)
    assert fit.k_correlation < -0.99
    assert any("cannot tell k_left from k_right" in w for w in fit.warnings), fit.warnings
    assert fit.to_dict()["warnings"] == list(fit.warnings)


def test_one_component_cannot_separate_two_variances():
    # One number per run carries one variance: the two k's are exactly confounded.
    rng = np.random.default_rng(6)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(noisy_end_errors(K_LEFT, K_RIGHT, 40, rng), A, Bc,
                          components=("theta",))
    assert fit.k_correlation == pytest.approx(-1.0, abs=1e-9)
    assert any("cannot tell k_left from k_right" in w for w in fit.warnings)


@pytest.mark.slow
def test_k_correlation_matches_the_scatter_of_repeated_fits():
    # The reported correlation (expected Fisher information of k_L², k_R²) against the
    # correlation of the estimates over 150 independent experiments on an arc, where the
    # two wheels are partly confounded (ρ ≈ −0.88). Standard error of a sample correlation
    # of 150 pairs near −0.9: (1 − ρ²)/√150 ≈ 0.016.
    rng = np.random.default_rng(21)
    n = 100
    path = (np.full(n, 0.8 * STEP), np.full(n, 1.2 * STEP))
    A, Bc = wheel_noise_basis(*path, B)
    kl, kr = 0.002, 0.002
    q, rho = [], []
    for _ in range(150):
        fit = fit_wheel_noise(end_errors_on(path, kl, kr, 100, rng), A, Bc, mean=np.zeros(3))
        q.append((fit.k_left**2, fit.k_right**2))
        rho.append(fit.k_correlation)
    q_arr = np.array(q)
    empirical = np.corrcoef(q_arr.T)[0, 1]
    assert np.median(rho) == pytest.approx(empirical, abs=0.05)


def test_runs_beyond_the_first_order_regime_warn():
    # k = 0.03 m^½ over 10 m with B = 0.5 m: σθ ≈ √(2·10)·0.03/0.5 ≈ 0.27 rad at the turn
    # back and ≈ 0.38 rad at the end (Chong–Kleeman eq. 27): the first-order likelihood
    # no longer holds.
    rng = np.random.default_rng(8)
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    fit = fit_wheel_noise(noisy_end_errors(0.03, 0.03, 40, rng), A, Bc)
    sigma_theta = np.sqrt(fit.k_left**2 * A[2, 2] + fit.k_right**2 * Bc[2, 2])
    assert sigma_theta > 0.3
    assert any("first-order" in w for w in fit.warnings), fit.warnings


def test_an_unbounded_profile_gives_an_open_interval_not_a_crash():
    # The left wheel never moves: the runs say nothing about k_left, whose profile
    # likelihood is flat and never crosses the χ² level. Its interval is open above.
    rng = np.random.default_rng(0)
    path = (np.zeros(200), np.full(200, 0.01))
    A, Bc = wheel_noise_basis(*path, B)
    fit = fit_wheel_noise(end_errors_on(path, 0.0, 1e-3, 20, rng), A, Bc)
    assert fit.ci_left[1] == np.inf
    assert fit.to_dict()["ci_left"][1] == np.inf   # JSON writes it as null
    assert any("k_left" in w and "bound" in w for w in fit.warnings), fit.warnings
    assert fit.ci_right[0] < 1e-3 < fit.ci_right[1]


def test_identical_errors_are_refused_with_a_message():
    A, Bc = wheel_noise_basis(*forward_and_back(), B)
    with pytest.raises(InputError, match="spread"):
        fit_wheel_noise(np.tile([0.01, 0.02, 0.003], (5, 1)), A, Bc)


def test_degenerate_information_is_named_not_printed_as_nan():
    """A NaN correlation (degenerate information) used to print 'correlate at nan'."""
    from odomkit.calibrate import noise_fit

    notes = noise_fit._warnings(float("nan"), np.array([True, True]), [(0.0, 1.0), (0.0, 1.0)],
                                0.01, 0.95)
    text = " ".join(notes)
    assert "nan" not in text and "degenerate" in text


def _two_kinds_of_runs(r: float, spread: float, n: int = 40):
    """Runs of two kinds, half with heading bases (A, B) = (1, r), half (r, 1), and end
    headings ±``spread`` exactly: the likelihood's maximum is k_L² = k_R² = spread²/(1 + r),
    where every run's variance is spread², and the expected Fisher information of
    (k_L², k_R²), ½ Σ ∂C ∂C / C², has the correlation −2r/(1 + r²) (worked by hand)."""
    A, Bm = np.zeros((n, 3, 3)), np.zeros((n, 3, 3))
    A[:, 2, 2] = np.where(np.arange(n) < n // 2, 1.0, r)
    Bm[:, 2, 2] = np.where(np.arange(n) < n // 2, r, 1.0)
    e = np.zeros((n, 3))
    e[:, 2] = spread * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return fit_wheel_noise(e, A, Bm, mean=np.zeros(1), components=("theta",))


def test_calibrate_noise_judges_confounded_wheels_as_fit_noise_does():
    """API user study, L5: calibrate-noise said two k's were confounded beyond |ρ| 0.99,
    fit-noise beyond 0.95, for the same quantity (the Fisher correlation of two variance
    estimates); a CW+CCW square at ρ = −0.964 went without a word. One threshold now."""
    r = 0.78  # −2r/(1 + r²) = −0.9697
    fit = _two_kinds_of_runs(r, 0.01)
    assert fit.k_left**2 == pytest.approx(1e-4 / (1 + r), rel=1e-4)
    assert fit.k_correlation == pytest.approx(-2 * r / (1 + r**2), abs=1e-4)
    assert any("cannot tell k_left from k_right" in w for w in fit.warnings), fit.warnings
    from odomkit.calibrate.fit_noise import CONFOUNDED_CORRELATION

    assert CONFOUNDED_CORRELATION < abs(fit.k_correlation) < 0.99
    calm = _two_kinds_of_runs(0.5, 0.01)  # ρ = −0.8
    assert not any("cannot tell" in w for w in calm.warnings), calm.warnings


def test_calibrate_noise_leaves_the_first_order_regime_where_fit_noise_does():
    """σθ 0.25 rad at the end: the second-order along-track error D·σθ²/2 is 12 % of the
    first-order D·σθ, beyond fit-noise's tenth (σθ 0.2 rad); calibrate-noise said so only
    above 0.3 rad."""
    from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA

    fit = _two_kinds_of_runs(0.1, 0.25)
    assert fit.sigma_theta == pytest.approx(0.25, rel=1e-4)
    assert any("first-order" in w for w in fit.warnings), fit.warnings
    assert FIRST_ORDER_SIGMA_THETA < fit.sigma_theta < 0.3
    assert not any("first-order" in w for w in _two_kinds_of_runs(0.1, 0.15).warnings)
