"""UMBmark formulas (Borenstein–Feng 1996) checked against hand computation.

Every expected value below is computed in the test from the paper's equations (re-derived,
see docs/reference/commands/umbmark.md), not taken from the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.calibrate.umbmark import (
    apply_corrections,
    e_max_syst,
    umbmark,
    umbmark_chong_kleeman,
    umbmark_summary,
)
from odomkit.errors import InputError, ModelError
from odomkit.robot import DiffDrive


def first_order_cg(alpha: float, beta: float, L: float) -> tuple[list[float], list[float]]:
    """Centres of gravity predicted by Borenstein–Feng eq. (4.4), (4.8), (4.12), (4.16):
    CW (−2L(α+β), −2L(α+β)), CCW (−2L(α−β), +2L(α−β))."""
    return ([-2 * L * (alpha + beta), -2 * L * (alpha + beta)],
            [-2 * L * (alpha - beta), 2 * L * (alpha - beta)])


@pytest.mark.parametrize("alpha, beta", [(0.01, 0.02), (-0.015, 0.005), (0.003, -0.03)])
def test_first_order_model_is_inverted_exactly(alpha: float, beta: float) -> None:
    L, b = 4.0, 0.34
    cw, ccw = first_order_cg(alpha, beta, L)
    r = umbmark([cw], [ccw], L, b)
    assert r.alpha_x == pytest.approx(alpha, abs=1e-15)
    assert r.alpha_y == pytest.approx(alpha, abs=1e-15)
    assert r.beta_x == pytest.approx(beta, abs=1e-15)
    assert r.beta_y == pytest.approx(beta, abs=1e-15)
    assert r.alpha_disagreement == pytest.approx(0.0, abs=1e-15)
    # Eq. (4.21) and (4.22) with R written out (the code uses the multiplied-through form).
    R = (L / 2) / math.sin(beta / 2)
    assert r.radius == pytest.approx(R, rel=1e-12)
    E_d = (R + b / 2) / (R - b / 2)
    assert r.E_d == pytest.approx(E_d, rel=1e-12)
    # Eq. (4.27) in degrees, exactly as printed.
    alpha_deg = math.degrees(alpha)
    assert r.E_b == pytest.approx(90.0 / (90.0 - alpha_deg), rel=1e-12)
    assert r.wheel_base == pytest.approx(b * 90.0 / (90.0 - alpha_deg), rel=1e-12)
    # Eq. (4.31)-(4.32); they keep the mean diameter (4.28) and give the ratio E_d (4.22).
    assert r.c_left == pytest.approx(2 / (E_d + 1), rel=1e-12)
    assert r.c_right == pytest.approx(2 / (1 / E_d + 1), rel=1e-12)
    assert (r.c_left + r.c_right) / 2 == pytest.approx(1.0, abs=1e-14)
    assert r.c_right / r.c_left == pytest.approx(E_d, rel=1e-12)


def test_hand_computed_small_case() -> None:
    cw = [[-0.30, -0.32], [-0.34, -0.28]]
    ccw = [[0.05, 0.21], [0.07, 0.19]]
    r = umbmark(cw, ccw, side=4.0, wheel_base=0.34)
    # (3.2): means by hand.
    assert r.cg_cw == pytest.approx((-0.32, -0.30), abs=1e-15)
    assert r.cg_ccw == pytest.approx((0.06, 0.20), abs=1e-15)
    # (3.3)-(3.4): sqrt(0.1024 + 0.09) and sqrt(0.0036 + 0.04).
    assert r.r_cg_cw == pytest.approx(math.sqrt(0.1924), rel=1e-14)
    assert r.r_cg_ccw == pytest.approx(math.sqrt(0.0436), rel=1e-14)
    assert r.e_max_syst == pytest.approx(math.sqrt(0.1924), rel=1e-14)
    # (4.20a) (−0.32 − 0.06)/−16, (4.20b) (−0.30 + 0.20)/−16,
    # (4.24a) (−0.32 + 0.06)/−16, (4.24b) (−0.30 − 0.20)/−16.
    assert r.beta_x == pytest.approx(0.02375, abs=1e-15)
    assert r.beta_y == pytest.approx(0.00625, abs=1e-15)
    assert r.alpha_x == pytest.approx(0.01625, abs=1e-15)
    assert r.alpha_y == pytest.approx(0.03125, abs=1e-15)
    assert r.alpha == pytest.approx(0.02375, abs=1e-15)
    assert r.beta == pytest.approx(0.015, abs=1e-15)
    assert r.alpha_disagreement == pytest.approx(-0.015, abs=1e-15)
    # Two runs per cluster: std (ddof 1) of two numbers is |difference|/√2 = 0.04/√2.
    s = 0.04 / math.sqrt(2)
    assert r.sigma_cw == pytest.approx((s, s), rel=1e-12)
    assert r.sem_cw == pytest.approx(math.sqrt((s**2 + s**2) / 2), rel=1e-12)
    assert r.sem_ccw == pytest.approx(math.sqrt((0.02**2 / 2 * 2) / 2), rel=1e-12)
    assert r.second_compensation_advised is True  # 0.439 m >> 3·0.028 m


def test_three_sem_rule_says_no_when_clusters_straddle_the_origin() -> None:
    # c.g.s of 1 mm with a spread of ~50 mm: E_max,syst << 3·SEM.
    cw = [[0.05, 0.0], [-0.05, 0.002], [0.003, 0.05], [0.0, -0.05]]
    ccw = [[0.05, 0.001], [-0.05, 0.0], [0.001, 0.05], [0.002, -0.05]]
    r = umbmark(cw, ccw, 4.0, 0.34)
    assert r.e_max_syst < 0.002
    assert r.sem_cw > 0.02
    assert r.second_compensation_advised is False


def test_three_sem_rule_borderline_uses_three() -> None:
    # Two runs at (d ± s, 0): c.g. at d, SEM = s (σ_x = s√2, σ_y = 0, n = 2).
    s = 0.01
    for d, expected in [(2.9 * s, False), (3.1 * s, True)]:
        cw = [[d + s, 0.0], [d - s, 0.0]]
        ccw = [[s, 0.0], [-s, 0.0]]
        r = umbmark(cw, ccw, 4.0, 0.34)
        assert r.sem_cw == pytest.approx(s, rel=1e-12)
        assert r.second_compensation_advised is expected


def test_beta_zero_is_exact() -> None:
    # Pure Type A (first-order model with β = 0): straight legs, R infinite, E_d = 1.
    cw, ccw = first_order_cg(0.01, 0.0, 4.0)
    r = umbmark([cw], [ccw], 4.0, 0.34)
    assert r.beta == 0.0
    assert math.isinf(r.radius)
    assert r.E_d == 1.0 and r.c_left == 1.0 and r.c_right == 1.0
    assert r.to_dict()["radius"] is None
    # β_x = −β_y ≠ 0 averages to exactly 0 as well.
    r2 = umbmark([[0.1, -0.1]], [[0.0, 0.0]], 4.0, 0.34)
    assert r2.beta_x == -r2.beta_y != 0.0 and r2.beta == 0.0
    assert r2.E_d == 1.0 and math.isinf(r2.radius)
    # And the all-zero case: nothing to correct.
    r3 = umbmark([[0.0, 0.0]], [[0.0, 0.0]], 4.0, 0.34)
    assert (r3.E_d, r3.E_b, r3.c_left, r3.c_right, r3.wheel_base) == (1.0, 1.0, 1.0, 1.0, 0.34)


def test_chong_kleeman_variant_differs_only_in_c_b() -> None:
    L, b, alpha, beta = 4.0, 0.34, 0.02, 0.01
    cw, ccw = first_order_cg(alpha, beta, L)
    bf = umbmark([cw], [ccw], L, b)
    ck = umbmark_chong_kleeman([cw], [ccw], L, b)
    # Chong–Kleeman eq. (9) E_d = (D + B sin(β/2))/(D − B sin(β/2)), (11)-(12).
    e_d = (L + b * math.sin(beta / 2)) / (L - b * math.sin(beta / 2))
    assert ck.E_d == pytest.approx(e_d, rel=1e-12) and bf.E_d == pytest.approx(e_d, rel=1e-12)
    assert ck.c_left == pytest.approx(2 / (e_d + 1), rel=1e-12)
    assert ck.c_right == pytest.approx(e_d * 2 / (e_d + 1), rel=1e-12)
    # Eq. (10) as printed vs Borenstein–Feng (4.27): (c_b − 1) is about half of (E_b − 1).
    assert ck.E_b == pytest.approx(math.pi / (math.pi - alpha), rel=1e-12)
    assert (ck.E_b - 1) / (bf.E_b - 1) == pytest.approx(0.5, abs=alpha)
    s = umbmark_summary([cw], [ccw], L, b)
    assert s["chong_kleeman"]["c_b"] == ck.E_b and s["E_b"] == bf.E_b


def test_single_run_has_no_sem() -> None:
    r = umbmark([[0.1, 0.1]], [[0.1, -0.1], [0.12, -0.1]], 4.0, 0.34)
    assert math.isnan(r.sem_cw) and not math.isnan(r.sem_ccw)
    assert r.second_compensation_advised is None


def test_e_max_syst_function() -> None:
    assert e_max_syst([[0.3, 0.4], [0.3, 0.4]], [[0.0, 0.1]]) == pytest.approx(0.5)


def test_apply_corrections_composes() -> None:
    robot = DiffDrive(0.34, c_left=0.99, c_right=1.01, c_wheel_base=1.02)
    cw, ccw = first_order_cg(0.01, 0.02, 4.0)
    r = umbmark([cw], [ccw], 4.0, 0.34 * 1.02)
    new = apply_corrections(robot, r)
    # The ratio c_R/c_L is multiplied by the measured E_d, the mean stays 1.0, b by E_b.
    assert new.c_right / new.c_left == pytest.approx(r.E_d * 1.01 / 0.99, rel=1e-12)
    assert (new.c_left + new.c_right) / 2 == pytest.approx(1.0, rel=1e-14)
    assert new.c_wheel_base == pytest.approx(1.02 * r.E_b, rel=1e-14)
    assert new.effective_wheel_base == pytest.approx(r.wheel_base, rel=1e-14)


@pytest.mark.parametrize("cw, ccw, exc", [
    ([[0.1, 0.1, 0.1]], [[0.0, 0.0]], InputError),
    (np.zeros((0, 2)), [[0.0, 0.0]], InputError),
    ([[0.1, math.nan]], [[0.0, 0.0]], InputError),
    ([[0.1, 0.1]], [[math.inf, 0.0]], InputError),
    ([["a", 0.1]], [[0.0, 0.0]], InputError),
])
def test_bad_errors_are_rejected(cw, ccw, exc) -> None:
    with pytest.raises(exc):
        umbmark(cw, ccw, 4.0, 0.34)


@pytest.mark.parametrize("side, b", [(0.0, 0.34), (-4.0, 0.34), (4.0, 0.0), (math.nan, 0.34),
                                     (4.0, math.inf)])
def test_bad_geometry_is_rejected(side, b) -> None:
    with pytest.raises(ModelError, match="side|wheel_base"):
        umbmark([[0.0, 0.0]], [[0.0, 0.0]], side, b)


def test_impossible_errors_are_rejected() -> None:
    # β so large that the curve radius is below b/2 (errors given in mm by mistake).
    with pytest.raises(ModelError, match="radius below b/2"):
        umbmark([[-300.0, -300.0]], [[300.0, -300.0]], 4.0, 0.34)
