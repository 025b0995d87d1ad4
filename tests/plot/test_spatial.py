"""Figures in the plane (odomkit.plot.spatial), checked on the drawn artists against
independent truth: the closed-form eigen-decomposition of a 2×2 covariance, Monte Carlo
samples counted inside the drawn polygon, and UMBmark's centres of gravity by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.plot import draw_monte_carlo, draw_track, draw_umbmark, new_figure

CHI2_2_95 = 5.991464547107979  # χ²₂(0.95) = −2 ln 0.05, to 16 digits


def _axes():
    fig, axes = new_figure()
    return axes[0]


def _closed_form_axes(P):
    """Semi-axis variances and major-axis angle of a 2×2 covariance, in closed form."""
    a, b, c = P[0, 0], P[0, 1], P[1, 1]
    mid, rad = (a + c) / 2, math.hypot((a - c) / 2, b)
    return mid + rad, mid - rad, 0.5 * math.atan2(2 * b, a - c)


@pytest.mark.parametrize("P", [np.array([[4e-4, 1.5e-4], [1.5e-4, 1e-4]]),
                               np.array([[1e-4, -0.9e-4], [-0.9e-4, 2e-4]]),
                               np.array([[3e-4, 0.0], [0.0, 3e-4]])])
def test_ellipse_semi_axes_and_orientation_match_the_eigen_decomposition(P):
    ax = _axes()
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 0.3]])
    cov = np.zeros((2, 3, 3))
    cov[1, :2, :2] = P
    artists = draw_track(ax, poses, cov, n_ellipses=1)
    ring = artists[-1].get_xydata()[:-1] - poses[1, :2]
    # Every vertex lies on the χ²₂(0.95) contour of P.
    d2 = np.einsum("ni,ij,nj->n", ring, np.linalg.inv(P), ring)
    assert np.allclose(d2, CHI2_2_95, rtol=1e-9)
    big, small, angle = _closed_form_axes(P)
    r = np.hypot(ring[:, 0], ring[:, 1])
    assert r.max() == pytest.approx(math.sqrt(CHI2_2_95 * big), rel=1e-9)
    assert r.min() == pytest.approx(math.sqrt(CHI2_2_95 * small), rel=1e-9)
    if big > small * (1 + 1e-9):
        far = ring[np.argmax(r)]
        direction = math.atan2(far[1], far[0])
        assert math.sin(direction - angle) == pytest.approx(0.0, abs=1e-9)  # along ±major axis


def test_the_legend_prints_the_probability_and_its_quantile():
    ax = _axes()
    poses = np.column_stack([np.linspace(0, 1, 20), np.zeros(20), np.zeros(20)])
    cov = np.linspace(0, 1e-4, 20)[:, None, None] * np.eye(3)
    draw_track(ax, poses, cov, probability=0.99, n_ellipses=3)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "99 % confidence ellipses (χ²₂ = 9.21)" in texts  # −2 ln 0.01 = 9.2103
    assert ax.get_aspect() == 1.0 and ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "y [m]"


def test_ellipses_are_spaced_along_the_path_not_the_rows():
    """A robot that stands still for most rows: the ellipses still spread along its travel."""
    ax = _axes()
    x = np.concatenate([np.zeros(900), np.linspace(0, 4, 101)])
    poses = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    cov = np.broadcast_to(1e-4 * np.eye(3), (x.size, 3, 3)).copy()
    artists = draw_track(ax, poses, cov, n_ellipses=4)
    centres = sorted(round(float(np.mean(a.get_xydata()[:-1, 0])), 6) for a in artists[1:])
    assert centres == [1.0, 2.0, 3.0, 4.0]


def test_monte_carlo_samples_fill_the_drawn_95_percent_ellipse_95_percent():
    from matplotlib.path import Path

    rng = np.random.default_rng(20240613)
    P = np.array([[4e-4, 1e-4, 2e-4], [1e-4, 1e-4, 0.0], [2e-4, 0.0, 3e-4]])
    mean = np.array([1.0, 0.5, 3.1])
    n = 4000
    ends = rng.multivariate_normal(mean, P, n)
    ends[:, 2] += 2 * np.pi  # a whole turn more: the heading difference is wrapped
    for comps in ((0, 1), (0, 2)):
        ax = _axes()
        _, _, ring = draw_monte_carlo(ax, ends, mean, P, components=comps)
        polygon = Path(ring.get_xydata())
        pts = ends[:, comps].copy()
        if 2 in comps:
            pts[:, 1] -= 2 * np.pi
        inside = polygon.contains_points(pts).mean()
        se = math.sqrt(0.95 * 0.05 / n)
        assert abs(inside - 0.95) < 3 * se
        printed = float(ring.get_label().split(": ")[1].split(" of")[0])
        assert printed == pytest.approx(inside, abs=2.0 / n + 5e-4)  # polygon vs exact ellipse
    assert ax.get_ylabel() == "θ [rad]"


def test_umbmark_centres_of_gravity_and_e_max_syst():
    rng = np.random.default_rng(3)
    cw = rng.normal([0.02, -0.01], 0.004, (5, 2))
    ccw = rng.normal([-0.015, 0.03], 0.004, (4, 2))
    after = (0.1 * cw, 0.2 * ccw)
    ax = _axes()
    artists = draw_umbmark(ax, cw, ccw, cw_after=after[0], ccw_after=after[1])
    for k, (a, b) in enumerate(((cw, ccw), after)):
        runs_cw, cg_cw, runs_ccw, cg_ccw, circle = artists[5 * k: 5 * k + 5]
        assert np.allclose(runs_cw.get_xydata(), 1000 * a)
        assert np.allclose(cg_cw.get_xydata()[0], 1000 * a.sum(axis=0) / len(a))
        assert np.allclose(cg_ccw.get_xydata()[0], 1000 * b.sum(axis=0) / len(b))
        e_max = 1000 * max(math.dist((0, 0), a.sum(axis=0) / len(a)),
                           math.dist((0, 0), b.sum(axis=0) / len(b)))
        radius = np.hypot(*circle.get_xydata().T)
        assert np.allclose(radius, e_max)
        assert f"E_max,syst = {e_max:.2f} mm" in circle.get_label()
    assert ax.get_xlabel() == "return error ε_x [mm]"


def test_umbmark_needs_both_after_sets():
    from odomkit.errors import InputError

    with pytest.raises(InputError, match="both"):
        draw_umbmark(_axes(), [[0.0, 0.0]], [[0.0, 0.0]], cw_after=[[0.0, 0.0]])
