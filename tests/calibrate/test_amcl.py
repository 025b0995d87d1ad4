"""nav2 AMCL's motion models and ``fit_amcl`` (issue 12 item 6).

The independent truth is AMCL's own sampler, written here from the published formulas
(nav2 ``differential_motion_model.cpp`` / ``omni_motion_model.cpp``, Thrun et al. table 5.6
in nav2's variance form), scalar by scalar with nav2's own ``angle_diff``: a robot whose
true motion is drawn by it with known α's must be fitted back inside the reported
intervals about as often as their level says.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.calibrate.amcl import (
    ALPHA_NAMES,
    amcl_data,
    amcl_update_rows,
    diff_motion,
    fit_amcl,
)
from odomkit.errors import InputError


def angle_diff(a: float, b: float) -> float:
    """nav2 angleutils::angle_diff: the shortest signed a − b."""
    a, b = math.atan2(math.sin(a), math.cos(a)), math.atan2(math.sin(b), math.cos(b))
    d1 = a - b
    d2 = 2 * math.pi - abs(d1)
    if d1 > 0:
        d2 *= -1.0
    return d1 if abs(d1) < abs(d2) else d2


def sample_diff(rng, odom, alpha, start):
    """nav2's DifferentialMotionModel::odometryUpdate for one particle along ``odom``."""
    a1, a2, a3, a4 = alpha
    poses = [np.array(start, dtype=float)]
    for p0, p1 in zip(odom[:-1], odom[1:], strict=True):
        dx, dy, dth = p1[0] - p0[0], p1[1] - p0[1], angle_diff(p1[2], p0[2])
        trans = math.hypot(dx, dy)
        rot1 = 0.0 if trans < 0.01 else angle_diff(math.atan2(dy, dx), p0[2])
        rot2 = angle_diff(dth, rot1)
        n1 = min(abs(angle_diff(rot1, 0.0)), abs(angle_diff(rot1, math.pi)))
        n2 = min(abs(angle_diff(rot2, 0.0)), abs(angle_diff(rot2, math.pi)))
        rot1_hat = angle_diff(rot1, rng.normal(0.0, math.sqrt(a1 * n1 * n1 + a2 * trans * trans)))
        trans_hat = trans - rng.normal(0.0, math.sqrt(a3 * trans * trans + a4 * n1 * n1 + a4 * n2 * n2))
        rot2_hat = angle_diff(rot2, rng.normal(0.0, math.sqrt(a1 * n2 * n2 + a2 * trans * trans)))
        q = poses[-1].copy()
        q[0] += trans_hat * math.cos(q[2] + rot1_hat)
        q[1] += trans_hat * math.sin(q[2] + rot1_hat)
        q[2] += rot1_hat + rot2_hat
        poses.append(q)
    return np.array(poses)


def sample_omni(rng, odom, alpha, start):
    """nav2's OmniMotionModel::odometryUpdate for one particle along ``odom``."""
    a1, a2, a3, a4, a5 = alpha
    poses = [np.array(start, dtype=float)]
    for p0, p1 in zip(odom[:-1], odom[1:], strict=True):
        dx, dy, rot = p1[0] - p0[0], p1[1] - p0[1], angle_diff(p1[2], p0[2])
        trans = math.hypot(dx, dy)
        q = poses[-1].copy()
        bearing = angle_diff(math.atan2(dy, dx), p0[2]) + q[2]
        t_hat = trans + rng.normal(0.0, math.sqrt(a3 * trans**2 + a4 * rot**2))
        r_hat = rot + rng.normal(0.0, math.sqrt(a1 * rot**2 + a2 * trans**2))
        s_hat = rng.normal(0.0, math.sqrt(a4 * rot**2 + a5 * trans**2))
        q[0] += t_hat * math.cos(bearing) + s_hat * math.sin(bearing)
        q[1] += t_hat * math.sin(bearing) - s_hat * math.cos(bearing)
        q[2] += r_hat
        poses.append(q)
    return np.array(poses)


def diff_odometry(rng, n):
    """Odometry poses at AMCL updates: forward and backward moves, arcs both ways, spins."""
    pose, out = np.zeros(3), [np.zeros(3)]
    for _ in range(n):
        kind = rng.choice(4, p=[0.4, 0.1, 0.3, 0.2])
        if kind == 3:  # spin in place (nav2 takes no bearing below 1 cm)
            turn, d = rng.choice([-1, 1]) * rng.uniform(0.21, 0.5), rng.uniform(0.0, 0.008)
        elif kind == 2:  # arc
            turn, d = rng.choice([-1, 1]) * rng.uniform(0.05, 0.3), rng.uniform(0.1, 0.35)
        else:  # straight forward or backward
            turn, d = rng.normal(0.0, 0.03), rng.uniform(0.26, 0.4) * (1 if kind == 0 else -1)
        h = pose[2] + turn / 2
        pose = pose + np.array([d * math.cos(h), d * math.sin(h), turn])
        out.append(pose.copy())
    return np.array(out)


def omni_odometry(rng, n):
    pose, out = np.zeros(3), [np.zeros(3)]
    for _ in range(n):
        direction = rng.uniform(-math.pi, math.pi)
        d = rng.uniform(0.26, 0.4) if rng.random() < 0.5 else rng.uniform(0.0, 0.05)
        turn = rng.normal(0.0, 0.05) if rng.random() < 0.5 else rng.choice([-1, 1]) * rng.uniform(0.21, 0.5)
        pose = pose + np.array([d * math.cos(pose[2] + direction), d * math.sin(pose[2] + direction), turn])
        out.append(pose.copy())
    return np.array(out)


def _coverage(model, alpha, seeds, updates=300, truth_sigma=0.0):
    hits = np.zeros(len(alpha))
    fits = []
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        if model == "diff":
            odom = diff_odometry(rng, updates)
            truth = sample_diff(rng, odom, alpha, [1.0, -2.0, 0.7])
        else:
            odom = omni_odometry(rng, updates)
            truth = sample_omni(rng, odom, alpha, [1.0, -2.0, 0.7])
        if truth_sigma:
            truth[:, :2] += rng.normal(0.0, truth_sigma, (truth.shape[0], 2))
        fit = fit_amcl(amcl_data(odom[:-1], odom[1:], truth[:-1], truth[1:], model, truth_sigma))
        hits += (fit.interval[:, 0] <= alpha) & (alpha <= fit.interval[:, 1])
        fits.append(fit)
    return hits / seeds, fits


@pytest.mark.parametrize(("model", "alpha"), [
    ("diff", np.array([0.05, 0.1, 0.04, 0.2])),
    ("omni", np.array([0.05, 0.1, 0.04, 0.2, 0.03])),
])
def test_alphas_of_amcls_own_sampler_are_fitted_back_inside_the_intervals(model, alpha):
    coverage, fits = _coverage(model, alpha, seeds=12)
    # 95 % intervals over 12 seeds: a true coverage of 0.95 gives 10+ hits with 98 % probability.
    assert np.all(coverage >= 10 / 12), coverage
    # and the estimates are near: the mean over seeds within 15 % of the truth
    mean = np.mean([f.alpha for f in fits], axis=0)
    assert np.allclose(mean, alpha, rtol=0.15), mean
    assert fits[0].names == ALPHA_NAMES[model] and fits[0].updates == 300


def test_truth_noise_is_accounted_for():
    """4 mm truth noise: ignored, it is read as rotation noise (the bearing of a short move
    is noisy) and the α1, α2 intervals miss; with ``truth_sigma`` they cover again."""
    alpha = np.array([0.05, 0.1, 0.04, 0.2])
    with_sigma, naive = np.zeros(4), np.zeros(4)
    seeds = 6
    for seed in range(seeds):
        rng = np.random.default_rng(2000 + seed)
        odom = diff_odometry(rng, 300)
        truth = sample_diff(rng, odom, alpha, [0.0, 0.0, 0.0])
        truth[:, :2] += rng.normal(0.0, 0.004, (truth.shape[0], 2))
        for sigma, hits in ((0.004, with_sigma), (0.0, naive)):
            fit = fit_amcl(amcl_data(odom[:-1], odom[1:], truth[:-1], truth[1:], "diff", sigma))
            hits += (fit.interval[:, 0] <= alpha) & (alpha <= fit.interval[:, 1])
    assert with_sigma.sum() >= 4 * seeds - 3, with_sigma
    assert naive[:2].sum() <= 2 * seeds - 4, naive


def test_nav2_decomposition_by_hand():
    # forward 0.3 m at heading 0 after a 90° bearing: rot1 = π/2, trans 0.3, rot2 = −π/2 + Δθ
    r1, t, r2 = diff_motion([[0.0, 0.0, 0.0]], [[0.0, 0.3, 0.1]])
    assert (r1[0], t[0], r2[0]) == pytest.approx((math.pi / 2, 0.3, 0.1 - math.pi / 2))
    # below 1 cm nav2 takes no bearing: rot1 = 0 and the whole turn is rot2
    r1, t, r2 = diff_motion([[0.0, 0.0, 0.0]], [[0.0, 0.005, 0.3]])
    assert (r1[0], r2[0]) == (0.0, pytest.approx(0.3))
    # wrapped differences across ±π
    r1, t, r2 = diff_motion([[0.0, 0.0, 3.1]], [[-0.3, 0.0, -3.1]])
    turn = 2 * math.pi - 6.2  # from 3.1 to −3.1 the short way
    assert r1[0] == pytest.approx(math.pi - 3.1) and r2[0] == pytest.approx(turn - (math.pi - 3.1))


def test_reverse_motion_has_the_noise_of_forward_motion():
    """nav2 folds rot ≈ π onto 0 for the noise: a straight move backwards has only the
    translation-driven variances, exactly like the same move forwards."""
    zero = np.zeros((1, 3))
    fwd = amcl_data(zero, [[0.3, 0.0, 0.0]], zero, [[0.3, 0.0, 0.0]])
    back = amcl_data(zero, [[-0.3, 0.0, 0.0]], zero, [[-0.3, 0.0, 0.0]])
    assert np.allclose(fwd.design, back.design)
    assert np.allclose(back.residual, 0.0, atol=1e-12)  # the truth on the odometry's branch


def test_update_rows_follow_nav2s_rule():
    # x and y each tested against update_min_d (not the distance), and the wrapped turn
    poses = np.array([[0, 0, 0], [0.2, 0.2, 0], [0.26, 0.0, 0], [0.3, 0.1, 0], [0.3, 0.1, 0.15],
                      [0.3, 0.1, 0.36], [0.3, 0.1, 0.36 + 2 * math.pi]], dtype=float)
    # row 1: |dx| = 0.2, |dy| = 0.2, distance 0.28 > 0.25 but no axis passes: no update
    assert amcl_update_rows(poses, 0.25, 0.2).tolist() == [0, 2, 5]
    with pytest.raises(InputError, match="update_min_d"):
        amcl_update_rows(poses, 0.0, 0.2)


def test_unidentified_alpha_gets_an_open_interval_and_a_warning():
    """Straight moves only: nothing turns, so α1 (rotation noise from rotation) is free."""
    rng = np.random.default_rng(3)
    n = 200
    o0 = np.zeros((n, 3))
    o1 = np.column_stack((rng.uniform(0.26, 0.4, n), np.zeros(n), np.zeros(n)))
    truth = np.array([sample_diff(rng, np.array([a, b]), [0.05, 0.1, 0.04, 0.2], a)[1]
                      for a, b in zip(o0, o1, strict=True)])
    fit = fit_amcl(amcl_data(o0, o1, o0, truth))
    assert math.isinf(fit.interval[0, 1]) and math.isinf(fit.interval[3, 1])
    assert any("alpha1" in w for w in fit.warnings)
    assert fit.to_dict()["interval95"]["alpha1"][1] is None


def test_bad_input():
    with pytest.raises(InputError, match="model"):
        amcl_data(np.zeros((3, 3)), np.ones((3, 3)), np.zeros((3, 3)), np.ones((3, 3)), "ackermann")
    with pytest.raises(InputError, match="too few"):
        fit_amcl(amcl_data(np.zeros((3, 3)), np.ones((3, 3)), np.zeros((3, 3)), np.ones((3, 3))))
    with pytest.raises(InputError, match="one row per update"):
        amcl_data(np.zeros((3, 3)), np.ones((2, 3)), np.zeros((3, 3)), np.ones((3, 3)))


@pytest.mark.parametrize("known", ["zero", "bearing", "full"])
def test_likelihood_equals_a_sum_of_gaussian_log_densities(known):
    """The three code paths of the likelihood (diagonal, 2x2 block, general 3x3) against
    scipy's multivariate normal, and their gradients against central differences."""
    from scipy.stats import multivariate_normal

    from odomkit.calibrate.amcl import AmclData, log_likelihood

    rng = np.random.default_rng(7)
    n = 30
    residual, design = rng.normal(size=(n, 3)) * 0.1, rng.uniform(0.0, 1.0, (n, 3, 4))
    extra = np.zeros((n, 3, 3))
    if known != "zero":
        extra[:, 0, 0] = extra[:, 2, 2] = 0.01
        extra[:, 0, 2] = extra[:, 2, 0] = -0.01
        extra[:, 1, 1] = 0.02
    if known == "full":
        extra[:, 0, 1] = extra[:, 1, 0] = 0.003
    data = AmclData("diff", residual, design, extra)
    alpha = np.array([0.03, 0.05, 0.02, 0.04])
    expected = sum(multivariate_normal(np.zeros(3), np.diag(design[i] @ alpha) + extra[i]).logpdf(residual[i])
                   for i in range(n))
    value, grad = log_likelihood(alpha, data)
    assert value == pytest.approx(expected, rel=1e-9)
    h = 1e-7
    numeric = [(log_likelihood(alpha + h * e, data)[0] - log_likelihood(alpha - h * e, data)[0]) / (2 * h)
               for e in np.eye(4)]
    assert np.allclose(grad, numeric, rtol=1e-5, atol=1e-6)
